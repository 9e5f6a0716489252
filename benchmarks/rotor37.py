"""The published Rotor 37 rub (built-in scenes ``rotor37`` and ``rotor37-thermal``).

Runs ``femrub run SCENE -o DIR`` (unless ``--reuse`` finds a finished folder), then reads
``summary.json`` and ``history.npz`` and writes ``DIR/rotor37_results.json`` and
``DIR/rotor37_results.md``: status, revolutions, run times, the radial displacement of
every contact node (RMS and max |.| over the first and last 5 revolutions), the largest
normal and friction force per node, the friction work and heat, and the Coulomb check of
every step (|λ_t| <= μ λ to 1e-8, equality and direction where a contact slips). These are
the numbers of ``docs/rotor37.md``.

Run: ``python benchmarks/rotor37.py [--scene rotor37] [--out DIR] [--reuse]``. ``--docs``
also keeps the numbers, stamped with the date, commit and machine, in
``docs/rotor37/results-SCENE.json`` and renders the results section of ``docs/rotor37.md``
from every such file; ``--render-only`` renders that section from the committed files (no
run). A run needs the Rotor 37 deck of the shared data (``FEMRUB_SHARED_DATA``).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
from _common import stamp

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "rotor37.md"
DATA_DIR = ROOT / "docs" / "rotor37"
SCENES = ("rotor37", "rotor37-thermal")
MARKER = "rotor37-results"


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
            "reduction_error",
            "time_step_error",
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


def _estimate(doc) -> str:
    if not isinstance(doc, dict) or doc.get("estimate") is None:
        return "—"
    return f"{100 * doc['estimate']:.2g} % ({doc.get('status', 'judged')})"


def _coulomb(check) -> str:
    if not isinstance(check, dict):
        return "—"
    return ", ".join(f"{k} {v:.2g}" for k, v in check.items() if isinstance(v, float))


def summary_table(row: dict) -> str:
    """The run's verdict and balances, from its ``summary.json``."""
    timings = row.get("timings") or {}
    times = ", ".join(f"{k} {v:.1f} s" for k, v in timings.items() if isinstance(v, float))
    cpu = row.get("cpu_per_step_us")
    forces = f"{row['max_contact_force']:.4g} / {row['max_friction_force'] or 0:.4g}"
    rows = [
        ("status", f"**{row['status']}**, {row['revolutions']:.1f} revolutions"),
        ("steps", str(row["steps"])),
        ("reduced / full state dofs", f"{row.get('n_dofs')} / {row.get('n_full')}"),
        ("reduction error estimate", _estimate(row.get("reduction_error"))),
        ("time-step error estimate", _estimate(row.get("time_step_error"))),
        ("energy balance (`energy_error`)", f"{row['energy_error']:.2g}"),
        ("largest normal / friction force (N)", forces),
        ("friction work (J)", f"{row['friction_work'] or 0:.4g}"),
        ("Coulomb check (`coulomb_check`)", _coulomb(row.get("coulomb_check"))),
        ("CPU per step (µs)", f"{cpu:.3g}" if cpu else "—"),
        ("times", times or "—"),
    ]
    return "\n".join(["| | |", "|---|---|", *(f"| {k} | {v} |" for k, v in rows)])


def render(data: dict[str, dict]) -> str:
    """The results section of ``docs/rotor37.md`` from ``{scene: results document}``."""
    if not data:
        return (
            "Not measured on this version: `python benchmarks/rotor37.py --docs` (and "
            "`--scene rotor37-thermal --docs`) runs the scenes and renders their numbers here."
        )
    parts = []
    for scene, doc in data.items():
        row = doc["results"]
        parts += [
            f"### `femrub run {scene}`",
            stamp("python benchmarks/rotor37.py --docs", doc.get("machine")),
            summary_table(row),
            "Radial (normal) displacement of each contact node (negative: pushed inwards by "
            "the casing), largest normal and friction force per node and fraction of the "
            "steps in contact:",
            table(row),
        ]
    return "\n\n".join(parts)


def committed() -> dict[str, dict]:
    """The results documents in ``docs/rotor37/``, in the order of :data:`SCENES`."""
    found = {}
    for scene in SCENES:
        path = DATA_DIR / f"results-{scene}.json"
        if path.exists():
            found[scene] = json.loads(path.read_text())
    return found


def render_page() -> Path:
    from _common import write_between

    write_between(PAGE, MARKER, render(committed()))
    return PAGE


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="rotor37", choices=SCENES)
    ap.add_argument("--out", default=None)
    ap.add_argument("--reuse", action="store_true", help="post-process a finished folder")
    ap.add_argument("--docs", action="store_true", help="keep the numbers and render the page")
    ap.add_argument("--render-only", action="store_true", help="render the page, no run")
    a = ap.parse_args(argv)
    if a.render_only:
        print(f"wrote {render_page()}")
        return 0
    from femrub.geometry.rotor37 import shared_data_dir

    if not (shared_data_dir() / "rotor37-fe-mesh").is_dir():
        print(f"skipped: no Rotor 37 mesh under {shared_data_dir()} (set FEMRUB_SHARED_DATA)")
        return 0
    from _common import machine

    stamp = machine()
    out = Path(a.out or f"out/bench-{a.scene}")
    if not (a.reuse and (out / "history.npz").exists()):
        cmd = [sys.executable, "-m", "femrub", "run", a.scene, "-o", str(out), "--overwrite"]
        subprocess.run(cmd, check=False)
    row = metrics(out)
    (out / "rotor37_results.json").write_text(json.dumps(row, indent=2, default=str))
    (out / "rotor37_results.md").write_text(table(row) + "\n")
    print(json.dumps({k: row[k] for k in ("status", "revolutions", "coulomb_check")}, indent=1))
    print(table(row))
    if a.docs:
        doc = {"scene": a.scene, "machine": stamp, "results": row}
        path = DATA_DIR / f"results-{a.scene}.json"
        path.write_text(json.dumps(doc, indent=1, default=str))
        print(f"wrote {path} and {render_page()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
