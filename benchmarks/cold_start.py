"""A fresh machine's first ``femrub paper`` against the next ones, in one run.

Runs ``femrub paper --out DIR`` in a fresh process with an empty numba cache
(``NUMBA_CACHE_DIR``: the contact kernels compiled, as on a fresh install), then ``--repeat``
times with that cache warm, and records wall and CPU seconds and peak resident memory of
each (the child's ``ru_maxrss``) with the machine's load. Target: cold ≤ 2.5 × warm (the
ratio of the cold run to the median warm run, measured in the same run of this script).
Writes ``docs/performance/cold_start.json`` and the table between the ``cold_start`` markers
of ``README.md`` (``--no-write``: print it).

Run: ``python benchmarks/cold_start.py [--repeat 2] [--no-write]``.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

JSON = C.OUT / "cold_start.json"
README = C.ROOT / "README.md"
#: largest accepted ratio of the cold run's wall time to the warm runs' median
TARGET = 2.5


def _femrub_paper(out: Path, cache: Path) -> dict:
    """Wall, CPU (user + system) seconds and peak memory (MiB) of ``femrub paper``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    cmd = [sys.executable, "-m", "femrub.app.cli", "paper", "--out", str(out), "-q"]
    subprocess.run(cmd, env=env, check=True, cwd=C.ROOT)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "peak_mib": after.ru_maxrss / 1024.0}


def measure(repeat: int) -> dict:
    """The cold run, then ``repeat`` warm runs, each in a fresh output folder."""
    with tempfile.TemporaryDirectory(prefix="femrub-cold-") as tmp:
        tmp = Path(tmp)
        cold = _femrub_paper(tmp / "cold", tmp / "numba")
        warm = [_femrub_paper(tmp / f"warm{i}", tmp / "numba") for i in range(repeat)]
    median = statistics.median(w["wall_s"] for w in warm)
    return {
        "machine": C.machine(),
        "cold": cold,
        "warm": warm,
        "ratio": cold["wall_s"] / median,
        "target": TARGET,
    }


def table(doc: dict) -> str:
    """The README's lines: both runs and their ratio, stamped with the machine."""
    cold, warm = doc["cold"], doc["warm"]
    wall = statistics.median(w["wall_s"] for w in warm)
    cpu = statistics.median(w["cpu_s"] for w in warm)
    m = doc["machine"]
    return (
        f"`femrub paper`: first run on a fresh machine {cold['wall_s']:.1f} s wall "
        f"({cold['cpu_s']:.1f} s CPU, the contact kernels it needs compiled), later runs "
        f"{wall:.1f} s wall ({cpu:.1f} s CPU, median of {len(warm)}), ratio "
        f"{doc['ratio']:.2f} (target ≤ {doc['target']:g}); peak memory "
        f"{max(w['peak_mib'] for w in warm):.0f} MiB. Measured by `benchmarks/cold_start.py` "
        f"on {m['date']} (commit {m['commit']}, {m['cores']} cores, load "
        f"{m['load_average'][0]:.1f})."
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2, help="warm runs (default 2)")
    ap.add_argument("--no-write", action="store_true", help="print, write nothing")
    a = ap.parse_args(argv)
    doc = measure(max(1, a.repeat))
    text = table(doc)
    print(text)
    if not a.no_write:
        C.write_json(JSON, doc)
        C.write_between(README, "cold_start", text)
    return 0 if doc["ratio"] <= TARGET else 1


if __name__ == "__main__":
    raise SystemExit(main())
