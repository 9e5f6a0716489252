"""Rotor 37 Campbell diagram, 0-1800 rad/s (minutes and ~5 GB): writes docs/campbell.md.

``python benchmarks/campbell_rotor37.py [linear] [nonlinear]`` runs ``femrub campbell`` on the
CalculiX Rotor 37 mesh with the deck's material (E = 210 GPa, ν = 0.3, ρ = 9000 kg/m³) and a
consistent mass, for each prestress method, and tabulates the rest frequencies against the
published C3D15 values, the tip growth at 1800 rad/s, the interpolation check and the run
time into ``docs/campbell.md`` (figures in ``docs/performance/``). Needs ../shared/data.
"""

from __future__ import annotations

import sys
import time

from _common import DOCS, OUT, fmt, machine

PUBLISHED_HZ = (312.12, 922.81, 1165.62)
DECK = {
    "material.young": 210e9,
    "material.poisson": 0.3,
    "material.density": 9000.0,
    "physics.lumping": "consistent",
}


def main(methods) -> None:
    from femrub.app.campbell import campbell, parse_speeds, write_campbell
    from femrub.geometry.rotor37 import shared_data_dir
    from femrub.scene import load_scene

    if not (shared_data_dir() / "rotor37-fe-mesh").is_dir():
        print(f"skipped: no Rotor 37 mesh under {shared_data_dir()}")
        return
    lines = ["# Rotor 37 Campbell diagram", "", f"Machine: {machine()}", ""]
    head = "| method | f1 / f2 / f3 at rest (Hz) | vs published | tip growth at 1800 rad/s "
    lines += [
        head + "(max, mean) | self-check (samples; worst check) | run time |",
        "|---|---|---|---|---|---|",
    ]
    for method in methods:
        scene = load_scene("rotor37", {**DECK, "loads.centrifugal": method})
        t0 = time.perf_counter()
        res = campbell(scene, parse_speeds("0:1800:10"), modes=6, samples=2)
        doc = write_campbell(res, OUT / f"campbell-rotor37-{method}")
        wall = time.perf_counter() - t0
        rest = doc["rest_frequencies_hz"][:3]
        dev = ", ".join(f"{100 * (f / p - 1):+.2f} %" for f, p in zip(rest, PUBLISHED_HZ))
        lines.append(
            f"| {method} | {' / '.join(fmt(f, 5) for f in rest)} | {dev} | "
            f"{doc['tip_growth_max_m'][-1] * 1e3:.3f} mm, "
            f"{doc['tip_growth_mean_m'][-1] * 1e3:.3f} mm"
            f" | **{doc['status']}** ({len(doc['sample_speeds'])} samples; "
            f"{100 * doc['check_max_relative_error']:.2g} % at {doc['check_speed']:.0f} rad/s) "
            f"| {wall:.0f} s |"
        )
        lines.append("")
        lines.append(f"![{method}](performance/campbell-rotor37-{method}/{doc['files'][1]})")
        lines.append("")
    (DOCS / "campbell.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:] or ["linear", "nonlinear"])
