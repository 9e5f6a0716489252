"""Interaction map of a sweep: response peaks against the swept parameter, Campbell diagram.

Panels: maximum tip displacement, maximum contact force and maximum temperature against the
first swept parameter (one curve per combination of the others) and, when that parameter is
the rotation speed, the Campbell diagram: natural frequencies of the blade against the
engine-order lines ``k Ω / 2π`` of the casing lobes (and of the tip force), with the
crossings (interaction speeds ``Ω = 2π f / k``) drawn as dotted lines across every panel.
"""

from __future__ import annotations

import math

import numpy as np

from .plots import plt, savefig

__all__ = ["engine_orders", "plot_interaction_map"]

_PANELS = [
    ("max_tip_displacement", "max |tip displacement| (µm)", 1e6),
    ("max_contact_force", "max contact force (N)", 1.0),
    ("max_temperature", "max temperature rise (K)", 1.0),
]


def engine_orders(scene) -> list[int]:
    """Engine orders that excite the blade: casing lobes (and harmonics) and the tip force."""
    casing = scene["contact"]["casing"]
    lobes = {"lobed": casing.get("lobes", 0), "two-lobe": 2}.get(casing["kind"], 0)
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
    n = len(_PANELS) + int(campbell)
    fig, axes = plt.subplots(n, 1, sharex=True, figsize=(7.5, 2.2 * n + 0.6))
    groups = _groups(rows, keys)
    for ax, (name, label, scale) in zip(axes, _PANELS):
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
    xs = np.array(sorted({r["x"] for r in rows}), dtype=float)
    freqs = [r.get("natural_frequencies_hz") or [] for r in sorted(rows, key=lambda r: r["x"])]
    f_ref = next((f for f in freqs if f), [])
    x_line = np.linspace(0.0, max(xs.max(), 1e-12) * 1.05, 50)
    for j, f in enumerate(f_ref):
        ax.axhline(
            f, color="C0", lw=1.0, alpha=0.8, label="natural frequencies" if j == 0 else None
        )
    orders = engine_orders(scene)
    for k in orders:
        ax.plot(x_line, k * x_line / (2 * math.pi), "--", lw=0.9, color="0.35")
        ax.annotate(f"EO {k}", (x_line[-1], k * x_line[-1] / (2 * math.pi)), fontsize=7)
        for f in f_ref:
            w = 2 * math.pi * f / k
            if xs.min() <= w <= xs.max():
                for a in axes:
                    a.axvline(w, color="C3", lw=0.7, ls=":")
    # the engine-order fan and at least the first natural frequency
    top = max(max(orders) * x_line[-1] / (2 * math.pi), f_ref[0] if f_ref else 0.0) * 1.2
    ax.set_ylim(0.0, top)
    ax.set_ylabel("frequency (Hz)", fontsize=8)
    ax.grid(True, lw=0.3, alpha=0.6)
    ax.legend(fontsize=7, loc="upper left")
