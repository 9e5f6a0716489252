"""Generate the default example blade meshes of femrub.

Usage::

    python meshes/make_meshes.py                 # box_blade.msh, naca_blade.msh here
    python meshes/make_meshes.py --rotor37       # also Rotor 37 meshes into out/meshes/

The Rotor 37 meshes are derived from the read-only reference data (see
``../shared/data/README.md`` for their licences) and are written outside this
folder on purpose; they are skipped with a message when the data are absent.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from femrub.geometry import (
    GeometryError,
    box_blade,
    naca_blade,
    read_rotor37_mesh,
    rotor37_sections_blade,
    shared_data_dir,
)

HERE = Path(__file__).resolve().parent


def _report(name: str, blade, start: float, path: Path) -> None:
    seconds, size_kb = time.perf_counter() - start, path.stat().st_size / 1024
    print(f"{name}: {blade.n_tets} tets, {blade.n_vertices} vertices, {seconds:.2f} s,", end=" ")
    print(f"{path} ({size_kb:.0f} KB)")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=HERE, help="folder of the example meshes (default: meshes/)"
    )
    parser.add_argument(
        "--rotor37", action="store_true", help="also mesh the Rotor 37 reference data"
    )
    parser.add_argument("--rotor37-out", type=Path, default=HERE.parent / "out" / "meshes")
    args = parser.parse_args(argv)

    examples = {
        "box_blade.msh": lambda: box_blade(
            span=0.1, chord=0.03, thickness=0.003, h=0.003, n_contact=10
        ),
        "naca_blade.msh": lambda: naca_blade(
            "2412", span=0.1, root_chord=0.05, tip_chord=0.035, twist=20.0
        ),
    }
    for name, build in examples.items():
        start = time.perf_counter()
        blade = build()
        _report(name, blade, start, blade.save(args.out / name, binary=True))

    if args.rotor37:
        data = shared_data_dir()
        for name, build in (
            ("rotor37_sections.msh", rotor37_sections_blade),
            ("rotor37_fe.vtu", read_rotor37_mesh),
        ):
            start = time.perf_counter()
            try:
                blade = build(data)
            except GeometryError as exc:
                print(f"{name}: skipped ({exc})")
                continue
            _report(name, blade, start, blade.save(args.rotor37_out / name))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
