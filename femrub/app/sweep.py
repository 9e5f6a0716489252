"""Parameter sweeps of a scene on dask.distributed, resumable, with an interaction map.

``femrub sweep SCENE --param rotation_speed=200:2000:50 -o DIR`` runs every point of the
grid (cartesian product of the ``--param`` values), each writing its own results folder
``DIR/runs/NNN_key=value/`` (:func:`femrub.scene.run_scene`). On this machine, this process
and up to ``--workers`` − 1 worker processes of a ``LocalCluster`` (1 thread each; 2
processes by default) walk the grid in order and each runs the next point no other has
claimed (:func:`claim_point`); on the cluster behind ``--scheduler ADDRESS`` (the output
folder must then be shared) each worker runs one chunk of points, every N-th of the grid
(:func:`run_points`: in both, a point at another speed reuses the model of the point
before, the speed being its parameter). A point whose folder holds a finished result is skipped, so
rerunning the command after a failure or an interruption only runs what is missing. A
point is keyed by a hash of its resolved scene (:func:`femrub.app.run.scene_hash`): its
folder name ends with the first characters of the hash, so changing the scene between two
runs of the sweep runs the changed points into new folders (the old results stay, never
reported as the new ones). The sweep folder is claimed like a run folder (kind ``sweep``,
locked). At the end ``DIR/interaction.csv`` and ``DIR/interaction.png``
(:mod:`femrub.output.interaction`) summarise the sweep.

Parameter values: ``start:stop:step`` (stop included), ``a,b,c`` or one value; a unit may
follow the numbers (``1000:3000:500rpm``); plain numbers are SI.
"""

from __future__ import annotations

import contextlib
import csv
import itertools
import json
import os
import re
import tempfile
from pathlib import Path

import numpy as np

from .. import heap
from ..output.folder import FINISHED, FolderError, claim, folder_status
from ..output.jsonfile import write_json
from ..output.results import PROBE_PREFIX
from ..output.run_folder import signal_measures
from ..output.safe_write import atomic_file, write_atomic
from ..scene import SceneError, parse_value, resolve_key
from ..scene.run_checks import check_run
from ..scene.scene import Scene
from .run import run_scene, scene_hash
from .simulation import SceneBuilds
from .translate import kernel_kinds

__all__ = ["parse_param", "grid", "run_point", "run_points", "point_metrics", "run_sweep"]

_RANGE = re.compile(r"^\s*([^:]+):([^:]+):([^:]+?)\s*([A-Za-zµμ/^]+[A-Za-z0-9µμ/^]*)?\s*$")
#: natural frequencies computed for the Campbell diagram
N_MODES = 4


