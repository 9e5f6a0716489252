"""Command line: ``femrub paper --out DIR`` and friends.

Errors in the input are reported on one line (``femrub: error: ...``) with exit status 2;
an interrupted run keeps what it wrote and exits with status 130.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

__all__ = ["main", "build_parser"]


def _paper(args) -> int:
    from .paper import FIGURES, reproduce

    out = Path(args.out)
    figures = args.figures.split(",") if args.figures else None
    log = (lambda s: None) if args.quiet else print
    t0 = time.perf_counter()
    if not args.quiet:
        print(f"femrub paper: reproducing {', '.join(figures or FIGURES)} into {out}/")
    rows = reproduce(out, figures=figures, t_end=args.t_end, progress=not args.quiet, log=log)
    if not args.quiet:
        bad = [r for r in rows if r["status"] != "ok"]
        for r in bad:
            print(f"  note: {r['figure']} / {r['label']}: {r['status']} ({r['message']})")
        print(f"done in {time.perf_counter() - t0:.1f} s: {out / 'summary.json'}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="femrub", description="Nonsmooth thermomechanical blade-casing rub (SI units)."
    )
    p.add_argument("--version", action="store_true", help="print the version and exit")
    sub = p.add_subparsers(dest="command")
    pp = sub.add_parser("paper", help="reproduce the paper's figures on the 1D bar")
    pp.add_argument("--out", "-o", default="paper-out", help="output folder (default paper-out)")
    pp.add_argument("--figures", help="comma-separated subset, e.g. fig2,fig6")
    pp.add_argument("--t-end", type=float, default=0.4, help="end time in s (default 0.4)")
    pp.add_argument("--quiet", "-q", action="store_true", help="no progress output")
    pp.set_defaults(func=_paper)
    try:
        from .geometry.cli import add_mesh_parser, run_mesh
    except ImportError:  # geometry extras not installed
        pass
    else:
        mp = add_mesh_parser(sub)
        mp.set_defaults(func=run_mesh)
    return p


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.version:
        from . import __version__

        print(f"femrub {__version__}")
        return 0
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print("femrub: interrupted; files written so far are kept", file=sys.stderr)
        return 130
    except (ValueError, FileNotFoundError, KeyError) as exc:
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        print(f"femrub: error: {msg}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
