"""Time-step convergence of a rub against an abradable coating.

One scene is built once (model, reduction, coating); its θ-method is then stepped over the
same interval at ``h / f`` for every factor ``f``, a fresh coating each time. Per factor:
the steps per wear-map cell, the total normal impulse, the share of contact-steps held at
the coating's yield bound, the number of separate cutting episodes of the most active
contact, the worn volume, the largest wear depth, the hottest contact temperature and the
CPU time. The same set-up with a rigid casing (``contact.abradable.thickness = 0``) is
stepped as a control.

``python benchmarks/abradable_convergence.py`` (twisted NACA blade with a 100 µm coating,
yield 20 N, 3600 cells, 1.5 ms) and ``--rotor37`` (the ``rotor37-thermal`` scene over one
lobe passage; run it under ``flock /tmp/femrub-heavy.lock``) store their rows with where
they were measured in ``docs/performance/abradable_convergence.json`` and render the tables
between the ``abradable_convergence_<study>`` markers of ``docs/abradable.md``
(``--render-only``: render the page from the JSON without running anything).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from _common import command_line, machine, read_json, render_sections, stamp, write_json

from femrub.analysis import make_stepper
from femrub.app.cache import DEFAULT_LIMIT, ModelCache
from femrub.app.scheme import scheme_options
from femrub.app.simulation import build
from femrub.scene.scene import load_scene

DOCS = Path(__file__).resolve().parents[1] / "docs"
DOC = DOCS / "abradable.md"
JSON = DOCS / "performance" / "abradable_convergence.json"

NACA = {
    "contact.abradable.thickness": 1e-4,
    "contact.abradable.yield": 20.0,
    "contact.abradable.n_angle": 3600,
    "reduction.method": "craig-bampton",
    "reduction.n_uv": 16,
    "reduction.n_theta": 16,
    "outputs.vtk_stride": 0,
}
# stepped over one lobe passage from the published 1000 steps per revolution down
ROTOR37 = {"outputs.vtk_stride": 0, "scheme.h": 4.675e-6}


def study(scene, t_end: float, factors) -> list[dict]:
    """Step ``scene``'s model at ``h / f`` for each factor; one row per factor."""
    sim = build(scene, cache=ModelCache(None, DEFAULT_LIMIT))
    h0, options = scene["scheme"]["h"], scheme_options(scene)
    wear = sim.model.contact.wear
    rows = []
    for f in factors:
        h = h0 / f
        stepper = make_stepper(scene["scheme"]["name"], sim.model, h, **options)
        c0 = time.process_time()
        res = stepper.run(t_end)
        cpu = time.process_time() - c0
        P = res.impulse
        row = {"f": f, "h": h, "impulse": float(P.sum()), "cpu": cpu}
        temps = res.signals.get("contact_temperature")
        row["T_max"] = float(np.max(temps)) if temps is not None else float("nan")
        if wear is not None:
            wear = stepper.model.contact.wear  # this run's coating
            cap = h * wear.yield_force
            held = P >= (1.0 - 1e-9) * cap
            active = P > 0
            j = int(np.argmax(active.sum(axis=0)))
            steps_j = np.flatnonzero(active[:, j])
            row.update(
                steps_per_cell=(2 * np.pi / wear.n_angle) / abs(wear.grid.omega * h),
                held=float(held.sum() / max(active.sum(), 1)),
                episodes=int(np.sum(np.diff(steps_j) > 1) + 1) if steps_j.size else 0,
                volume=wear.worn_volume,
                depth=wear.max_depth,
            )
        rows.append(row)
        print(row, flush=True)
    return rows


def table(rows, rigid) -> str:
    ref = rows[-1]
    out = [
        "| h | steps per cell | total impulse (N s) | vs finest | held at the yield | "
        "cutting episodes (busiest contact) | worn volume (m³) | vs finest | max wear (µm) | "
        "hottest contact rise (K) | CPU (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        out.append(
            f"| h/{r['f']} = {r['h']:.3g} s | {r['steps_per_cell']:.2g} | {r['impulse']:.4g} | "
            f"{r['impulse'] / ref['impulse'] - 1:+.1%} | {r['held']:.0%} | {r['episodes']} | "
            f"{r['volume']:.4g} | {r['volume'] / ref['volume'] - 1:+.1%} | "
            f"{1e6 * r['depth']:.4g} | {r['T_max']:.4g} | {r['cpu']:.2g} |"
        )
    if not rigid:
        return "\n".join(out)
    out.append("")
    out.append("Rigid casing (no coating), same interval:")
    out.append("")
    out.append("| h | total impulse (N s) | vs finest | hottest contact rise (K) |")
    out.append("|---|---|---|---|")
    for r in rigid:
        out.append(
            f"| h/{r['f']} | {r['impulse']:.4g} | {r['impulse'] / rigid[-1]['impulse'] - 1:+.2%} "
            f"| {r['T_max']:.4g} |"
        )
    return "\n".join(out)


def section(entry: dict) -> str:
    """One study's stamp and tables."""
    return stamp(entry["command"], entry["machine"]) + "\n\n" + table(entry["rows"], entry["rigid"])


def render(data: dict) -> dict[str, str]:
    """``marker name -> text`` of every study in ``data`` (the JSON document)."""
    return {f"abradable_convergence_{k}": section(v) for k, v in data.items()}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rotor37", action="store_true", help="rotor37-thermal, one lobe passage")
    p.add_argument("--factors", default=None, help="comma-separated step divisors")
    p.add_argument("--no-rigid", action="store_true", help="skip the rigid-casing control")
    p.add_argument("--render-only", action="store_true", help="render docs from the JSON")
    a = p.parse_args(argv)
    command = command_line("abradable_convergence.py", argv)
    data = read_json(JSON) if JSON.exists() else {}
    if a.render_only:
        render_sections(DOC, render(data))
        return 0
    if a.rotor37:
        name, scene = "rotor37-thermal", load_scene("rotor37-thermal", ROTOR37)
        t_end, factors = 2.3375e-3, [1, 2, 4, 8, 16]
    else:
        name, scene = "twisted-naca", load_scene("twisted-naca", NACA)
        t_end, factors = 1.5e-3, [1, 2, 4, 8, 16, 32]
    if a.factors:
        factors = [int(x) for x in a.factors.split(",")]
    where = machine()
    rows = study(scene, t_end, factors)
    rigid = []
    if not a.no_rigid:
        rigid = study(scene.with_changes({"contact.abradable.thickness": 0.0}), t_end, factors[::2])
    data[name] = {"command": command, "machine": where, "rows": rows, "rigid": rigid}
    write_json(JSON, data)
    render_sections(DOC, render(read_json(JSON)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
