"""Interaction map of a sweep: response peaks against the swept parameter, Campbell diagram.

Panels: maximum and RMS tip displacement, maximum contact force, maximum temperature and
maximum abradable wear depth (these two only when the scene models them: see
:func:`panels`) against the first swept parameter (one curve per combination
of the others) and, when that parameter is the rotation speed, the Campbell diagram: the
natural frequencies of each point's model (prestressed at its speed) against the
engine-order lines ``k Ω / 2π`` of the casing lobes (and of the tip force), with the
crossings (interaction speeds ``Ω = 2π f / k``) drawn as dotted lines across every panel.
"""

from __future__ import annotations

import math

import numpy as np

from ..contact.casing import lobe_count
from .plots import plt, savefig

__all__ = ["engine_orders", "panels", "plot_interaction_map"]

_PANELS = [
    ("max_tip_displacement", "max |tip displacement| (µm)", 1e6),
    ("rms_tip_displacement", "RMS tip displacement (µm)", 1e6),
    ("max_contact_force", "max contact force (N)", 1.0),
    ("max_temperature", "max temperature rise (K)", 1.0),
    ("max_wear_depth", "max wear depth (µm)", 1e6),
]


def panels(rows, scene) -> list[tuple]:
    """The panels of a map: the temperature only with ``physics.thermal = "on"`` or a point
    that heated, the wear only with an abradable coating or a point that wore."""
    models = {
        "max_temperature": scene["physics"]["thermal"] == "on",
        "max_wear_depth": scene["contact"]["abradable"]["thickness"] > 0.0,
    }
    return [p for p in _PANELS if models.get(p[0], True) or any(r.get(p[0]) for r in rows)]


def engine_orders(scene) -> list[int]:
    """Engine orders that excite the blade: casing lobes (and harmonics) and the tip force."""
    casing = scene["contact"]["casing"]
    lobes = lobe_count(casing)
    orders = {lobes * j for j in (1, 2, 3)} if lobes else {1, 2, 3}
    force = scene["loads"]["tip_force"]
    if force["law"] == "sin" and force["frequency"] == "rotation":
        orders.add(force["engine_order"])
    return sorted(orders)


def _groups(rows, keys):
    """Rows grouped by the values of the parameters after the first one."""
    out = {}
    for r in rows:
        label = ", ".join(f"{k.rsplit('.', 1)[-1]} = {r['params'][k]}" for k in keys[1:])
        out.setdefault(label, []).append(r)
    return out


def plot_interaction_map(rows, keys, scene, path) -> None:
    """Draw the interaction map of sweep ``rows`` (see :func:`femrub.app.sweep.run_sweep`)."""
    x_key = keys[0]
    campbell = x_key == "loads.rotation_speed"
    shown = panels(rows, scene)
    n = len(shown) + int(campbell)
    fig, axes = plt.subplots(n, 1, sharex=True, figsize=(7.5, 2.2 * n + 0.6))
    groups = _groups(rows, keys)
    for ax, (name, label, scale) in zip(axes, shown):
        for glabel, grp in groups.items():
            grp = sorted((r for r in grp if r.get(name) is not None), key=lambda r: r["x"])
            xs = [r["x"] for r in grp]
            ys = [r[name] * scale for r in grp]
            ax.plot(xs, ys, "o-", ms=3, lw=1.2, label=glabel or None)
            bad = [(r["x"], r[name] * scale) for r in grp if r["status"] != "ok"]
            if bad:
                ax.plot(*zip(*bad), "x", color="r", ms=6, label="status not ok")
        ax.set_ylabel(label, fontsize=8)
        ax.grid(True, lw=0.3, alpha=0.6)
    if any(ax.get_legend_handles_labels()[1] for ax in axes[:1]):
        axes[0].legend(fontsize=7, loc="best")
    if campbell:
        _campbell(axes[-1], rows, scene, axes)
    axes[-1].set_xlabel(x_key + (" Ω (rad/s)" if campbell else ""))
    fig.suptitle(f"interaction map: {scene['name']}", fontsize=10)
    fig.tight_layout()
    savefig(fig, path)


def _campbell(ax, rows, scene, axes) -> None:
    """Natural frequencies of each point's (prestressed) model against Ω, engine orders and
    their crossings ``k Ω / 2π = f_j(Ω)`` (interpolated between the points)."""
    done = sorted((r for r in rows if r.get("natural_frequencies_hz")), key=lambda r: r["x"])
    xs = np.array(sorted({r["x"] for r in rows}), dtype=float)
    n_f = min((len(r["natural_frequencies_hz"]) for r in done), default=0)
    xf = np.array([r["x"] for r in done], dtype=float)
    F = np.array([r["natural_frequencies_hz"][:n_f] for r in done]).reshape(len(done), n_f)
    f_ref = list(F[0]) if len(done) else []
    x_line = np.linspace(0.0, max(xs.max(), 1e-12) * 1.05, 50)
    for j in range(n_f):
        ax.plot(
            xf, F[:, j], "-", color="C0", lw=1.2, label="natural frequencies" if j == 0 else None
        )
    orders = engine_orders(scene)
    for k in orders:
        ax.plot(x_line, k * x_line / (2 * math.pi), "--", lw=0.9, color="0.35")
        ax.annotate(f"EO {k}", (x_line[-1], k * x_line[-1] / (2 * math.pi)), fontsize=7)
        for j in range(n_f):
            d = F[:, j] - k * xf / (2 * math.pi)
            for i in np.flatnonzero(np.sign(d[:-1]) * np.sign(d[1:]) <= 0):
                w = (
                    xf[i] + (xf[i + 1] - xf[i]) * d[i] / (d[i] - d[i + 1])
                    if d[i] != d[i + 1]
                    else xf[i]
                )
                for a in axes:
                    a.axvline(w, color="C3", lw=0.7, ls=":")
            if len(done) == 1:  # one point: the crossing of its constant line
                w = 2 * math.pi * F[0, j] / k
                if xs.min() <= w <= xs.max():
                    for a in axes:
                        a.axvline(w, color="C3", lw=0.7, ls=":")
    # the engine-order fan and at least the first natural frequency
    top = max(max(orders) * x_line[-1] / (2 * math.pi), f_ref[0] if f_ref else 0.0) * 1.2
    ax.set_ylim(0.0, top)
    ax.set_ylabel("frequency (Hz)", fontsize=8)
    ax.grid(True, lw=0.3, alpha=0.6)
    if ax.get_legend_handles_labels()[0]:  # a bladed disk's points carry no frequencies
        ax.legend(fontsize=7, loc="upper left")
