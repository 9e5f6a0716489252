"""``mesh`` sub-command: build or read a blade mesh and write it to ``.msh``/``.vtu``.

Wire into a main parser with::

    sub = parser.add_subparsers(dest="command")
    add_mesh_parser(sub)          # sets func=run_mesh
    args = parser.parse_args(); return args.func(args)

Stand-alone: ``python -m femrub.geometry.cli box -o box.msh``.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

from .errors import GeometryError

__all__ = ["add_mesh_parser", "main", "run_mesh"]

_DESCRIPTION = (
    "Build or read a blade mesh (linear tetrahedra, metres) and write it to .msh or .vtu."
)


def _common(p: argparse.ArgumentParser, sizes: bool = True) -> None:
    p.add_argument("-o", "--output", help="write the mesh to OUT.msh or OUT.vtu")
    p.add_argument("-v", "--verbose", action="store_true", help="show gmsh messages")
    if sizes:
        p.add_argument("--h", type=float, help="target element size [m]")
        p.add_argument(
            "--h-min", type=float, help="lower bound of the element size [m] (default h/4)"
        )
        p.add_argument(
            "--n-contact", type=int, default=None, help="number of contact nodes on the tip"
        )
        p.add_argument(
            "--contact-margin",
            type=float,
            default=None,
            help="chord fraction kept free of contact nodes at each edge (default 0.05)",
        )


def _fill(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    kinds = parser.add_subparsers(dest="mesh_kind", metavar="{box,naca,sections,read}")
    kinds.required = True
    box = kinds.add_parser("box", help="straight rectangular blade")
    box.add_argument("--span", type=float, default=0.1, help="span [m] (default 0.1)")
    box.add_argument("--chord", type=float, default=0.03, help="chord [m] (default 0.03)")
    box.add_argument("--thickness", type=float, default=0.003, help="thickness [m] (default 0.003)")
    box.add_argument(
        "--hub-radius", type=float, default=0.0, help="radius of the root face [m] (default 0)"
    )
    _common(box)
    naca = kinds.add_parser("naca", help="twisted, tapered NACA 4-digit blade")
    naca.add_argument("--code", default="0012", help="NACA 4-digit code (default 0012)")
    naca.add_argument("--span", type=float, default=0.1, help="span [m] (default 0.1)")
    naca.add_argument(
        "--root-chord", type=float, default=0.05, help="root chord [m] (default 0.05)"
    )
    naca.add_argument(
        "--tip-chord", type=float, default=0.035, help="tip chord [m] (default 0.035)"
    )
    naca.add_argument("--twist", type=float, default=20.0, help="tip twist [deg] (default 20)")
    naca.add_argument("--n-sections", type=int, default=5, help="lofted sections (default 5)")
    naca.add_argument(
        "--hub-radius",
        type=float,
        default=0.0,
        help="radius of the root section from the machine axis (x) [m] (default 0)",
    )
    naca.add_argument(
        "--stacking",
        type=float,
        default=0.25,
        help="chord fraction of the twist axis (default 0.25)",
    )
    naca.add_argument(
        "--n-points", type=int, default=40, help="points per section side (default 40)"
    )
    _common(naca)
    sec = kinds.add_parser("sections", help="blade lofted through section files (x,y,z rows)")
    sec.add_argument("files", nargs="+", help="section files hub to tip, or one folder")
    sec.add_argument(
        "--pattern", default="*.csv", help="glob pattern inside a folder (default *.csv)"
    )
    sec.add_argument(
        "--unit", default="cm", help="coordinate unit of the files: m, cm, mm (default cm)"
    )
    sec.add_argument("--axis", default="x", help="rotation axis x, y or z (default x)")
    _common(sec)
    read = kinds.add_parser("read", help="read a gmsh .msh, Abaqus/CalculiX .inp or .vtu mesh")
    read.add_argument("path", help="mesh file")
    read.add_argument("--unit", default=None, help="coordinate unit: m, cm, mm (required for .inp)")
    read.add_argument("--axis", default=None, help="rotation axis x, y or z (default: stored or z)")
    read.add_argument("--root", default=None, help="node set / group of the clamped face")
    read.add_argument(
        "--tip", default=None, help="node set / group of the tip face (default: detect)"
    )
    read.add_argument(
        "--contact", default=None, help="contact NSET name or comma-separated node ids"
    )
    _common(read, sizes=False)
    parser.set_defaults(func=run_mesh)
    return parser


def add_mesh_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``mesh`` sub-command to an ``argparse`` sub-parsers object.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        Result of ``parser.add_subparsers()``.

    Returns
    -------
    argparse.ArgumentParser
        The ``mesh`` parser (its default ``func`` is :func:`run_mesh`).
    """
    parser = subparsers.add_parser(
        "mesh", help="build or read a blade mesh", description=_DESCRIPTION
    )
    return _fill(parser)