def _number(text: str, what: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise SceneError(f"--param {what}: {text!r} is not a number") from None


def parse_param(text: str) -> tuple[str, list]:
    """``"key=spec"`` -> ``(dotted key, values)`` (module docstring for ``spec``)."""
    if "=" not in text:
        raise SceneError(f"--param {text!r}: use KEY=START:STOP:STEP or KEY=A,B,C")
    key, spec = (s.strip() for s in text.split("=", 1))
    key = resolve_key(key)
    m = _RANGE.match(spec)
    if m:
        a, b, step = (_number(g, text) for g in m.groups()[:3])
        if step <= 0 or b < a or (b - a) / step > 10_000:
            raise SceneError(f"--param {text!r}: need START <= STOP, STEP > 0, <= 10000 points")
        n = int(np.floor((b - a) / step + 1e-9)) + 1
        values = [float(f"{a + i * step:.12g}") for i in range(n)]
        unit = m.group(4)
        return key, [f"{v:g} {unit}" for v in values] if unit else values
    return key, [parse_value(v) for v in _with_unit([v.strip() for v in spec.split(",")], text)]


_UNIT = re.compile(r"^([-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?)\s*([A-Za-zµμ/^][A-Za-z0-9µμ/^]*)?$")


def _with_unit(items: list[str], text: str) -> list[str]:
    """``["1000", "2000rpm"]`` -> ``["1000 rpm", "2000 rpm"]``: a unit written once, after
    the last value, applies to every bare number of the list (as in ``START:STOP:STEPunit``).
    """
    if any(not v for v in items):
        raise SceneError(f"--param {text!r}: an empty value between commas")
    parts = [_UNIT.match(v) for v in items]
    unit = parts[-1].group(2) if parts[-1] else None
    if unit is None:
        if any(m and m.group(2) for m in parts):
            raise SceneError(
                f"--param {text!r}: a unit on some values and not on the last; write it after "
                "the last value (applies to all) or after each value"
            )
        return items
    return [f"{m.group(1)} {unit}" if m and m.group(2) is None else v for m, v in zip(parts, items)]


def grid(params: list[tuple[str, list]]) -> list[dict]:
    """Cartesian product of the parameter values, as dicts of dotted key -> value."""
    keys = [k for k, _ in params]
    return [dict(zip(keys, combo)) for combo in itertools.product(*(v for _, v in params))]


def _point_name(i: int, changes: dict, digest: str) -> str:
    parts = [f"{k.rsplit('.', 1)[-1]}={v}" for k, v in changes.items()]
    name = re.sub(r"[^A-Za-z0-9_=.,+-]+", "", f"{i:03d}_" + "_".join(parts))[:110]
    return f"{name}_{digest[:10]}"


def point_metrics(folder) -> dict:
    """The interaction-map quantities of one run folder (from its ``summary.json``)."""
    folder = Path(folder)
    try:
        s = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        return {"status": "missing", "message": f"no summary.json in {folder}"}
    peaks = s.get("signals_max_abs", {})
    temps = [peaks[k] for k in ("tip_temperature", "contact_temperature") if k in peaks]
    disp = [peaks[k] for k in ("tip_displacement", "contact_displacement") if k in peaks]
    build = s.get("inputs", {}).get("build", {})
    measures = _measures(s, folder / "history.npz")
    return {
        "status": s.get("status"),
        "message": s.get("message", ""),
        "max_tip_displacement": max(disp) if disp else None,
        "rms_tip_displacement": measures["signals_rms"].get("tip_displacement"),
        "max_wear_depth": s.get("max_wear_depth", 0.0),
        "max_contact_force": s.get("max_contact_force"),
        "max_temperature": max(temps) if temps else 0.0,
        "first_contact_time": s.get("first_contact_time"),
        "t_reached": s.get("t_reached"),
        "wall_seconds": s.get("wall_seconds"),
        "natural_frequencies_hz": build.get("natural_frequencies_hz", []),
        "probes": _probe_metrics(measures, s.get("units", {})),
    }


def _measures(summary: dict, path) -> dict:
    """Each signal's and probe's ``signals_rms`` and ``signals_max_abs`` (summary names):
    the summary's, or measured in ``history.npz`` for a folder written before the summary
    held ``signals_rms`` (the same :func:`~femrub.output.run_folder.signal_measures`; empty
    when neither is there)."""
    if "signals_rms" in summary:
        return {k: summary.get(k, {}) for k in ("signals_rms", "signals_max_abs")}
    try:
        with np.load(path) as h:
            stored = {
                k.removeprefix("signal_"): h[k]
                for k in h.files
                if k.startswith(("signal_", PROBE_PREFIX))
            }
    except (OSError, ValueError):
        return {"signals_rms": {}, "signals_max_abs": {}}
    return signal_measures(stored)


def _probe_metrics(measures: dict, units: dict) -> dict:
    """``rms_probe_<name>_<unit>`` and ``max_probe_<name>_<unit>`` (largest magnitude) of
    each probe (``outputs.probes``; SI units, ``m_s`` for m/s) from :func:`_measures`."""
    out = {}
    peak = measures["signals_max_abs"]
    for key, rms in measures["signals_rms"].items():
        if key.startswith(PROBE_PREFIX):
            unit = units.get(key, "-").replace("/", "_")
            out[f"rms_{key}_{unit}"], out[f"max_{key}_{unit}"] = rms, peak.get(key)
    return out


def run_points(
    scene_data: dict,
    source: str,
    base_dir: str,
    points: list,
    cache=None,
    done=None,
    builds=None,
    claims=None,
) -> list:
    """Run ``points`` (``[(changes, folder), ...]``) in order in one worker and return their
    rows; never raises: a failed point comes back as its row.

    Their models come from one :class:`~femrub.app.simulation.SceneBuilds` (``builds``, or a
    new one): a point at another rotation speed than the one before takes the previous
    point's model at its own speed (its parameter) instead of building one; any other point
    shares the mesh's bases, the assembled blocks and the reductor the points before it
    built. ``cache``: a :class:`~femrub.app.cache.ModelCache` shared by the workers;
    ``done``: called after each point (a progress bar). ``claims``: a folder shared by the
    processes given the same points (:func:`claim_point`): each point runs in the process
    that claims it first, the others skip it (its row ``None``), so that a process free
    before the others takes the next point left.
    """
    heap.map_large_arrays()  # workers of another scheduler (femrub.heap)
    base = Scene(scene_data, source, Path(base_dir))
    builds = builds if builds is not None else SceneBuilds(cache)
    rows = []
    for changes, out in points:
        if claims is not None and not claim_point(claims, out):
            rows.append(None)  # run by another process
            continue
        rows.append(_run_one(base.with_changes(changes), out, builds))
        if done is not None:
            done()
    return rows


def claim_point(claims, folder) -> bool:
    """Whether this process is the first to claim the point whose folder is ``folder``
    (an empty file named after it created in ``claims``, exclusively)."""
    try:
        os.close(os.open(Path(claims) / Path(folder).name, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return False
    return True


def run_point(
    scene_data: dict, source: str, base_dir: str, changes: dict, out: str, cache=None
) -> dict:
    """Run one point (:func:`run_points` of that point alone)."""
    (row,) = run_points(scene_data, source, base_dir, [(changes, out)], cache)
    return row


def _run_one(scene: Scene, out: str, builds: SceneBuilds) -> dict:
    try:
        run_scene(scene, out, overwrite=True, modes=N_MODES, builds=builds)
    except Exception as exc:  # a bad point must not stop the sweep
        msg = f"{type(exc).__name__}: {exc}".splitlines()[0]
        try:
            Path(out).mkdir(parents=True, exist_ok=True)
            if folder_status(out) in (None, "running"):
                write_json(Path(out) / "summary.json", {"status": "failed", "message": msg})
        except OSError:
            pass
        return {"status": "failed", "message": msg}
    return point_metrics(out)


def _hash_of(folder) -> str | None:
    """``scene_sha256`` recorded in a point's ``summary.json`` (``None``: none readable)."""
    try:
        s = json.loads((Path(folder) / "summary.json").read_text())
        return s.get("inputs", {}).get("scene_sha256")
    except (OSError, ValueError, AttributeError):
        return None


def _client(scheduler, workers):
    from dask.distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler), None
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        env={
            "OMP_NUM_THREADS": "1",
            "OPENBLAS_NUM_THREADS": "1",
            "MKL_NUM_THREADS": "1",
            heap.ENV: str(heap.LARGE),  # femrub.heap, from the workers' start
        },
    )
    return Client(cluster), cluster


def run_sweep(
    scene: Scene,
    params,
    out,
    *,
    scheduler=None,
    workers=2,
    overwrite=False,
    progress=False,
    log=None,
    cache=None,
) -> list[dict]:
    """Run the sweep; return one row per point (params, metrics, folder, skipped).

    Parameters
    ----------
    scene : base :class:`~femrub.scene.scene.Scene`.
    params : list of ``(dotted key, values)`` (:func:`parse_param`).
    out : sweep folder.
    scheduler : address of a dask scheduler; ``None``: this machine.
    workers : processes running points on this machine: this one and at most
        ``workers - 1`` worker processes of a ``LocalCluster`` (:func:`_share_here`); 0 or 1
        (or points for one chunk): the points run one after the other in this process,
        without dask (a small map, a debugger, a script that is not guarded by
        ``if __name__ == "__main__"``).
    overwrite : rerun points that already have a finished result.
    cache : a :class:`~femrub.app.cache.ModelCache` (its folder must be shared with the
        workers): the first point runs alone and stores its models (assembly, damping,
        reduction bases, map to the mesh), the others then load what they share with it
        instead of building it again (:func:`_batches`); without a cache every worker starts
        at once and builds its own.
    """
    out = Path(out)
    if scheduler is None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 0
    ):
        raise FolderError(
            f"--workers {workers!r}: give a number of worker processes (this one included), "
            "or 0 to run here"
        )
    keys = [k for k, _ in params]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise SceneError(
            f"--param {twice[0]} is given twice; give each key once with all its values "
            f"(--param {twice[0].rsplit('.', 1)[-1]}=A,B,C)"
        )
    points = grid(params)
    scenes = [scene.with_changes(p) for p in points]  # every point valid before any work
    for s in scenes:
        check_run(s)
    with claim(out, "sweep", check_result=False):
        return _sweep(
            scene,
            params,
            points,
            scenes,
            keys,
            out,
            scheduler,
            workers,
            overwrite,
            progress,
            log,
            cache,
        )


