"""Rotor 37 mesh file -> reduced thermo-mechanical model (target: ≤ 60 s, ≤ 3 GB), one command.

Builds a scene (default ``rotor37``) in a fresh process without the model cache, up to its
first step, and records wall and CPU time, peak resident memory (``VmHWM``), every logged
phase with its time and the 1-minute load; the reduction error estimate is timed on its own
(its value and verdict too), so the path is reported with and without it, and so is the
estimate's run of the chosen sizes, which is the scene's run (``Simulation.ran``: it is not
stepped again), so the path is also reported without it. Writes the table between the
``mesh_to_rom`` markers of ``docs/performance/rotor37-costs.md`` (``--no-write``: print it).

The contact kernels are compiled once per machine (numba's on-disk cache); the table says
whether this run found them compiled (``kernels``: ``cached``) or compiled them (``compiled
in a background process``, overlapping the assembly: a first run on a fresh install);
``--cold-kernels`` measures the latter with an empty kernel cache (``NUMBA_CACHE_DIR``).

Run: ``python benchmarks/mesh_to_rom.py [--scene rotor37] [--no-write] [--cold-kernels]``
(Rotor 37-sized: ``flock /tmp/femrub-heavy.lock python benchmarks/mesh_to_rom.py``). Skips without
``../shared/data``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "performance" / "rotor37-costs.md"
BEGIN, END = "<!-- mesh_to_rom:begin -->", "<!-- mesh_to_rom:end -->"


def _peak_mib() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def child(scene_name: str) -> dict:
    """Build ``scene_name`` without cache up to its first step (in this process)."""
    from femrub.app.simulation import build
    from femrub.contact import jit
    from femrub.contact.theta_block import friction_block
    from femrub.scene import load_scene

    scene = load_scene(scene_name)
    cold = jit.compiled() and jit._cold(friction_block)
    lines: list[str] = []
    t0, c0, load0 = time.perf_counter(), time.process_time(), os.getloadavg()[0]

    def log(text: str) -> None:
        lines.append(f"[{time.perf_counter() - t0:6.1f} s, {_peak_mib():5.0f} MiB] {text}")

    sim = build(scene, log=log)
    next(iter(sim.stepper.iterate(scene["scheme"]["t_end"])))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    err = sim.report.get("reduction", {}).get("error", {})
    return {
        "scene": scene_name,
        "wall": wall,
        "cpu": cpu,
        "peak_mib": _peak_mib(),
        "load": [round(load0, 2), round(os.getloadavg()[0], 2)],
        "timings": sim.timings,
        "phases": sim.model.info.get("timings", {}),
        "n_dofs": sim.model.n_dofs,
        "estimate": err.get("estimate"),
        "estimate_seconds": err.get("seconds", 0.0),
        # the estimate's run of the chosen sizes, kept as the scene's run (Simulation.ran)
        "run_seconds": sim.ran[1] if sim.ran is not None else 0.0,
        "tolerance": err.get("tolerance"),
        "kernels": "compiled in a background process" if cold else "cached",
        "log": lines,
    }


def row(r: dict) -> str:
    est, run = r["estimate_seconds"], r.get("run_seconds", 0.0)
    ph = ", ".join(f"{k.replace('_', ' ')} {v:.1f}" for k, v in r["phases"].items())
    ok = r["estimate"] is not None and r["estimate"] <= r["tolerance"]
    verdict = "ok" if ok else "inaccurate"
    return (
        f"| `{r['scene']}` | {r['wall']:.1f} | {r['wall'] - est:.1f} | {r['cpu']:.1f} | "
        f"{r['peak_mib']:.0f} ({r['peak_mib'] * 1.048576 / 1000:.2f} GB) | "
        f"{r['timings'].get('assembly', 0):.1f} | {r['timings'].get('reduction', 0):.1f} "
        f"({ph}; estimate {est:.1f}, of which the run itself {run:.1f}, kept as the run; "
        f"wall without it {r['wall'] - run:.1f}) | "
        f"{100 * (r['estimate'] or 0):.2f} % ({verdict}) | "
        f"{r['n_dofs']} | {r.get('kernels', '?')} | {r['load'][0]}–{r['load'][1]} |"
    )


HEADER = (
    "| scene | wall (s) | wall without the estimate (s) | CPU (s) | peak MiB | assembly (s) "
    "| reduction (s) | estimate (verdict) | reduced dofs | kernels | load |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|"
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="rotor37")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--cold-kernels", action="store_true", help="empty kernel cache")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child:
        print(json.dumps(child(a.scene)))
        return 0
    if a.scene.startswith("rotor37") and not (ROOT.parent / "shared" / "data").is_dir():
        if not os.environ.get("FEMRUB_SHARED_DATA"):
            print("skipped: no ../shared/data (Rotor 37 mesh)")
            return 0
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = [sys.executable, __file__, "--child", "--scene", a.scene]
    with tempfile.TemporaryDirectory() as kernels:
        if a.cold_kernels:  # a first run on this machine: numba compiles the kernels
            env["NUMBA_CACHE_DIR"] = kernels
        p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    last = [x for x in p.stdout.splitlines() if x.startswith("{")]
    if p.returncode or not last:
        print(p.stderr[-2000:], file=sys.stderr)
        return 1
    r = json.loads(last[-1])
    print("\n".join(r["log"]))
    table = f"{HEADER}\n{row(r)}"
    print(table)
    if not a.no_write:
        text = DOC.read_text()
        i, j = text.index(BEGIN) + len(BEGIN), text.index(END)
        DOC.write_text(text[:i] + "\n" + table + "\n" + text[j:])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
