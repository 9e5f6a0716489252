"""Command line: ``femrub run | check | sweep | periodic | campbell | modes | scenes |
scene show | paper | mesh | cache``.

``run``, ``check`` and ``sweep`` keep the assembled and reduced models in a cache folder
(:mod:`femrub.app.cache`): ``--cache-dir`` or ``$FEMRUB_CACHE_DIR`` (default: the user's
cache folder), size limit ``$FEMRUB_CACHE_SIZE`` (default 8 GiB), ``--no-cache`` to build
everything; ``femrub cache info`` and ``femrub cache clear`` inspect and empty it.

Errors in the input or the output folder are reported on one line (``femrub: error: ...``)
with exit status 2, never as a traceback (set ``FEMRUB_DEBUG=1`` to see one); an
interrupted run (Ctrl-C or SIGTERM, any command) keeps what it wrote, says where, and exits
with status 130 (129 after SIGHUP); a run that fails, or a fault of the machine (a full
disk, a read error), keeps its partial results and exits with status 1 and one line naming
the file and the fix. The
default output folder is made from the scene name with anything but letters, digits and
``_.-`` replaced (it is always inside the working folder).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from ..heap import map_large_arrays

__all__ = ["main", "build_parser"]


def _paper(args) -> int:
    from ..cases.paper import FIGURES, reproduce

    out = Path(args.out)
    figures = args.figures.split(",") if args.figures else None
    log = (lambda s: None) if args.quiet else print
    t0 = time.perf_counter()
    if not args.quiet:
        print(f"femrub paper: reproducing {', '.join(figures or FIGURES)} into {out}/")
    try:
        rows = reproduce(
            out,
            figures=figures,
            t_end=args.t_end,
            progress=not args.quiet,
            log=log,
            overwrite=args.overwrite,
        )
    except KeyboardInterrupt:
        print(
            f"femrub: paper interrupted; the rows of the finished runs are kept in "
            f"{out / 'summary.json'} (status interrupted); rerun with --overwrite to start again",
            file=sys.stderr,
        )
        from ..output.interrupts import exit_status

        return exit_status()
    if not args.quiet:
        bad = [r for r in rows if r["status"] != "ok"]
        for r in bad:
            print(f"  note: {r['figure']} / {r['label']}: {r['status']} ({r['message']})")
        for r in rows:
            for w in r.get("warnings", []):
                print(f"  warning: {r['figure']} / {r['label']}: {w}")
        print(f"done in {time.perf_counter() - t0:.1f} s: {out / 'summary.json'}")
    return 0


def _changes(args) -> dict:
    from ..scene import SceneError, parse_value

    out = {}
    for item in args.set or []:
        if "=" not in item:
            raise SceneError(f"--set {item!r}: use KEY=VALUE, e.g. --set scheme.h=1e-5")
        key, value = item.split("=", 1)
        out[key.strip()] = parse_value(value.strip())
    return out


def _cache(args, log=None):
    """The model cache the command line asks for (``None`` with ``--no-cache``)."""
    from .cache import DEFAULT_LIMIT, ModelCache, parse_size

    if getattr(args, "no_cache", False):
        return None
    root = getattr(args, "cache_dir", None) or os.environ.get("FEMRUB_CACHE_DIR") or None
    size = os.environ.get("FEMRUB_CACHE_SIZE")
    return ModelCache(root, parse_size(size) if size else DEFAULT_LIMIT, log=log)


def _cache_command(args) -> int:
    cache = _cache(args, log=lambda text: print(f"femrub {text}"))
    if args.cache_command == "clear":
        n, freed = cache.clear()
        print(f"femrub cache: removed {n} entries ({freed / 1e6:.1f} MB) from {cache.root}")
        return 0
    info = cache.info()
    marked = "" if info["marked"] else " (no femrub entries: not a femrub cache folder)"
    print(f"cache folder  {info['root']}{marked}")
    print(
        f"entries       {info['entries']} ({info['bytes'] / 1e6:.1f} MB of "
        f"{info['limit'] / 1e6:.0f} MB)"
    )
    for stage, s in sorted(info["stages"].items()):
        print(f"  {stage:<12}{s['entries']} ({s['bytes'] / 1e6:.1f} MB)")
    print(f"code version  {info['code']}")
    return 0


def _load(args):
    from ..scene import load_scene
    from ..scene.run_checks import check_run

    scene = load_scene(args.scene, _changes(args))
    check_run(scene)
    return scene


def _log(args):
    return None if args.quiet else (lambda s: print(f"  {s}", flush=True))


def _run(args) -> int:
    from ..output.folder import safe_name
    from ..output.interrupts import exit_status
    from .run import run_scene

    scene = _load(args)
    out = Path(args.out or f"{safe_name(scene.name)}-out")
    if not args.quiet:
        print(f"femrub run: {scene.source} -> {out}/", flush=True)

    def on_built(built):
        if args.explain:
            print(built.explain(), flush=True)

    t0 = time.perf_counter()
    res, built = run_scene(
        scene,
        out,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=_log(args),
        on_built=on_built,
        cache=_cache(args, _log(args)),
        keep_build=False,
    )
    written = ["summary.json"]
    written += ["history.npz"] if scene["outputs.history_npz"] else []
    written += ["history.csv"] if scene["outputs.csv_stride"] else []
    where = f"{out}/ ({', '.join(written)})"
    if res.status == "interrupted":
        print(
            f"femrub: interrupted at t = {res.t[-1]:.6g} s after {res.steps} steps; partial "
            f"results kept in {where}; rerun the same command to start again",
            file=sys.stderr,
        )
        return exit_status()
    if res.status == "failed":
        print(
            f"femrub: run failed at t = {res.t[-1]:.6g} s: {res.message}; partial results "
            f"kept in {where}",
            file=sys.stderr,
        )
        return 1
    if not args.quiet:
        peak = max(
            (abs(res.signals[k]).max() for k in res.signals if "temperature" in k), default=0.0
        )
        force = res.force.max() if res.force.size else 0.0
        print(
            f"done in {time.perf_counter() - t0:.1f} s: status {res.status}, {res.steps} "
            f"steps, max force at one contact point {force:.4g} N, max temperature rise "
            f"at a contact point {peak:.4g} K"
        )
        if res.status != "ok":
            print(f"  note: {res.message}")
        for w in res.warnings:
            print(f"  warning: {w}")
        vtk = ""
        if built.fields is not None and scene["outputs.vtk_stride"]:
            series = built.fields.parts() if hasattr(built.fields, "parts") else ("rub",)
            vtk = " and " + ", ".join(f"vtk/{name}.pvd" for name in series) + " (ParaView)"
        plots = ", signals.png" if scene["outputs.plots"] else ""
        print(f"  results in {out}/: {', '.join(written)}{plots}{vtk}")
    if args.explain:
        from .explain import format_timings

        print(f"  {'timings':<10} {format_timings(res.info['timings'])}")
    return 0


def _check(args) -> int:
    from .simulation import build

    scene = _load(args)
    if args.schema_only:
        scene.check_files()
        if not args.quiet:
            print(f"ok: {scene.source} is a valid scene (model not built)")
        return 0
    built = build(scene, log=_log(args), cache=_cache(args, _log(args)))
    if args.explain:
        print(built.explain())
    if not args.quiet:
        r = built.report
        print(
            f"ok: {scene.source}: {r['model']['n_dofs']} dofs, {r['model']['n_contacts']} "
            f"contact(s), {r['scheme']['name']} h = {r['scheme']['h']:g} s, "
            f"{r['scheme']['steps']} steps"
        )
    return 0


def _scenes(args) -> int:
    from ..scene import builtin_scenes

    for name, desc in builtin_scenes().items():
        print(f"{name:<14} {desc}")
    return 0


def _scene_show(args) -> int:
    from ..scene import builtin_text

    sys.stdout.write(builtin_text(args.name))
    return 0


def _sweep(args) -> int:
    from ..output.folder import FINISHED
    from .sweep import parse_param, run_sweep

    scene = _load(args)
    if not args.param:
        raise ValueError("give at least one --param KEY=START:STOP:STEP")
    from ..output.folder import safe_name

    params = [parse_param(p) for p in args.param]
    out = Path(args.out or f"{safe_name(scene.name)}-sweep")
    t0 = time.perf_counter()
    rows = run_sweep(
        scene,
        params,
        out,
        scheduler=args.scheduler,
        workers=args.workers,
        overwrite=args.overwrite,
        progress=not args.quiet,
        log=None if args.quiet else print,
        cache=_cache(args),
    )
    failed = [r for r in rows if r.get("status") not in FINISHED]
    for r in failed:
        print(
            f"femrub: point {r['point']} ({r['folder']}): {r.get('status')}: "
            f"{r.get('message', '')}",
            file=sys.stderr,
        )
    if not args.quiet:
        print(
            f"done in {time.perf_counter() - t0:.1f} s: {len(rows)} points "
            f"({sum(r['skipped'] for r in rows)} skipped), {len(failed)} failed; "
            f"{out / 'interaction.png'}, {out / 'interaction.csv'}"
        )
    return 1 if failed else 0


def _periodic(args) -> int:
    from ..output.folder import claim, safe_name
    from ..periodic.continuation import check_model, continue_branch
    from ..periodic.output import write_branch
    from ..periodic.scene_family import parse_range, scene_family

    scene = _load(args)
    if scene["scheme"]["name"] != "theta":
        raise ValueError(
            f"scheme.name = {scene['scheme']['name']!r}: periodic orbits are found by "
            "shooting on the theta-method; use --set scheme.name=theta"
        )
    if scene["physics"]["thermal"] == "on":  # "auto" is refused once built (check_model)
        raise ValueError(
            "physics.thermal = 'on': periodic orbits are computed on mechanical models only; "
            "use --set physics.thermal=off"
        )
    key, start, stop = parse_range(args.param, scene)
    out = Path(args.out or f"{safe_name(scene.name)}-periodic")
    t0 = time.perf_counter()
    with claim(out, "periodic", overwrite=args.overwrite):
        family = scene_family(
            scene.with_changes({key: start}), key, log=_log(args), cache=_cache(args, _log(args))
        )
        check_model(family(start))
        s = scene["scheme"]
        branch = continue_branch(
            family,
            start,
            stop,
            h=s["h"],
            key=key,
            gamma=s["gamma"],
            activation=s.get("activation"),
            multiple=args.multiple,
            max_points=args.max_points,
            log=_log(args),
        )
        doc = write_branch(
            branch, out, model_of=family, extra={"wall_seconds": time.perf_counter() - t0}
        )
    if not args.quiet:
        print(
            f"done in {time.perf_counter() - t0:.1f} s: {doc['points']} points, "
            f"{len(doc['special'])} special; {out / 'branch.csv'}, {out / 'branch.png'}"
        )
    if doc["status"] != "ok":
        print(f"femrub: periodic {scene.name}: {doc['status']}: {doc['message']}", file=sys.stderr)
        return 1
    return 0


def _campbell(args) -> int:
    from .campbell import campbell, parse_speeds, write_campbell

    scene = _load(args)
    speeds = parse_speeds(args.speeds)
    out = Path(args.out or f"{scene.name}-campbell")
    t0 = time.perf_counter()
    res = campbell(
        scene,
        speeds,
        modes=args.modes,
        samples=args.samples,
        check=not args.no_check,
        log=_log(args),
        exact=args.exact,
        **{k: v for k, v in vars(args).items() if k in ("tolerance", "max_samples") and v},
    )
    doc = write_campbell(res, out)
    if doc["status"] == "failed":
        print(
            f"femrub: error: campbell {scene.name}: {doc['message']}; outputs marked failed "
            f"in {out}/ ({', '.join(doc['files'])}, campbell.json)",
            file=sys.stderr,
        )
        return 1
    if not args.quiet:
        rest = ", ".join(f"{f:.5g}" for f in doc["rest_frequencies_hz"])
        print(
            f"done in {time.perf_counter() - t0:.1f} s: {out / 'campbell.png'}, "
            f"{out / 'campbell.csv'}; at rest {rest} Hz"
        )
        print(f"  {doc['status']}: {doc['message']}")
    return 0


def _modes(args) -> int:
    from ..output.folder import safe_name
    from ..scene import load_scene
    from .modes import modes_speeds, modes_to_folder

    scene = load_scene(args.scene, _changes(args))  # no run checks: a bladed disk is welcome
    speeds = None if args.speeds is None else modes_speeds(args.speeds, scene)
    out = Path(args.out or f"{safe_name(scene.name)}-modes")
    t0 = time.perf_counter()
    log = _log(args)
    doc = modes_to_folder(scene, out, overwrite=args.overwrite, log=log, speeds=speeds)
    if not args.quiet:
        print(f"done in {time.perf_counter() - t0:.1f} s: {doc['message']}; {out / 'modes.csv'}")
    return 0


def _scene_args(p: argparse.ArgumentParser, out: bool = True) -> None:
    p.add_argument("scene", help="scene file (.toml) or built-in scene name (femrub scenes)")
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="change a key, e.g. --set scheme.h=1e-5 (repeatable)",
    )
    if out:
        p.add_argument("-o", "--out", help="results folder (default NAME-out)")
        p.add_argument("--overwrite", action="store_true", help="replace a finished result")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress output")
    _cache_args(p)


def _cache_args(p: argparse.ArgumentParser, switch: bool = True) -> None:
    p.add_argument(
        "--cache-dir",
        help="cache folder of built models (default $FEMRUB_CACHE_DIR, else "
        "the user's cache folder)",
    )
    if switch:
        p.add_argument("--no-cache", action="store_true", help="build every model anew")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="femrub", description="Nonsmooth thermomechanical blade-casing rub (SI units)."
    )
    p.add_argument("--version", action="store_true", help="print the version and exit")
    sub = p.add_subparsers(dest="command")
    rp = sub.add_parser("run", help="run a scene into a results folder")
    _scene_args(rp)
    rp.add_argument(
        "--explain",
        action="store_true",
        help="print what was built and why (dofs, dropped physics and contacts)",
    )
    rp.set_defaults(func=_run)
    cp = sub.add_parser("check", help="validate a scene and build its model, without running")
    _scene_args(cp, out=False)
    cp.add_argument("--explain", action="store_true", help="print what would be built and why")
    cp.add_argument("--schema-only", action="store_true", help="only check the file (instant)")
    cp.set_defaults(func=_check)
    sp = sub.add_parser("sweep", help="run a scene over a parameter grid (dask.distributed)")
    _scene_args(sp)
    sp.add_argument(
        "--param",
        action="append",
        metavar="KEY=SPEC",
        help="swept key: START:STOP:STEP (stop included) or A,B,C (repeatable)",
    )
    sp.add_argument(
        "--workers",
        type=int,
        default=2,
        help="processes running points on this machine, this one included (default 2; 0 or 1: "
        "the points one after the other here)",
    )
    sp.add_argument("--scheduler", help="address of a dask scheduler (default: LocalCluster)")
    sp.set_defaults(func=_sweep)
    pe = sub.add_parser("periodic", help="a branch of periodic orbits and their stability")
    _scene_args(pe)
    pe.add_argument(
        "--param",
        required=True,
        metavar="KEY=A:B",
        help="continued key and range, e.g. loads.rotation_speed=20000rpm:40000rpm",
    )
    pe.add_argument(
        "--multiple", type=int, default=1, help="orbit period in excitation periods (default 1)"
    )
    pe.add_argument("--max-points", type=int, default=400, help="most branch points (400)")
    pe.set_defaults(func=_periodic)
    cb = sub.add_parser("campbell", help="Campbell diagram of a scene's blade (PNG + CSV)")
    _scene_args(cb)
    cb.add_argument("--speeds", required=True, help="START:STOP:STEP (rad/s, stop included)")
    cb.add_argument("--modes", type=int, default=6, help="mode lines (default 6)")
    cb.add_argument(
        "--samples",
        type=int,
        default=3,
        help="first full modal samples, equally spaced in Ω² from rest to the top (default 3)",
    )
    cb.add_argument(
        "--no-check", action="store_true", help="skip the residual bounds of the frequencies"
    )
    cb.add_argument(
        "--exact",
        action="store_true",
        help="full prestress (warm-started) and eigen-solve at every speed, no reduced basis",
    )
    cb.add_argument(
        "--tolerance",
        type=float,
        help="largest relative frequency error bound accepted (default 0.005: 0.5 %%)",
    )
    cb.add_argument(
        "--max-samples",
        type=int,
        help="most full modal samples the self-check adds up to (default 12)",
    )
    cb.set_defaults(func=_campbell)
    mp = sub.add_parser(
        "modes", help="modes of a bladed disk and its casing ring by nodal diameter (CSV + PNG)"
    )
    mp.add_argument("scene", help="scene file (.toml) or built-in scene name (femrub scenes)")
    mp.add_argument("--set", action="append", metavar="KEY=VALUE", help="change a key (repeatable)")
    mp.add_argument("-o", "--out", help="results folder (default NAME-modes)")
    mp.add_argument(
        "--speeds",
        help="the disk's modes at these speeds, rad/s: START:STOP:STEP or A,B,C "
        "(adds campbell.png; coincidences solved between speeds)",
    )
    mp.add_argument("--overwrite", action="store_true", help="replace a finished result")
    mp.add_argument("--quiet", "-q", action="store_true", help="no progress output")
    mp.set_defaults(func=_modes)
    lp = sub.add_parser("scenes", help="list the built-in scenes")
    lp.set_defaults(func=_scenes)
    shp = sub.add_parser("scene", help="show a built-in scene")
    ssub = shp.add_subparsers(dest="scene_command", required=True)
    show = ssub.add_parser("show", help="print a built-in scene (copy it to edit)")
    show.add_argument("name")
    show.set_defaults(func=_scene_show)
    pp = sub.add_parser("paper", help="reproduce the paper's figures on the 1D bar")
    pp.add_argument("--out", "-o", default="paper-out", help="output folder (default paper-out)")
    pp.add_argument("--figures", help="comma-separated subset, e.g. fig2,fig6")
    pp.add_argument("--t-end", type=float, default=0.4, help="end time in s (default 0.4)")
    pp.add_argument("--quiet", "-q", action="store_true", help="no progress output")
    pp.add_argument("--overwrite", action="store_true", help="replace a finished reproduction")
    pp.set_defaults(func=_paper)
    cap = sub.add_parser("cache", help="the cache of assembled and reduced models")
    csub = cap.add_subparsers(dest="cache_command", required=True)
    for name, text in (("info", "where it is, entries and size"), ("clear", "remove all")):
        c = csub.add_parser(name, help=text)
        _cache_args(c, switch=False)
        c.set_defaults(func=_cache_command)
    try:
        from ..geometry.cli import add_mesh_parser, run_mesh
    except ImportError:  # geometry extras not installed
        pass
    else:
        mp = add_mesh_parser(sub)
        mp.set_defaults(func=run_mesh)
    return p


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def main(argv=None) -> int:
    map_large_arrays()  # a long build's freed arrays go back to the system (femrub.heap)
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.version:
        from .. import __version__

        print(f"femrub {__version__}")
        return 0
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    from ..output.interrupts import exit_status, interruptible

    try:
        with interruptible():
            return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print("femrub: interrupted; files written so far are kept", file=sys.stderr)
        return exit_status()
    except (ValueError, FileNotFoundError, FileExistsError, KeyError) as exc:
        print(f"femrub: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:  # a full disk, a read error: one line naming the file, status 1
        if os.environ.get("FEMRUB_DEBUG"):
            raise
        from ..output.safe_write import describe_os_error

        print(f"femrub: error: {_one_line(describe_os_error(exc))}", file=sys.stderr)
        return 1
    except Exception as exc:
        if os.environ.get("FEMRUB_DEBUG"):
            raise
        print(
            f"femrub: internal error: {type(exc).__name__}: {_one_line(exc)} "
            "(set FEMRUB_DEBUG=1 for the traceback)",
            file=sys.stderr,
        )
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
