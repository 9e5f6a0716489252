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
    "tip_temperature": ("tip temp. rise (K)", 1.0),
    "contact_force": ("force = impulse/h (N)", 1.0),
    "phase_impulse": ("impulse/phase (mN s)", 1e3),
}
#: axis label unit and scale of a probe's SI unit (``outputs.probes``)
_PROBE_AXES = {"m": ("µm", 1e6), "m/s": ("m/s", 1.0), "K": ("K", 1.0)}
#: thin lines for per-step force traces (impulse / h flips between steps while closed)
_THIN = {"lw": 0.5, "alpha": 0.75}


def _series(res, key):
    if key == "contact_force":
        return res.force.sum(axis=1) if res.force.size else np.zeros_like(res.t)
    if key in res.signals:
        return res.signal(key)
    return None


def phase_impulses(res, merge: float) -> tuple[np.ndarray, np.ndarray]:
    """Mid-times and total impulse (N s, all contacts) of the contact phases of ``res``.

    Impacts closer than ``merge`` seconds belong to one phase.
    """
    mids, total = [], []
    on = np.any(res.impulse > 0.0, axis=1) if res.impulse.size else np.zeros(0, bool)
    idx = np.flatnonzero(on)
    if idx.size == 0:
        return np.zeros(0), np.zeros(0)
    t = res.t
    cut = np.flatnonzero(np.diff(t[idx]) > merge) + 1
    for grp in np.split(idx, cut):
        mids.append(0.5 * (t[grp[0]] + t[grp[-1]]))
        total.append(res.impulse[grp].sum())
    return np.array(mids), np.array(total)


def _axis(key: str, runs) -> tuple[str, float]:
    """Label and scale of a panel: a known signal, or a probe ``probe_<name>`` in its unit."""
    if key in _PANELS:
        return _PANELS[key]
    unit = next((r.info.get("signal_units", {}).get(key) for _, r, _ in runs), None) or "-"
    label, scale = _PROBE_AXES.get(unit, (unit, 1.0))
    return f"probe {key.removeprefix('probe_')} ({label})", scale


def _draw(ax, key, runs, *, tlim, scale_t, gap, merge, log, titles):
    ylabel, scale = _axis(key, runs)
    if titles and key in titles:
        ax.set_title(titles[key], fontsize=8.5, loc="left")
    for label, res, style in runs:
        style = dict(style or {})
        if key == "phase_impulse":
            tm, imp = phase_impulses(res, merge)
            if tlim is not None:
                sel = (tm >= tlim[0]) & (tm <= tlim[1])
                tm, imp = tm[sel], imp[sel]
            style.pop("lw", None)
            ax.plot(tm * scale_t, imp * scale, marker="o", ms=3.5, label=label, **style)
            ax.set_yscale("log")
            continue
        y = _series(res, key)
        if y is None:
            continue
        t = res.t
        if tlim is not None:
            sel = (t >= tlim[0]) & (t <= tlim[1])
            t, y = t[sel], y[sel]
        if key == "contact_force":
            style.update(_THIN)
        ax.plot(t * scale_t, y * scale, label=label, **style)
    if key == "tip_displacement" and gap is not None:
        ax.axhline(gap * 1e6, color="0.4", lw=0.8, ls=":", label="casing (gap)")
    if log:
        ax.set_yscale("symlog", linthresh=1.0)
        ylabel = ylabel.replace(")", "; log > 1)")
    ax.set_ylabel(ylabel, fontsize=9)
    ax.grid(True, lw=0.3, alpha=0.6)