def _sweep(
    scene, params, points, scenes, keys, out, scheduler, workers, overwrite, progress, log, cache
):
    hashes = [scene_hash(s) for s in scenes]
    doc = {
        "scene": scene.data,
        "params": {k: v for k, v in params},
        "n_points": len(points),
        "scene_sha256": hashes,
    }
    write_json(out / "sweep.json", doc)
    write_atomic(out / "scene.toml", scene.dumps())
    rows = []
    for i, (p, digest) in enumerate(zip(points, hashes)):
        folder = out / "runs" / _point_name(i, p, digest)
        done = folder_status(folder) in FINISHED and not overwrite
        done = done and _hash_of(folder) == digest
        rows.append(
            {
                "point": i,
                "params": p,
                "folder": str(folder),
                "skipped": done,
                "scene_sha256": digest,
            }
        )
    todo = [r for r in rows if not r["skipped"]]
    for r in rows:
        if r["skipped"]:
            r.update(point_metrics(r["folder"]))
    if log:
        log(
            f"sweep: {len(points)} points, {len(rows) - len(todo)} already done, "
            f"{len(todo)} to run -> {out}/"
        )
    if todo:
        _compute(scene, todo, scheduler, workers, progress, cache)
    for r in rows:
        r["x"] = _x(scene.with_changes(r["params"]), keys[0])
    _write_csv(rows, keys, out / "interaction.csv")
    from ..output.interaction import plot_interaction_map

    plot_interaction_map(rows, keys, scene.data, out / "interaction.png")
    return rows


