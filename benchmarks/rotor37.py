"""The published Rotor 37 rub (built-in scenes ``rotor37`` and ``rotor37-thermal``).

Runs ``femrub run SCENE -o DIR`` (unless ``--reuse`` finds a finished folder), then reads
``summary.json`` and ``history.npz`` and writes ``DIR/rotor37_results.json`` and
``DIR/rotor37_results.md``: status, revolutions, run times, the radial displacement of
every contact node (RMS and max |.| over the first and last 5 revolutions), the largest
normal and friction force per node, the friction work and heat, and the Coulomb check of
every step (|λ_t| <= μ λ to 1e-8, equality and direction where a contact slips). These are
the numbers of ``docs/rotor37.md``.

Run: ``python benchmarks/rotor37.py [--scene rotor37] [--out DIR] [--reuse]``.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np


def metrics(out: Path, window: float = 5.0) -> dict:
    s = json.loads((out / "summary.json").read_text())
    omega = s["inputs"]["scene"]["loads"]["rotation_speed"]
    with np.load(out / "history.npz") as d:
        t, lam, ff = d["t"], d["normal_force"], d["friction_force"]
        u = d["signal_contact_displacement"]
        state = d["contact_state"]
    rev = t * omega / (2 * math.pi)
    first, last = rev <= rev[0] + window, rev >= rev[-1] - window
    row = {
        k: s.get(k)
        for k in (
            "status",
            "message",
            "revolutions",
            "steps",
            "n_dofs",
            "n_full",
            "timings",
            "cpu_per_step_us",
            "energy_error",
            "max_contact_force",
            "max_friction_force",
            "friction_work",
            "heat_to_blade",
            "heat_to_casing",
            "coulomb_check",
        )
    }
    row["rms_um_first"] = (1e6 * np.sqrt(np.mean(u[first] ** 2, axis=0))).tolist()
    row["rms_um_last"] = (1e6 * np.sqrt(np.mean(u[last] ** 2, axis=0))).tolist()
    row["max_um_first"] = (1e6 * np.abs(u[first]).max(axis=0)).tolist()
    row["max_um_last"] = (1e6 * np.abs(u[last]).max(axis=0)).tolist()
    row["max_normal_force"] = lam.max(axis=0).tolist()
    row["max_friction_force_per_node"] = np.linalg.norm(ff, axis=-1).max(axis=0).tolist()
    row["contact_fraction"] = (lam > 0).mean(axis=0).tolist()
    row["stick_fraction"] = float(np.mean(state == 1))
    return row


def table(row: dict) -> str:
    lines = [
        "| node | RMS first 5 rev (µm) | max first 5 (µm) | RMS last 5 (µm) | max last 5 (µm) "
        "| max normal force (N) | max friction force (N) | time in contact |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for i in range(len(row["max_normal_force"])):
        lines.append(
            f"| {i} | {row['rms_um_first'][i]:.1f} | {row['max_um_first'][i]:.1f} | "
            f"{row['rms_um_last'][i]:.1f} | {row['max_um_last'][i]:.1f} | "
            f"{row['max_normal_force'][i]:.1f} | {row['max_friction_force_per_node'][i]:.1f} | "
            f"{100 * row['contact_fraction'][i]:.2f} % |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="rotor37")
    ap.add_argument("--out", default=None)
    ap.add_argument("--reuse", action="store_true", help="post-process a finished folder")
    a = ap.parse_args(argv)
    out = Path(a.out or f"out/bench-{a.scene}")
    if not (a.reuse and (out / "history.npz").exists()):
        cmd = [sys.executable, "-m", "femrub", "run", a.scene, "-o", str(out), "--overwrite"]
        subprocess.run(cmd, check=False)
    row = metrics(out)
    (out / "rotor37_results.json").write_text(json.dumps(row, indent=2, default=str))
    (out / "rotor37_results.md").write_text(table(row) + "\n")
    print(json.dumps({k: row[k] for k in ("status", "revolutions", "coulomb_check")}, indent=1))
    print(table(row))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
