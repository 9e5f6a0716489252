"""Periodic orbits of reduced Rotor 37: a stretch of the branch, its cost, and its points
against long time integrations (docs/periodic.md, docs/performance/periodic-rotor37.md).

Builds the ``rotor37`` scene (mechanical, reduced, 16 frictional contacts on the two-lobe
casing; through the model cache), continues its periodic orbits in the rotation speed from
``--start`` towards ``--stop`` for at most ``--points`` points (``femrub.periodic.
continue_branch``) and records per point the speed, the largest tip displacement of the
orbit, its largest Floquet multiplier, whether the finite-difference monodromy settled
(``unsettled_columns``) and the wall time. The stretch's two ends and up to three of its
stable points are then integrated in time from rest over ``--periods`` forcing periods by
the same θ-method (the period map iterated, the same steps): the largest tip displacement
of the last ``--last`` periods is compared with the orbit's, with the spread of the
per-period maxima (0 for a run that settled onto a periodic response). From the stretch it
extrapolates what the whole range would cost at the same rate (points per rad/s, seconds
per point), to compare with the 40-speed sweep of ``benchmarks/speed_map.py``. A stretch
that stops early (the continuation's step below its floor) says so in its status.

Writes ``docs/performance/periodic_rotor37.json`` and renders
``docs/performance/periodic-rotor37.md`` (``--no-write``: print only).

Usage::

    python benchmarks/periodic_rotor37.py [--start 850] [--stop 1800] [--points 20]
        [--periods 300] [--last 20] [--set KEY=VALUE ...] [--no-write | --render-only]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

ROOT = Path(__file__).resolve().parents[1]
STORE = ROOT / "docs" / "performance" / "periodic_rotor37.json"
PAGE = ROOT / "docs" / "performance" / "periodic-rotor37.md"


def build_model(scene):
    """The reduced model of ``scene`` (through the default model cache) and its build time."""
    from femrub.app.cache import ModelCache
    from femrub.app.simulation import build

    (sim, _, wall) = C.timed(build, scene, cache=ModelCache(None), stepper=False)
    return sim.model, wall


def stretch(model, args, h: float) -> tuple:
    """The branch from ``args.start`` (at most ``args.points`` points) and the wall time at
    which each point was logged."""
    from femrub.periodic import continue_branch

    t0, clock = time.perf_counter(), []

    def log(text: str) -> None:
        clock.append(time.perf_counter() - t0)
        print(f"{clock[-1]:8.1f} s  {text}", flush=True)

    branch = continue_branch(model, args.start, args.stop, h=h, max_points=args.points, log=log)
    return branch, time.perf_counter() - t0, clock


def _picks(points) -> list[int]:
    """The points integrated in time: the stretch's two ends and up to three stable points
    (spread over those there are)."""
    if not points:
        return []
    stable = [i for i, p in enumerate(points) if p.stable]
    spread = [stable[j] for j in np.linspace(0, len(stable) - 1, min(3, len(stable))).astype(int)]
    return sorted({0, len(points) - 1, *spread})


def time_run(model, point, periods: int, last: int) -> dict:
    """The θ-method from rest at the point's speed over ``periods`` periods, on the point's
    own grid: the largest tip displacement of the last ``last`` periods and the spread
    ``(max − min) / max`` of their per-period maxima."""
    from femrub.periodic import PeriodMap, measures

    at = model.with_parameters(rotation_speed=point.parameter)
    pm = PeriodMap(at, point.h, steps=point.steps)
    X, peaks = np.zeros(at.n_dofs), []
    for k in range(periods):
        orbit = pm.orbit(X)
        X = orbit.X[-1]
        if k >= periods - last:
            peaks.append(measures(at, orbit, pm.h)["max_tip_displacement"])
    peaks = np.array(peaks)
    orbit_peak = point.measures["max_tip_displacement"]
    return {
        "rotation_speed": point.parameter,
        "orbit": orbit_peak,
        "run": float(peaks.max()),
        "relative": abs(orbit_peak - peaks.max()) / peaks.max(),
        "spread": float((peaks.max() - peaks.min()) / peaks.max()),
        "stable": bool(point.stable),
        "max_floquet_modulus": point.max_floquet_modulus,
    }


def _speeds(rows: list[dict]) -> list[dict]:
    """``rows`` with the rotation speed as text to 0.1 rad/s."""
    return [{**r, "rotation_speed": f"{r['rotation_speed']:.1f}"} for r in rows]


def page(doc: dict) -> str:
    """The page's generated text."""
    pts = _speeds(doc["points"])
    rate = doc["extrapolation"]
    lo, hi = (f"{doc[k]:.0f}" for k in ("start", "stop"))
    lines = [
        "## A stretch of the branch",
        "",
        f"Branch from {lo} rad/s towards {hi} rad/s, {len(pts)} points in "
        f"{C.fmt(doc['branch_wall'])} s (the model's build {C.fmt(doc['build_wall'])} s, from "
        f"the cache); the stretch's status `{doc['status']}`: {doc['message']}",
        "",
        C.md_table(
            pts,
            [
                ("rotation_speed", "Ω (rad/s)"),
                ("max_tip_displacement", "max tip (m)"),
                ("max_floquet_modulus", "max abs μ"),
                ("stable", "stable"),
                ("unsettled", "unsettled columns"),
                ("iterations", "corrections"),
                ("seconds", "wall (s)"),
            ],
        ),
        "",
        "Time integrations from rest at its ends and at up to three stable points (the same "
        "θ-method and steps):",
        "",
        C.md_table(
            _speeds(doc["runs"]),
            [
                ("rotation_speed", "Ω (rad/s)"),
                ("stable", "orbit stable"),
                ("max_floquet_modulus", "max abs μ"),
                ("orbit", "orbit max tip (m)"),
                ("run", "run max tip (m)"),
                ("relative", "difference"),
                ("spread", "run's per-period spread"),
            ],
        ),
        "",
        f"At this stretch's rate ({C.fmt(rate['rad_s_per_point'])} rad/s and "
        f"{C.fmt(rate['seconds_per_point'])} s per point) the branch over "
        f"{lo}–{hi} rad/s would take about "
        f"{C.fmt(rate['points'])} points and {C.fmt(rate['seconds'])} s.",
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--start", type=float, default=850.0, help="rad/s")
    ap.add_argument("--stop", type=float, default=1800.0, help="rad/s")
    ap.add_argument("--points", type=int, default=20, help="most branch points")
    ap.add_argument("--periods", type=int, default=300, help="forcing periods per time run")
    ap.add_argument("--last", type=int, default=20, help="periods of a run compared")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--render-only", action="store_true", help="render the page from the JSON")
    args = ap.parse_args(argv)
    if args.render_only:
        entry = C.read_json(STORE)["stretch"]
        entry["text"] = page(entry["data"])
        C.store_section(STORE, PAGE, "periodic_rotor37", "stretch", entry)
        return 0
    scene = C.cli_scene("rotor37", [*args.set, f"loads.rotation_speed={args.start!r}"])
    if scene is None:
        return 0
    machine = C.machine()
    model, build_wall = build_model(scene)
    branch, wall, clock = stretch(model, args, scene["scheme"]["h"])
    seconds = np.diff([0.0, *clock])
    pts = [
        {
            "rotation_speed": p.parameter,
            "max_tip_displacement": p.measures["max_tip_displacement"],
            "max_floquet_modulus": p.max_floquet_modulus,
            "stable": int(p.stable),
            "unsettled": p.unsettled,
            "iterations": p.iterations,
            "seconds": float(s),
        }
        for p, s in zip(branch.points, seconds)
    ]
    picks = _picks(branch.points)
    runs = [time_run(model, branch.points[i], args.periods, args.last) for i in picks]
    for r in runs:
        print(r)
    span = abs(pts[-1]["rotation_speed"] - pts[0]["rotation_speed"]) if len(pts) > 1 else 0.0
    per_point = span / max(len(pts) - 1, 1)
    count = abs(args.stop - args.start) / per_point if per_point else float("nan")
    mean = wall / max(len(pts), 1)
    doc = {
        "machine": machine,
        "start": args.start,
        "stop": args.stop,
        "status": branch.status,
        "message": branch.message,
        "build_wall": build_wall,
        "branch_wall": wall,
        "points": pts,
        "runs": runs,
        "extrapolation": {
            "rad_s_per_point": per_point,
            "seconds_per_point": mean,
            "points": count,
            "seconds": count * mean,
        },
    }
    text = page(doc)
    print(text)
    if not args.no_write:
        entry = {"command": C.command_line("periodic_rotor37.py", argv), "machine": machine}
        entry["text"] = text
        entry["data"] = {k: v for k, v in doc.items() if k != "machine"}
        if not PAGE.exists():
            PAGE.write_text(
                "# Periodic orbits of reduced Rotor 37\n\nWhat `femrub periodic rotor37` costs "
                "and how its orbits compare with time integrations "
                "(`python benchmarks/periodic_rotor37.py`; docs/periodic.md).\n"
            )
        C.store_section(STORE, PAGE, "periodic_rotor37", "stretch", entry)
    return 0


if __name__ == "__main__":
    sys.exit(main())
