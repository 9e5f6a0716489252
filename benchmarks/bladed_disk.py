"""The built-in ``bladed-disk`` scene: its cost, and its sweep against the coincidence rule.

One command, three measurements, each through the CLI a user runs:

1. ``femrub modes bladed-disk``: the disk's and the ring's modes per nodal diameter
   (``modes.csv``); the coincidence speed of the casing's lobe order ``k``,
   ``Ω_c = (ω_disk,k + ω_casing,k)/k`` of the first families, computed here from
   ``modes.csv``.
2. ``femrub run bladed-disk`` (20 revolutions, checks on): the build (assembly and the
   bases: targets ≤ 2 min) and the whole run's wall time (≤ 5 min), from ``summary.json``
   and the wall clock; its status and check estimates.
3. ``femrub sweep bladed-disk --param loads.rotation_speed=START:STOP:STEP``: the
   ``rms_tip_displacement_m`` per speed of ``interaction.csv``; the speed of the largest
   response against ``Ω_c`` (target: within 3 %), every point's status.

Writes the section between the ``bladed_disk`` markers of
``docs/performance/bladed-disk.md`` (``--no-write``: print it). Run alone:
``flock /tmp/femrub-heavy.lock python benchmarks/bladed_disk.py`` (about 20 minutes on the
2-core machine with the default sweep of 21 speeds on two processes: `--workers 2`).
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import _common as C  # noqa: E402

STORE = ROOT / "docs" / "performance" / "bladed_disk.json"
PAGE = ROOT / "docs" / "performance" / "bladed-disk.md"
SCENE = "bladed-disk"
INTRO = """# The built-in bladed disk: cost and coincidence

What the built-in `bladed-disk` scene (12 blades, a thin 5-lobed casing ring; the scene's
file says why each value) costs on the 2-core machine, and where its speed sweep's largest
response lies against the coincidence rule of [Bladed disk and casing
modes](../bladed-disk.md) (`python benchmarks/bladed_disk.py`). `Ω_c` is computed from the
`modes.csv` that `femrub modes bladed-disk` writes; the sweep is `femrub sweep` of the scene
over the listed speeds, its measure the `rms_tip_displacement_m` of `interaction.csv` (the
tips' normal displacement over the run, every blade). A point's status is the run's own
(`inaccurate` when its reduction or time-step estimate is above its tolerance).
"""


def femrub(*args) -> float:
    """Run ``femrub ARGS`` in a child process; its wall time (s)."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "femrub.app.cli", *args], check=True)
    return time.perf_counter() - t0


def coincidence(modes_csv: Path, k: int) -> dict:
    """``Ω_c = (ω_disk,k + ω_casing,k)/k`` (rad/s) of the first families in ``modes_csv``."""
    first = {}
    with open(modes_csv, newline="") as f:
        for row in csv.DictReader(f):
            if int(row["nodal_diameter"]) == k and int(row["family"]) == 1:
                first[row["structure"]] = float(row["frequency_hz"])
    disk, casing = first["disk"], first["casing"]
    omega = 2.0 * 3.141592653589793 * (disk + casing) / k
    return {"disk_hz": disk, "casing_hz": casing, "omega_c": omega}


def sweep_rows(folder: Path) -> list[dict]:
    """``interaction.csv`` of a sweep with each point's status (its ``summary.json``)."""
    with open(folder / "interaction.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    out = []
    for row in rows:
        speed = float(row["loads.rotation_speed"])
        out.append(
            {
                "speed": speed,
                "rms": float(row["rms_tip_displacement_m"]),
                "status": row.get("status", "?"),
            }
        )
    return sorted(out, key=lambda r: r["speed"])


def run_entry(folder: Path, wall: float) -> dict:
    s = json.loads((folder / "summary.json").read_text())
    t = s["timings"]
    bases = s["inputs"]["build"]["reduction"]["seconds"]["bases"]  # without the estimate's runs
    return {
        "wall": wall,
        "build": t.get("assembly", 0.0) + bases,
        "stepping": t.get("stepping"),
        "status": s["status"],
        "reduction": s["reduction_error"]["estimate"],
        "time_step": s["time_step_error"]["estimate"],
        "coordinates": s["n_dofs"],
        "steps": s["steps"],
    }


def section(k: int, c: dict, run: dict, rows: list[dict], speeds: str) -> str:
    peak = max(rows, key=lambda r: r["rms"])
    off = peak["speed"] / c["omega_c"] - 1.0
    lines = [
        "## Cost and the sweep's largest response",
        "",
        f"Coincidence of the ring's lobe order k = {k}: disk {c['disk_hz']:.1f} Hz, casing "
        f"{c['casing_hz']:.1f} Hz, Ω_c = {c['omega_c']:.1f} rad/s.",
        "",
        f"`femrub run {SCENE}`: {run['wall']:.1f} s wall (target ≤ 300 s), of which the build "
        f"(assembly and bases) {run['build']:.1f} s (target ≤ 120 s) and the scene's run "
        f"{C.fmt(run['stepping'])} s; {run['coordinates']} coordinates, {run['steps']} steps; "
        f"status `{run['status']}` (reduction estimate {run['reduction']:.3g}, time-step "
        f"estimate {run['time_step']:.3g}).",
        "",
        f"`femrub sweep {SCENE} --param loads.rotation_speed={speeds}`: the largest response "
        f"at {peak['speed']:.1f} rad/s, {100 * off:+.2f} % from Ω_c (target: within 3 %; "
        f"status there `{peak['status']}`).",
        "",
        "| Ω (rad/s) | Ω/Ω_c | rms tip displacement (m) | status |",
        "|---|---|---|---|",
    ]
    for r in rows:
        mark = " (largest)" if r is peak else ""
        lines.append(
            f"| {r['speed']:.1f}{mark} | {r['speed'] / c['omega_c']:.4f} | {C.fmt(r['rms'])} "
            f"| {r['status']} |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", default="1800:2000:10", help="sweep START:STOP:STEP (rad/s)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--render-only", action="store_true", help="render the page from the JSON")
    args = ap.parse_args(argv)
    if args.render_only:
        C.store_section(STORE, PAGE, "bladed_disk", "cost", C.read_json(STORE)["cost"])
        return 0
    from femrub.scene import load_scene

    k = int(load_scene(SCENE)["casing.ring.lobes"])
    machine = C.machine()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        femrub("modes", SCENE, "-o", str(tmp / "modes"), "-q")
        c = coincidence(tmp / "modes" / "modes.csv", k)
        wall = femrub("run", SCENE, "-o", str(tmp / "run"), "-q")
        run = run_entry(tmp / "run", wall)
        femrub(
            "sweep",
            SCENE,
            "--param",
            f"loads.rotation_speed={args.speeds}",
            "--workers",
            str(args.workers),
            "--no-cache",
            "-o",
            str(tmp / "sweep"),
            "-q",
        )
        rows = sweep_rows(tmp / "sweep")
    text = section(k, c, run, rows, args.speeds)
    if args.no_write:
        print(text)
        return 0
    if not PAGE.exists():
        PAGE.write_text(INTRO)
    entry = {"command": C.command_line("bladed_disk.py", argv), "machine": machine, "text": text}
    C.store_section(STORE, PAGE, "bladed_disk", "cost", entry)
    print(f"wrote {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
