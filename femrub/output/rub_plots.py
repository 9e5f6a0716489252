"""Figures of a rub run on a rotating blade, against revolutions of the rotor.

* :func:`response_panels`: the response (the first displacement probe, else one contact
  node) over the whole run and over its first and last ``window`` revolutions;
* :func:`spectrum_panel`: the amplitude spectrum of that response with the engine-order
  lines ``k Ω / 2π``;
* :func:`contact_force_panel`: the summed normal (and friction) force of the contacts as a
  map, rotor angle ``mod(Ω t, 360°)`` across and revolution up (:func:`force_map`).

Inputs are :class:`~femrub.output.results.Results` and the rotation speed Ω (rad/s).
"""

from __future__ import annotations

import numpy as np

from .plots import plt
from .results import PROBE_PREFIX

__all__ = [
    "contact_force_panel",
    "force_map",
    "response_of",
    "response_panels",
    "spectrum_panel",
]


def response_of(res, node: int = 0) -> tuple[np.ndarray, str]:
    """The response engineers read (m) and its label: the first displacement probe
    (``outputs.probes``, e.g. Rotor 37's node 1353 along y), else the normal displacement of
    contact ``node``, else the mean tip displacement."""
    units = res.info.get("signal_units", {}) if isinstance(res.info, dict) else {}
    probes = [k for k in res.signals if k.startswith(PROBE_PREFIX) and units.get(k) == "m"]
    if probes:
        return res.signals[probes[0]][:, 0], f"probe {probes[0][len(PROBE_PREFIX) :]}"
    if "contact_displacement" in res.signals:
        n = res.signals["contact_displacement"].shape[1]
        node = int(np.clip(node, 0, n - 1))
        return res.signals["contact_displacement"][:, node], f"contact {node} (normal)"
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
        a.set_ylabel("displacement (µm)")
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
    ax.set_title(f"spectrum of the displacement, {label}", fontsize=9)
    ax.grid(True, lw=0.3, alpha=0.6)
    fig.tight_layout()
    return fig


#: largest number of rotor-angle cells of a contact-force map
MAX_ANGLE_CELLS = 360


def force_map(t, force, omega: float, n_angle: int) -> tuple[np.ndarray, np.ndarray]:
    """The largest ``force`` (one value per time of ``t``, s) in each cell of rotor angle
    ``mod(Ω t, 2π)`` (``n_angle`` cells) and revolution ``floor(Ω t / 2π)``:
    ``(revolution edges, (revolutions, n_angle) array)``, NaN where no time falls."""
    turns = np.asarray(t, dtype=float) * omega / (2.0 * np.pi)
    rev = np.floor(turns).astype(np.int64)
    rev -= rev.min(initial=0)
    cell = np.minimum((np.mod(turns, 1.0) * n_angle).astype(np.int64), n_angle - 1)
    grid = np.full((int(rev.max(initial=0)) + 1, n_angle), -np.inf)
    np.maximum.at(grid, (rev, cell), np.asarray(force, dtype=float))
    grid[np.isneginf(grid)] = np.nan
    if grid.shape[0] > 1 and np.count_nonzero(rev == rev[-1]) == 1:
        grid = grid[:-1]  # a run ending on a whole revolution: its last time opens no new one
    first = np.floor(turns[0]) if turns.size else 0.0
    return first + np.arange(grid.shape[0] + 1), grid


def contact_force_panel(res, omega: float):
    """The summed normal force (and friction force) of the contacts (N) as a map: rotor
    angle ``mod(Ω t, 360°)`` across, revolution up; each cell holds the largest force of the
    steps that fall in it (the lobes' passages line up, an interaction's drift shows)."""
    lam = res.force
    total = lam.sum(axis=1)
    ff = res.friction_force
    friction = None if ff is None or not ff.size else res.friction_magnitude().sum(axis=1)
    steps_per_rev = 2.0 * np.pi / max(omega * res.h, 1e-300)
    n_angle = int(np.clip(steps_per_rev, 1, MAX_ANGLE_CELLS))
    maps = [("normal", total)] + ([("friction", friction)] if friction is not None else [])
    fig, ax = plt.subplots(1, len(maps), figsize=(6.0 * len(maps), 4.5), squeeze=False)
    edges = np.linspace(0.0, 360.0, n_angle + 1)
    for a, (name, values) in zip(ax[0], maps):
        revs, grid = force_map(res.t, values, omega, n_angle)
        im = a.pcolormesh(edges, revs, grid, shading="flat", cmap="viridis")
        fig.colorbar(im, ax=a, label=f"summed {name} force (N)")
        a.set_xlabel("rotor angle Ω t mod 360 (deg)")
        a.set_ylabel("revolution")
        a.set_title(f"{name} force of the {lam.shape[1]} contacts, largest per cell", fontsize=9)
    fig.tight_layout()
    return fig
