"""The 40-speed × 50-revolution interaction map of Rotor 37 (target: ≤ 2 min), one command.

Runs ``femrub sweep rotor37 --param loads.rotation_speed=850:1825:25`` (reduced, friction
on, 50,000 steps per point; no VTK frames, no PNG plots, no ``history.csv`` and no
``history.npz`` in the points: the map reads each point's ``summary.json``, which holds the
largest magnitude and root mean square of every signal) on ``--workers`` processes (the sweep's
own and local dask workers) with an empty model cache and numba's cache warm (a short run of
the same scene first, in a child, with its own model cache: every function femrub compiles
for the map, the contact kernels and the finite-element ones, is then on disk; a fresh
install's compilation is ``cold_start.py``'s subject), in a child process, and records the
wall time, the CPU and the largest resident memory of the processes (``getrusage`` of the
children), the 1-minute load at the start, at the end and its median (sampled every 15 s),
the points' statuses, the median of each stage of a point (``summary.json["timings"]``), the
time of the first point, of a worker's first point and of the others (the sweep's critical
path) and the size of the model cache at the end. Appends a row to the table between the
``speed_map`` markers of ``docs/performance/speed-map-costs.md`` (``--no-write``: print it).

Run: ``flock /tmp/femrub-heavy.lock python benchmarks/speed_map.py`` (both cores for a few
minutes); ``--speeds 1300:1400:25`` for a smaller map. Skips without ``../shared/data``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _common import DOCS, write_between  # noqa: E402

STAGES = ("mesh", "assembly", "reduction", "stepping", "output")
SETS = (
    "outputs.vtk_stride=0",
    "outputs.plots=false",
    "outputs.csv_stride=0",
    "outputs.history_npz=false",
)
HEADER = (
    "| date (UTC) | code | speeds | wall (s) | CPU user + sys (s) | largest process | "
    "ok / inaccurate / other | per point, median (s): mesh, assembly, reduction, stepping, "
    "output = total | first point; a worker's first (median); the others (median) (s) | "
    "model cache at the end | load start – end (median) |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|"
)


def _commit() -> str:
    p = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    )
    dirty = subprocess.run(
        ["git", "-C", str(ROOT), "status", "--porcelain", "femrub"], capture_output=True, text=True
    ).stdout.strip()
    return p.stdout.strip() + (" + changes" if dirty else "")


def _sample_load(samples: list, stop: threading.Event) -> None:
    while not stop.wait(15.0):
        samples.append(os.getloadavg()[0])


def _dir_bytes(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def _points(out: Path) -> list[dict]:
    """Each point's status and stage timings, in the grid's order (the first point first)."""
    rows = []
    for s in sorted(out.glob("runs/*/summary.json")):
        d = json.loads(s.read_text())
        rows.append({"status": d.get("status"), "timings": d.get("timings", {})})
    return rows


def _critical(points: list[dict]) -> list[float]:
    """Seconds of the first point (it builds and fills the cache), the median of the points
    that built their full model from the cache (a worker's first: a ``mesh`` stage) and the
    median of the others (the previous point's model at their speed)."""
    total = [sum(p["timings"].get(k, 0.0) for k in STAGES) for p in points]
    built = [t for t, p in zip(total[1:], points[1:]) if p["timings"].get("mesh")]
    rest = [t for t, p in zip(total[1:], points[1:]) if not p["timings"].get("mesh")]
    medians = [statistics.median(x) if x else 0.0 for x in (built, rest)]
    return [total[0] if total else 0.0, *medians]


#: the warm-up run: the map's scene and settings over two revolutions (2,000 steps, its
#: checks included), in its own folder and model cache
WARM = ("--set", "scheme.t_end=0.00935")


def measure(speeds: str, workers: int, out: Path, cache: Path) -> dict:
    """Run the sweep in a child process (numba's cache warmed first); what it took."""
    cmd = [
        sys.executable,
        "-m",
        "femrub",
        "sweep",
        "rotor37",
        "--param",
        f"loads.rotation_speed={speeds}",
        "--workers",
        str(workers),
        "-o",
        str(out),
        "--cache-dir",
        str(cache),
    ]
    for s in SETS:
        cmd += ["--set", s]
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with tempfile.TemporaryDirectory() as warm:
        run = [sys.executable, "-m", "femrub", "run", "rotor37", "-q", *WARM]
        for s in SETS:
            run += ["--set", s]
        run += ["-o", str(Path(warm) / "run"), "--cache-dir", str(Path(warm) / "cache")]
        subprocess.run(run, env=env, check=True, capture_output=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)  # the warm-up's CPU left out
    samples, stop = [os.getloadavg()[0]], threading.Event()
    sampler = threading.Thread(target=_sample_load, args=(samples, stop), daemon=True)
    sampler.start()
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    stop.set()
    load_end = os.getloadavg()[0]
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode:
        raise RuntimeError(f"sweep failed ({p.returncode}): {p.stderr[-2000:]}")
    points = _points(out)
    statuses = [r["status"] for r in points]
    med = {k: statistics.median(r["timings"].get(k, 0.0) for r in points) for k in STAGES}
    return {
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M"),
        "code": _commit(),
        "speeds": speeds,
        "n_points": len(points),
        "wall": wall,
        "cpu": ru.ru_utime + ru.ru_stime - before.ru_utime - before.ru_stime,
        "peak_gb": ru.ru_maxrss * 1024 / 1e9,
        "ok": statuses.count("ok"),
        "inaccurate": statuses.count("inaccurate"),
        "other": len(statuses) - statuses.count("ok") - statuses.count("inaccurate"),
        "median": med,
        "critical": _critical(points),
        "cache_gb": _dir_bytes(cache) / 1e9,
        "load": [samples[0], load_end, statistics.median(samples + [load_end])],
    }


def row(r: dict) -> str:
    m = r["median"]
    parts = ", ".join(f"{m[k]:.1f}" for k in STAGES)
    lo, hi, med = r["load"]
    return (
        f"| {r['date']} | {r['code']} | {r['speeds']} ({r['n_points']}) | {r['wall']:.1f} | "
        f"{r['cpu']:.0f} | {r['peak_gb']:.2f} GB | {r['ok']} / {r['inaccurate']} / "
        f"{r['other']} | {parts} = {sum(m.values()):.1f} | "
        f"{'; '.join(f'{x:.1f}' for x in r['critical'])} | {r['cache_gb']:.2f} GB | "
        f"{lo:.2f} – {hi:.2f} ({med:.2f}) |"
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", default="850:1825:25", help="rad/s, START:STOP:STEP or A,B")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", help="sweep folder to keep (default: a temporary one)")
    ap.add_argument("--no-write", action="store_true")
    a = ap.parse_args(argv)
    if not (ROOT.parent / "shared" / "data").is_dir() and not os.environ.get("FEMRUB_SHARED_DATA"):
        print("skipped: no ../shared/data (Rotor 37 mesh)")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(a.out) if a.out else Path(tmp) / "map"
        r = measure(a.speeds, a.workers, out, Path(tmp) / "cache")
    print(json.dumps(r, indent=1))
    line = row(r)
    print(line)
    if not a.no_write:
        doc = DOCS / "performance" / "speed-map-costs.md"
        text = doc.read_text()
        begin, end = "<!-- speed_map:begin -->", "<!-- speed_map:end -->"
        old = text[text.index(begin) + len(begin) : text.index(end)] if begin in text else ""
        rows = [x for x in old.strip().splitlines() if x.startswith("| 20")]
        write_between(doc, "speed_map", "\n".join([HEADER, *rows, line]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