def _compute(scene, todo, scheduler, workers, progress, cache=None) -> None:
    from tqdm.auto import tqdm

    bar = tqdm(total=len(todo), disable=not progress, unit="point", desc="sweep")
    local = scheduler is None  # this process is one of the ``workers`` processes
    first, (_, *theirs) = _split(todo, cache, workers) if local else ([], ([], []))
    if local and not theirs:  # --workers 0 or 1, or one chunk: here, the points in a row
        _points_here(scene, todo, cache, bar)
        bar.close()
        return
    client, cluster = _client(scheduler, len(theirs) if local else workers)

    def submit(chunks, claims=None, on=()):
        """A task per chunk (on the worker ``on[i]`` when given)."""
        return {
            client.submit(
                run_points,
                *_here(scene),
                [(r["params"], r["folder"]) for r in chunk],
                cache,
                claims=claims,
                pure=False,
                key=f"femrub-points-{chunk[0]['point']}-{id(chunk)}-{i}",
                workers=[on[i]] if on else None,
            ): chunk
            for i, chunk in enumerate(chunks)
        }

    try:
        if local:
            with _claims_folder(todo[0]["folder"]) as claims:
                _share_here(scene, first, todo[len(first) :], cache, client, submit, bar, claims)
        else:
            n_workers = len(client.scheduler_info().get("workers", {})) or workers
            for chunks in _batches(todo, cache, n_workers):
                _collect(submit(chunks), bar)
        bar.close()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@contextlib.contextmanager