def _sizes(args) -> dict:
    out = {"h": args.h, "h_min": args.h_min}
    for key in ("n_contact", "contact_margin"):
        if getattr(args, key, None) is not None:
            out[key] = getattr(args, key)
    return out


def _read_kwargs(args) -> dict:
    from .readers import detect_format

    fmt = detect_format(args.path)
    kw = {}
    if args.axis is not None:
        kw["radial_axis"] = args.axis
    if args.root is not None:
        kw["root"] = args.root
    if fmt == "abaqus":
        kw["tip"] = args.tip
        if args.contact:
            parts = [s.strip() for s in args.contact.split(",") if s.strip()]
            kw["contact"] = (
                [int(s) for s in parts] if all(s.isdigit() for s in parts) else args.contact
            )
    elif args.tip is not None:
        kw["tip"] = None if args.tip.lower() == "detect" else args.tip
    return kw


#: largest number of tetrahedra ``femrub mesh`` makes (as the scene path: MAX_ELEMENTS)
MAX_TETS = 2_000_000
# tetrahedra per h³ of volume in a gmsh mesh of size h (regular tetrahedra: 6 √2)
_TETS_PER_H3 = 8.5


def estimate_tets(args) -> float | None:
    """Tetrahedra a box or NACA blade of size ``--h`` gets (``None``: cannot estimate)."""
    h = getattr(args, "h", None)
    if args.mesh_kind == "box":
        dims = (args.span, args.chord, args.thickness)
        if min(dims) <= 0:
            return None  # the builder names the length at fault
        h = h or args.thickness
        t = min(args.thickness, h)  # at least one element through the thickness
        return _TETS_PER_H3 * (args.span / h) * (args.chord / h) * (args.thickness / t)
    code = str(getattr(args, "code", ""))
    if args.mesh_kind == "naca" and h and len(code) == 4 and code.isdigit():
        ratio = int(code[2:]) / 100.0
        if min(ratio, args.span, args.root_chord, args.tip_chord) <= 0:
            return None
        t = min(ratio * args.root_chord, h)
        area = 0.685 * ratio * 0.5 * (args.root_chord**2 + args.tip_chord**2)
        return _TETS_PER_H3 * (args.span / h) * (area / h) / t
    return None


def _check_size(args) -> None:
    """Refuse, before meshing, a size ``--h`` that gives more than :data:`MAX_TETS`."""
    h = getattr(args, "h", None)
    if h is not None and not h > 0:
        raise GeometryError(f"--h {h!r}: give a positive element size in metres")
    n = estimate_tets(args)
    if n is not None and n > MAX_TETS:
        what = f"--h {h}" if h else f"--thickness {args.thickness} (the default --h)"
        raise GeometryError(
            f"{what}: gives about {min(n, 1e300):.2g} tetrahedra (at most {MAX_TETS:.0e}, "
            "estimated before meshing); raise --h"
        )


def run_mesh(args: argparse.Namespace) -> int:
    """Execute the ``mesh`` sub-command; print a summary; return an exit code.

    Returns
    -------
    int
        0 on success, 2 on a :class:`GeometryError` (message printed to stderr).
    """
    from . import box_blade, naca_blade, read_mesh, sections_blade

    start = time.perf_counter()
    try:
        _check_size(args)
        if args.mesh_kind == "box":
            blade = box_blade(
                args.span,
                args.chord,
                args.thickness,
                hub_radius=args.hub_radius,
                verbose=args.verbose,
                **_sizes(args),
            )
        elif args.mesh_kind == "naca":
            blade = naca_blade(
                args.code,
                args.span,
                args.root_chord,
                args.tip_chord,
                args.twist,
                args.n_sections,
                hub_radius=args.hub_radius,
                stacking=args.stacking,
                n_points=args.n_points,
                verbose=args.verbose,
                **_sizes(args),
            )
        elif args.mesh_kind == "sections":
            paths = args.files[0] if len(args.files) == 1 else args.files
            blade = sections_blade(
                paths,
                length_unit=args.unit,
                pattern=args.pattern,
                radial_axis=args.axis,
                verbose=args.verbose,
                **_sizes(args),
            )
        else:
            blade = read_mesh(args.path, args.unit, **_read_kwargs(args))
        print(f"{blade.summary()} [{time.perf_counter() - start:.2f} s]")
        if args.output:
            print(f"wrote {blade.save(args.output)}")
    except GeometryError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Stand-alone entry point equivalent to ``femrub mesh ...``."""
    parser = _fill(argparse.ArgumentParser(prog="femrub mesh", description=_DESCRIPTION))
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())
