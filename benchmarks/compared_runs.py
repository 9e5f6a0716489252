"""What recording the checks' compared runs lean saves: one Rotor 37 point, same process.

The reduction error estimate (its reference and the reference's twin) and the time-step
check (the run at h/2 and its twin) step runs that are only compared with the run
(``RunOptions.compared``: no energy or heat balance, no Coulomb check, no gap or slip rows).
This script builds one point of a scene (``rotor37`` by default, at ``--speed``; the model
cache of the command line, so a second call loads the bases) and times, alternately in one
process, the estimate's reference run alone,
:func:`~femrub.analysis.reduction_check.checked_sizes` (the estimate) and
:func:`~femrub.analysis.step_check.check_step` (given the estimate's run, as a scene with
``scheme.step_check`` does) with the compared runs recorded as now and as before (lean
records that measure the balance and the Coulomb check on every row: ``compared=False``;
the gaps, which no lean record reads, are skipped on both paths),
checks that both give the same dicts, and prints the ratios of their CPU times (the process
runs on one BLAS thread; medians of ``--repeats``). Timings on a busy machine are noisy:
the ratio of two paths timed in turn in one process is what to read.

Run: ``python benchmarks/compared_runs.py [--scene rotor37] [--speed 1275] [--steps N]``
(``--steps``: a shorter run, ``scheme.t_end = N h``). Skips without ``../shared/data``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _paths(old: bool):
    """Record the compared runs as before (``old``: ``compared=False``) or as now."""
    from femrub.analysis import steppers

    original = steppers.__dict__.setdefault("_run_now", steppers.run)

    def before(stepper, t_end, options):
        return original(stepper, t_end, dataclasses.replace(options, compared=False))

    steppers.run = before if old else original


def _timed(call, old: bool):
    _paths(old)
    t0 = time.process_time()  # one thread: CPU seconds, less noisy than wall on a busy machine
    out = call()
    return out, time.process_time() - t0


def _without_seconds(d: dict) -> dict:
    return {k: v for k, v in d.items() if k != "seconds"}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="rotor37")
    ap.add_argument("--speed", type=float, default=1275.0, help="rad/s")
    ap.add_argument("--steps", type=int, default=0, help="steps of the run (0: the scene's)")
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args(argv)

    from femrub.analysis import reduction_check as est
    from femrub.analysis.step_check import check_step
    from femrub.app import build
    from femrub.app.cache import ModelCache
    from femrub.app.scheme import bare_stepper
    from femrub.geometry.rotor37 import shared_data_dir
    from femrub.scene import load_scene

    if not shared_data_dir().is_dir():
        print("skipped: no Rotor 37 data (../shared/data or $FEMRUB_SHARED_DATA)")
        return 0
    changes = {"loads.rotation_speed": args.speed, "outputs.vtk_stride": 0}
    scene = load_scene(args.scene, changes)
    if args.steps:
        changes["scheme.t_end"] = args.steps * scene["scheme"]["h"]
        scene = load_scene(args.scene, changes)
    cache = ModelCache(os.environ.get("FEMRUB_CACHE_DIR") or None)
    sim = build(scene, log=print, cache=cache)
    red = sim.reductor
    if red is None:
        print("the reduction came from the cache (no reductor): use another --speed")
        return 1
    chosen = tuple(sim.report["reduction"]["error"]["sizes"])  # (n_uv, n_θ) of the model run
    want = chosen if scene["reduction"]["method"] != "auto" else None
    make = lambda m: bare_stepper(scene, m)  # noqa: E731
    kept = []

    def estimate():  # keeps its run of the chosen sizes for the step check
        report = {}
        kept.clear()
        on_run = lambda *run: kept.append(run)  # noqa: E731
        est.checked_sizes(red, red.fom, want, make, scene, report, None, sim.limits, on_run)
        return _without_seconds(report["error"])

    def step():
        (res, states), fine = kept[0][0::2], lambda m, h: bare_stepper(scene, m, h)
        err, _, _ = check_step(scene, sim.model, sim.full, fine, sim.limits, (res.lean(), states))
        return _without_seconds(err)

    def reference():  # the estimate's reference alone: a run only compared
        most, t_end = (red.n_uv, red.n_theta), scene["scheme"]["t_end"]
        res, states = est.simulate(red, most, make, t_end, limits=sim.limits, lean=1)
        return res.t.tolist(), res.impulse.tolist(), states.tolist(), res.status

    calls = {"reference run": reference, "estimate": estimate, "step check": step}
    walls, outs = {(what, o): [] for what in calls for o in (False, True)}, {}
    for _ in range(args.repeats):
        for old in (True, False):
            for what, call in calls.items():
                outs[what, old], w = _timed(call, old)
                walls[what, old].append(w)
    _paths(False)
    for what in calls:
        same = outs[what, True] == outs[what, False]
        before = statistics.median(walls[what, True])
        now = statistics.median(walls[what, False])
        print(
            f"{args.scene} at {args.speed:g} rad/s, {what}: {now:.2f} s CPU now, {before:.2f} s "
            f"before (ratio {now / before:.3f}; same result: {same})"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
