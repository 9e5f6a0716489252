"""Figures of a rub run on a rotating blade, against revolutions of the rotor.

* :func:`response_panels`: the response of one contact node over the whole run and over its
  first and last ``window`` revolutions;
* :func:`spectrum_panel`: the amplitude spectrum of that response with the engine-order
  lines ``k Ω / 2π``;
* :func:`contact_force_panel`: the normal (and friction) force of each contact against the
  angular position of the rotor ``mod(Ω t, 360°)``.

Inputs are :class:`~femrub.output.results.Results` and the rotation speed Ω (rad/s).
"""

from __future__ import annotations

import numpy as np

from .plots import plt

__all__ = ["contact_force_panel", "response_of", "response_panels", "spectrum_panel"]


def response_of(res, node: int = 0) -> tuple[np.ndarray, str]:
    """Normal displacement (m) of contact ``node`` (or the mean tip displacement) and a label."""
    if "contact_displacement" in res.signals:
        n = res.signals["contact_displacement"].shape[1]
        node = int(np.clip(node, 0, n - 1))
        return res.signals["contact_displacement"][:, node], f"contact {node}"
    return res.signal("tip_displacement"), "tip (mean over the contacts)"


def response_panels(res, omega: float, *, node: int = 0, window: float = 5.0):
    """Radial displacement of ``node`` vs revolutions: whole run, first and last ``window``."""
    y, label = response_of(res, node)
    rev = res.t * omega / (2.0 * np.pi)
    fig, ax = plt.subplots(3, 1, figsize=(7.5, 7.5))
    spans = [(rev[0], rev[-1]), (rev[0], rev[0] + window), (max(rev[-1] - window, 0.0), rev[-1])]
    titles = ["whole run", f"first {window:g} revolutions", f"last {window:g} revolutions"]
    for a, (lo, hi), title in zip(ax, spans, titles):
        sel = (rev >= lo) & (rev <= hi)
        a.plot(rev[sel], y[sel] * 1e6, lw=0.6)
        a.set_title(f"{label}: {title}", fontsize=9)
        a.set_ylabel("radial displ. (µm)")
        a.grid(True, lw=0.3, alpha=0.6)
    ax[-1].set_xlabel("revolutions")
    fig.tight_layout()
    return fig


def spectrum_panel(res, omega: float, *, node: int = 0, max_order: int = 20):
    """Amplitude spectrum of the response of ``node`` with engine-order lines."""
    y, label = response_of(res, node)
    y = y - y.mean()
    n = y.size
    amp = 2.0 * np.abs(np.fft.rfft(y * np.hanning(n))) / max(np.hanning(n).sum(), 1e-300)
    f = np.fft.rfftfreq(n, d=res.h)
    f_rot = omega / (2.0 * np.pi)
    fig, ax = plt.subplots(figsize=(7.5, 3.5))
    keep = f <= (max_order + 0.5) * f_rot if f_rot > 0 else slice(None)
    ax.semilogy(f[keep], np.maximum(amp[keep], 1e-16) * 1e6, lw=0.7)
    for k in range(1, max_order + 1):
        ax.axvline(k * f_rot, color="0.6", lw=0.5, ls=":")
    ax.set_xlabel(f"frequency (Hz); dotted: engine orders k Ω/2π, Ω/2π = {f_rot:.1f} Hz")
    ax.set_ylabel("amplitude (µm)")
    ax.set_title(f"spectrum of the radial displacement, {label}", fontsize=9)
    ax.grid(True, lw=0.3, alpha=0.6)
    fig.tight_layout()
    return fig


def contact_force_panel(res, omega: float):
    """Normal and friction force (N) of every contact vs the rotor angle ``mod(Ω t, 360°)``."""
    angle = np.degrees(np.mod(res.t * omega, 2.0 * np.pi))
    lam = res.force
    ff = res.friction_force
    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7.5, 6))
    for i in range(lam.shape[1]):
        on = lam[:, i] > 0.0
        ax[0].plot(angle[on], lam[on, i], ".", ms=1.5, label=f"contact {i}")
        if ff is not None and ff.size:
            ax[1].plot(angle[on], np.linalg.norm(ff[on, i], axis=-1), ".", ms=1.5)
    ax[0].set_ylabel("normal force (N)")
    ax[1].set_ylabel("friction force (N)")
    ax[1].set_xlabel("rotor angle Ω t mod 360 (deg)")
    if lam.shape[1] <= 16:
        ax[0].legend(fontsize=6, ncol=4, markerscale=4)
    for a in ax:
        a.grid(True, lw=0.3, alpha=0.6)
    fig.tight_layout()
    return fig
