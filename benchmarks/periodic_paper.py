"""Periodic orbits of the paper's bar against long time integrations (docs/periodic.md).

Runs ``femrub periodic paper --set physics.thermal=off --set scheme.h=2e-6
--param loads.rotation_speed=20000rpm:40000rpm`` (or reads its finished folder), takes up to
``--points`` stable points of the branch, runs ``femrub run`` at each of their speeds for
``--revolutions`` periods of the forcing, and compares the branch's ``max_tip_displacement``
with the largest tip displacement of the run's last ``--last`` periods (the transient left
out). Without a stable point it runs at both ends of the range and reports the same
numbers. A run whose per-period maxima over those periods spread by more than 2 % has not
settled onto a periodic response (``spread`` in the output): no orbit can agree with it.
Writes ``DIR/comparison.json`` and prints one line per point; exit status 1 when a stable
point differs by more than 2 %, a compared run has not settled, the branch has no stable
point, or the branch is not ``ok``.

Usage::

    python benchmarks/periodic_paper.py -o periodic-paper [--points 3] [--revolutions 400]
        [--set KEY=VALUE ...]   (more changes, to the branch and the runs alike)
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

SETS = ["--set", "physics.thermal=off", "--set", "scheme.h=2e-6"]
PARAM = "loads.rotation_speed=20000rpm:40000rpm"
TOLERANCE = 0.02
#: the ends of PARAM (rad/s): long runs there when the branch has no stable point
ENDS = (20000 * math.pi / 30, 40000 * math.pi / 30)


def _femrub(*args: str) -> int:
    return subprocess.call([sys.executable, "-m", "femrub.app.cli", *args])


def branch_rows(out: Path, sets: list) -> list[dict]:
    """The branch's rows, running ``femrub periodic`` when its folder has no summary."""
    if not (out / "summary.json").exists():
        _femrub("periodic", "paper", *SETS, *sets, "--param", PARAM, "-o", str(out))
    with open(out / "branch.csv") as fh:
        return list(csv.DictReader(fh))


def run_peak(out: Path, speed: float, periods: int, last: int, sets: list) -> tuple:
    """Largest |tip displacement| (m) of the last ``last`` of ``periods`` forcing periods of
    a ``femrub run`` at ``speed`` (rad/s), and the spread ``(max − min) / max`` of the
    per-period maxima over those periods (0 for a periodic response)."""
    period = 2.0 * math.pi / speed
    t_end = periods * period
    h = period / math.ceil(period / 2e-6)  # a whole number of steps per period
    folder = out / f"run_{speed:.6g}"
    changes = ["--set", f"loads.rotation_speed={speed!r}", "--set", f"scheme.t_end={t_end!r}"]
    changes += ["--set", f"scheme.h={h!r}", "--set", "physics.thermal=off", *sets]
    _femrub("run", "paper", *changes, "-o", str(folder), "--overwrite", "--quiet")
    with np.load(folder / "history.npz") as hist:
        t, x = hist["t"], np.abs(hist["signal_tip_displacement"])
    which = np.floor((t_end - t) / period - 1e-9).astype(int)
    peaks = np.array([x[which == j].max() for j in range(last) if np.any(which == j)])
    return float(peaks.max()), float((peaks.max() - peaks.min()) / peaks.max())


def settling(out: Path, speed: float, args, sets: list) -> dict:
    """A long run at ``speed`` (rad/s) when the branch gives no stable point there to compare:
    its largest tip displacement and the spread of its per-period maxima (whether a periodic
    response exists for a branch to find)."""
    run, spread = run_peak(out, speed, args.revolutions, args.last, sets)
    print(
        f"{speed:.6g} rad/s: no orbit; run {run:.6g} m, "
        f"per-period maxima spread {100 * spread:.2f} %"
    )
    return {"rotation_speed": speed, "run": run, "spread": spread}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default="periodic-paper", help="branch folder")
    p.add_argument("--points", type=int, default=3, help="stable points compared")
    p.add_argument("--revolutions", type=int, default=400, help="forcing periods per run")
    p.add_argument("--last", type=int, default=20, help="periods of the run compared")
    p.add_argument("--set", action="append", default=[], help="more scene changes (both)")
    args = p.parse_args(argv)
    out = Path(args.out)
    sets = [a for kv in args.set for a in ("--set", kv)]
    rows = branch_rows(out, sets)
    summary = json.loads((out / "summary.json").read_text())
    stable = [r for r in rows if r["stable"] == "1"]
    pick = (
        [stable[i] for i in np.linspace(0, len(stable) - 1, args.points).astype(int)]
        if stable
        else []
    )
    result = []
    for r in pick:
        speed = float(r["loads.rotation_speed"])
        orbit = float(r["max_tip_displacement"])
        run, spread = run_peak(out, speed, args.revolutions, args.last, sets)
        err = abs(orbit - run) / run
        result.append(
            {"rotation_speed": speed, "orbit": orbit, "run": run, "relative": err, "spread": spread}
        )
        print(
            f"{speed:.6g} rad/s: orbit {orbit:.6g} m, run {run:.6g} m, {100 * err:.2f} % "
            f"(run's per-period maxima spread {100 * spread:.2f} %)"
        )
    if not pick:
        print(f"no stable point to compare ({summary.get('status')}: {summary.get('message')})")
    unsettled = [] if pick else [settling(out, speed, args, sets) for speed in ENDS]
    doc = {
        "branch_status": summary.get("status"),
        "branch_message": summary.get("message"),
        "points": len(rows),
        "stable": len(stable),
        "special": summary.get("special", []),
        "comparisons": result,
        "runs_without_orbit": unsettled,
    }
    (out / "comparison.json").write_text(json.dumps(doc, indent=2) + "\n")
    print(
        json.dumps({k: v for k, v in doc.items() if k not in ("comparisons", "runs_without_orbit")})
    )
    ok = (
        summary.get("status") == "ok"
        and result
        and all(c["relative"] <= TOLERANCE and c["spread"] <= TOLERANCE for c in result)
    )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