def _claims_folder(point_folder):
    """A new folder beside the points' folders for their claims (:func:`claim_point`),
    removed with the claims this sweep made in it."""
    runs = Path(point_folder).parent
    runs.mkdir(parents=True, exist_ok=True)
    claims = Path(tempfile.mkdtemp(prefix=".claims-", dir=runs))
    try:
        yield claims
    finally:
        for f in claims.iterdir():
            f.unlink(missing_ok=True)
        claims.rmdir()


def _points_here(scene, chunk, cache, bar, builds=None, claims=None) -> None:
    """Run ``chunk`` in this process (``builds``: what it built before), rows filled in
    (``claims``: :func:`run_points`; the points another process claimed are left as they
    are)."""
    points = [(r["params"], r["folder"]) for r in chunk]
    rows = run_points(
        *_here(scene), points, cache, done=lambda: bar.update(1), builds=builds, claims=claims
    )
    for r, row in zip(chunk, rows, strict=True):
        if row is not None:
            r.update(row)


def _share_here(scene, first, rest, cache, client, submit, bar, claims) -> None:
    """The points on this process (``first``, then its share of ``rest``) and on the
    workers of a ``LocalCluster`` (their share of ``rest``): every process walks ``rest`` in
    order and runs the points it claims first (:func:`run_points`, ``claims``), so each
    takes the next point left when it is free.

    With a cache, the first point runs here first, on all this process's cores (the local
    workers have one thread each and would otherwise build it on one while the others wait:
    on Rotor 37 46 s instead of 83 s), and fills the cache (assembly, damping, reduction
    bases, map to the mesh). The workers start at once when numba's cache holds the
    kernels the points need: their first point waits for each entry the first point is
    building (:meth:`ModelCache.building <femrub.app.cache.ModelCache.building>`), loads it,
    and runs as soon as the bases are stored, before the first point's own run; otherwise
    they prepare (:func:`prepare_worker`) and start after it. This process then runs its
    points on one BLAS thread from the model it holds (a worker's first point builds its
    model from the cache). MKL's reproducible mode
    (:data:`femrub.fem.linalg.MKL_REPRODUCIBLE`) keeps its threaded factorisations, and so
    the bases every point shares, the same from run to run.
    """
    from ..blas import one_blas_thread
    from ..contact.jit import cold_kinds

    builds = SceneBuilds(cache)
    workers = list(client.scheduler_info().get("workers", {}))
    kinds = kernel_kinds(scene)
    early = not first or not cold_kinds(kinds)
    futures = submit([rest] * len(workers), claims, workers) if early else None
    if first:
        prepared = [  # kept until the points are submitted after them
            client.submit(prepare_worker, kinds, workers=[w], pure=False)
            for w in workers
            if not early
        ]
        _points_here(scene, first, cache, bar, builds)
        del prepared
    if futures is None:
        futures = submit([rest] * len(workers), claims, workers)
    with one_blas_thread:
        _points_here(scene, rest, cache, bar, builds, claims)
    _collect(futures, bar)


def prepare_worker(kinds: tuple[str, ...]) -> None:
    """What a worker's first point would otherwise start with, done while the sweep's first
    point builds (:func:`_share_here`): femrub's modules and the libraries they load (MKL for
    Pardiso), and the contact kernels of ``kinds`` loaded from numba's cache
    (:func:`~femrub.contact.activation.compile_kernels`); 2–3 s per worker on Rotor 37.
    Kernels numba's cache does not hold yet are left alone: the first point's build
    compiles them once, in a child (:func:`~femrub.contact.jit.compile_in_background`),
    and each worker compiling them too took the cores that build needs (Rotor 37's first
    sweep on a fresh install: its first point 148 s instead of 50 s).
    Never raises: the point would then do it itself."""
    try:
        from ..contact.activation import compile_kernels
        from ..contact.jit import cold_kinds
        from ..fem.linalg import pardiso_available
        from ..output import run_folder  # noqa: F401 (the modules a point's output loads)

        pardiso_available()
        cold = cold_kinds(kinds)
        compile_kernels(tuple(k for k in kinds if k not in cold))
    except Exception:  # noqa: BLE001 - a preparation, never the point's failure
        pass