def tip_panels(
    runs,
    *,
    title: str = "",
    panels=("tip_displacement", "tip_temperature", "contact_force"),
    tlim=None,
    time_unit: str = "s",
    gap: float | None = None,
    merge: float = 0.0,
    log_panels=(),
    columns=None,
    titles=None,
):
    """Stacked panels (paper Figs. 2–7) for ``runs = [(label, results, style_dict), ...]``.

    ``columns = [(column_title, runs), ...]`` draws one column per group with shared y axes
    (``runs`` is then ignored). The legend sits above the panels, off the data.
    ``"phase_impulse"`` draws the impulse of each contact phase (impacts closer than
    ``merge`` seconds merged) at the phase's mid-time; ``log_panels`` get a symlog y axis;
    ``titles`` (by panel key) says above a panel what its curve is.
    """
    scale_t = 1e3 if time_unit == "ms" else 1.0
    cols = columns or [("", runs)]
    fig, axes = plt.subplots(
        len(panels),
        len(cols),
        sharex=True,
        sharey="row",
        figsize=(4.6 * len(cols) + 2.9 * (len(cols) == 1), 2.2 * len(panels) + 0.9),
        squeeze=False,
    )
    for j, (ctitle, cruns) in enumerate(cols):
        for i, key in enumerate(panels):
            _draw(
                axes[i, j],
                key,
                cruns,
                tlim=tlim,
                scale_t=scale_t,
                gap=gap,
                merge=merge,
                log=key in log_panels,
                titles=titles,
            )
            if j:
                axes[i, j].set_ylabel("")
        if ctitle:
            axes[0, j].set_title(ctitle, fontsize=9)  # (panel titles apply to single columns)
        axes[-1, j].set_xlabel(f"time ({time_unit})")
        if tlim is not None:
            axes[-1, j].set_xlim(tlim[0] * scale_t, tlim[1] * scale_t)
    handles, labels = {}, []
    for ax in axes.flat:
        for h_, l_ in zip(*ax.get_legend_handles_labels()):
            if l_ not in handles:
                handles[l_] = h_
                labels.append(l_)
    ncol = min(len(labels), 3 if len(cols) == 1 else 4)
    nrows = -(-len(labels) // max(ncol, 1))
    top = 1.0 - (0.1 + 0.2 * nrows + 0.3 * bool(title)) / fig.get_figheight()
    fig.tight_layout(rect=(0, 0, 1, top))
    fig.legend(
        [handles[l_] for l_ in labels],
        labels,
        loc="lower center",
        ncol=ncol,
        fontsize=8,
        bbox_to_anchor=(0.5, top),
        frameon=False,
    )
    if title:
        fig.suptitle(title, fontsize=10, y=0.995)
    return fig


def energy_panel(res, *, title: str = ""):
    """Energy balance of one run (J) and its residual.

    Top: mechanical energy, external work, work of the thermal stresses, impact
    dissipation. Bottom: the balance residual ``r_k`` in J; the title states the relative
    residual ``max |r| / scale`` (scale: largest energy or work of the run,
    :meth:`Results.energy_error`).
    """
    e = res.energy
    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7.5, 5.2))
    ax[0].plot(res.t, e["kinetic"] + e["elastic"], label="mechanical energy")
    ax[0].plot(res.t, e["external_work"], label="external work")
    ax[0].plot(res.t, e["thermal_work"], label="work of thermal stresses")
    ax[0].plot(res.t, e["impact_dissipation"], label="impact dissipation")
    ax[0].set_ylabel("energy, work (J)")
    ax[0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax[1].plot(res.t, e["energy_error"], lw=0.8, color="C3")
    ax[1].set_ylabel("balance residual r (J)")
    ax[1].set_xlabel("time (s)")
    ax[1].set_title(
        f"relative residual max|r| / scale = {res.energy_error():.1e} (dimensionless)",
        fontsize=9,
    )
    for a in ax:
        a.grid(True, lw=0.3, alpha=0.6)
    if title:
        ax[0].set_title(title, fontsize=10)
    fig.tight_layout()
    return fig


def savefig(fig, path) -> Path:
    """Save ``fig`` to ``path`` (format from the suffix) through a temporary file beside it
    (:func:`~femrub.output.safe_write.atomic_file`: never through a symbolic link)."""
    from .safe_write import atomic_file, naming

    path = Path(path)
    try:
        with naming(path), atomic_file(path) as fh:
            fig.savefig(fh, dpi=130, format=path.suffix.lstrip(".") or "png")
    finally:
        plt.close(fig)
    return path
