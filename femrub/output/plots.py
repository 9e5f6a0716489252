"""Figures in the style of the paper's panels: tip position, tip temperature, contact force.

Functions take a list of ``(label, Results, style)`` and draw with matplotlib (Agg backend,
no screen needed). Units on the axes: µm, K (rise above ambient), N, s or ms.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ["tip_panels", "energy_panel", "savefig"]

_PANELS = {
    "tip_displacement": ("tip position (µm)", 1e6),
    "tip_temperature": ("tip temperature rise (K)", 1.0),
    "contact_force": ("contact force (N)", 1.0),
}


def _series(res, key):
    if key == "contact_force":
        return res.force.sum(axis=1) if res.force.size else np.zeros_like(res.t)
    if key in res.signals:
        return res.signal(key)
    return None


def tip_panels(
    runs,
    *,
    title: str = "",
    panels=("tip_displacement", "tip_temperature", "contact_force"),
    tlim=None,
    time_unit: str = "s",
    gap: float | None = None,
):
    """Stacked panels (paper Figs. 2–7) for ``runs = [(label, results, style_dict), ...]``."""
    scale_t = 1e3 if time_unit == "ms" else 1.0
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(7.5, 2.3 * len(panels)))
    axes = np.atleast_1d(axes)
    for ax, key in zip(axes, panels):
        ylabel, scale = _PANELS[key]
        for label, res, style in runs:
            y = _series(res, key)
            if y is None:
                continue
            t = res.t
            if tlim is not None:
                sel = (t >= tlim[0]) & (t <= tlim[1])
                t, y = t[sel], y[sel]
            ax.plot(t * scale_t, y * scale, label=label, **(style or {}))
        if key == "tip_displacement" and gap is not None:
            ax.axhline(gap * 1e6, color="0.4", lw=0.8, ls=":", label="casing (gap)")
        ax.set_ylabel(ylabel)
        ax.grid(True, lw=0.3, alpha=0.6)
    axes[0].legend(fontsize=8, loc="best", ncol=2)
    axes[-1].set_xlabel(f"time ({time_unit})")
    if tlim is not None:
        axes[-1].set_xlim(tlim[0] * scale_t, tlim[1] * scale_t)
    if title:
        axes[0].set_title(title, fontsize=10)
    fig.tight_layout()
    return fig


def energy_panel(res, *, title: str = ""):
    """Energy balance of one run: mechanical energy, works, dissipation and residual (J)."""
    e = res.energy
    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7.5, 5))
    ax[0].plot(res.t, e["kinetic"] + e["elastic"], label="mechanical energy")
    ax[0].plot(res.t, e["external_work"], label="external work")
    ax[0].plot(res.t, e["thermal_work"], label="work of thermal stresses")
    ax[0].plot(res.t, e["impact_dissipation"], label="impact dissipation")
    ax[0].set_ylabel("energy (J)")
    ax[0].legend(fontsize=8)
    ax[1].plot(res.t, e["energy_error"], label="balance residual")
    ax[1].set_ylabel("residual (J)")
    ax[1].set_xlabel("time (s)")
    for a in ax:
        a.grid(True, lw=0.3, alpha=0.6)
    if title:
        ax[0].set_title(title, fontsize=10)
    fig.tight_layout()
    return fig


def savefig(fig, path) -> Path:
    path = Path(path)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path