def _here(scene) -> tuple:
    """The scene as :func:`run_points` takes it (what a worker receives)."""
    return scene.data, scene.source, str(scene.base_dir)


def _batches(todo: list, cache, workers: int) -> list[list[list]]:
    """The points to submit together to a scheduler's cluster, in order, as one chunk per
    worker (:func:`_chunks`; :func:`run_points`: a chunk builds its model once and takes it
    at each speed); a ``LocalCluster`` shares them with this process instead
    (:func:`_share_here`).

    With a cache and more than one point, the first point runs alone and fills the cache
    (assembly, damping, reduction bases, map to the mesh); the other chunks then load
    them (a worker's first point would otherwise build them again: on Rotor 37 two
    workers building at once took longer each than one alone)."""
    first, chunks = _split(todo, cache, workers)
    chunks = [c for c in chunks if c]
    batches = [[first]] if first else []
    if chunks:
        batches.append(chunks)
    return batches


def _split(todo: list, cache, n: int) -> tuple[list, list[list]]:
    """``(first, chunks)``: with a cache and more than one point, the first point alone (it
    fills the cache), and the other points dealt into at most ``n`` chunks (:func:`_chunks`)."""
    first = todo[:1] if cache is not None and len(todo) > 1 else []
    return first, _chunks(todo[len(first) :], n)


def _chunks(points: list, n: int) -> list[list]:
    """``points`` dealt into at most ``n`` chunks, chunk ``i`` every ``n``-th point from the
    ``i``-th (the first ones one point larger when they do not divide evenly; at least one
    chunk, maybe empty). Each chunk spans the whole grid, so points whose cost grows along
    it (a map's higher speeds: more contact) are shared evenly; in a grid whose last key
    varies fastest, a chunk's points in a row still differ in that key alone."""
    n = max(1, min(n, len(points)))
    return [points[i::n] for i in range(n)]


def _collect(futures, bar) -> None:
    """Fill in the rows of the points each task ran (``None``: run elsewhere); a point
    left without a row (its worker lost, ...) is ``failed``."""
    from dask.distributed import as_completed

    lost = None
    for fut in as_completed(futures):
        try:
            rows = fut.result()
        except Exception as exc:  # worker lost, etc.
            lost = f"{type(exc).__name__}: {exc}"
            continue
        ran = [(r, row) for r, row in zip(futures[fut], rows, strict=True) if row is not None]
        for r, row in ran:
            r.update(row)
        bar.update(len(ran))
    for r in (r for chunk in futures.values() for r in chunk):
        if "status" not in r:
            r.update(status="failed", message=lost or "not run")
            bar.update(1)


def _x(scene, key) -> float:
    v = scene[key]
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else str(v)


def _write_csv(rows, keys, path) -> None:
    n_f = max((len(r.get("natural_frequencies_hz") or []) for r in rows), default=0)
    probes = list(dict.fromkeys(k for r in rows for k in r.get("probes") or {}))
    cols = [
        "point",
        *keys,
        "status",
        "max_tip_displacement_m",
        "max_contact_force_N",
        "max_temperature_K",
        "first_contact_time_s",
        "t_reached_s",
        *[f"f{j + 1}_hz" for j in range(n_f)],
        "skipped",
        "folder",
        "message",
        "rms_tip_displacement_m",
        "max_wear_depth_m",
        *probes,
    ]
    with atomic_file(path, "w") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for r in rows:
            f = list(r.get("natural_frequencies_hz") or []) + [""] * n_f
            w.writerow(
                [
                    r["point"],
                    *[r["x"] if k == keys[0] else r["params"][k] for k in keys],
                    r.get("status"),
                    r.get("max_tip_displacement"),
                    r.get("max_contact_force"),
                    r.get("max_temperature"),
                    r.get("first_contact_time"),
                    r.get("t_reached"),
                    *f[:n_f],
                    r["skipped"],
                    r["folder"],
                    r.get("message", ""),
                    r.get("rms_tip_displacement"),
                    r.get("max_wear_depth"),
                    *[(r.get("probes") or {}).get(k) for k in probes],
                ]
            )
