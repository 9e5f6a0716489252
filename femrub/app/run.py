"""Run a scene into a results folder (:func:`femrub.output.run_folder.run_to_folder`).

Besides what :func:`~femrub.output.run_folder.run_to_folder` writes (``history.csv``/``.npz``,
``summary.json``, ``signals.png``, ``vtk/``, ``snapshot.png``), the folder gets
``scene.toml`` (the normalised scene, paths made absolute: ``femrub run`` reruns it) and
``explain.txt``. ``summary.json["inputs"]`` holds the scene, the build report, the versions
of the libraries and ``scene_sha256`` (:func:`scene_hash`). The folder is claimed before
the model is built (:func:`femrub.output.folder.claim`: writable, locked against a second
run, not a paper or sweep folder, no finished or unreadable result unless ``overwrite``).
"""

from __future__ import annotations

import copy
import functools
import hashlib
import json
import math
from pathlib import Path

from ..contact.casing import lobe_passing_frequency
from ..output.folder import FINISHED, FolderError, claim, folder_status
from ..output.jsonfile import write_json
from ..output.run_folder import run_to_folder
from ..output.safe_write import describe_os_error, write_atomic
from ..scene.run_checks import check_run
from ..scene.scene import Scene
from .cache import source_version
from .inputs import inputs_digest
from .simulation import build

__all__ = ["FINISHED", "folder_status", "merge_time", "run_scene", "scene_hash", "versions"]


def scene_hash(scene: Scene) -> str:
    """SHA-256 of what shapes a run's result: the resolved scene (SI values, defaults,
    absolute paths; name excluded), the bytes of every file it names
    (:func:`~femrub.app.inputs.inputs_digest`: mesh, includes, sections) and femrub's
    source (:func:`~femrub.app.cache.source_version`)."""
    data = {k: v for k, v in _resolved(scene).data.items() if k not in ("name", "description")}
    text = json.dumps(data, sort_keys=True, default=str)
    h = hashlib.sha256(text.encode())
    h.update(inputs_digest(scene).encode())
    h.update(source_version().encode())
    return h.hexdigest()


def merge_time(scene: Scene) -> float | None:
    """A quarter of the excitation period (s): impulses closer than this form one contact
    episode of the resolution check (tip force, else casing lobes passing at Ω)."""
    loads, casing = scene["loads"], scene["contact"]["casing"]
    omega = loads["rotation_speed"]
    force = loads["tip_force"]
    w = None
    if force["law"] == "sin":
        w = (
            force["engine_order"] * omega
            if force["frequency"] == "rotation"
            else force["frequency"]
        )
    elif omega > 0:  # the lobes passing, or once per revolution
        w = lobe_passing_frequency(casing, omega) or omega
    return 0.25 * 2.0 * math.pi / w if w else None


def versions() -> dict:
    """Versions of femrub and of the libraries that shape its results."""
    import gmsh
    import numpy
    import scipy
    import skfem

    from .. import __version__

    return {
        "femrub": __version__,
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "scikit-fem": getattr(skfem, "__version__", "?"),
        "gmsh": getattr(gmsh, "__version__", "?"),
    }


def _finite(x):
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_finite(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    return x


def _resolved(scene: Scene) -> Scene:
    data = copy.deepcopy(scene.data)
    g = data["geometry"]
    if g.get("path") is not None:
        g["path"] = str(scene.path(g["path"]).resolve())
    if g.get("files"):
        g["files"] = [str(scene.path(f).resolve()) for f in g["files"]]
    return Scene(data, scene.source, scene.base_dir)


def run_scene(
    scene: Scene,
    out,
    *,
    overwrite=False,
    progress=False,
    log=None,
    on_built=None,
    modes=0,
    cache=None,
    builds=None,
    keep_build=True,
):
    """Build and run ``scene`` into the folder ``out``; return ``(results, built)``.

    Parameters
    ----------
    scene : the :class:`~femrub.scene.scene.Scene`.
    out : results folder.
    overwrite : replace a finished result (otherwise :class:`ResultExists`); an unfinished
        one (interrupted, failed, killed) is always replaced.
    progress : show a progress bar while stepping.
    log : callable for progress messages (``None``: silent).
    on_built : callable ``f(built)`` called after the build, before the first step.
    modes : natural frequencies to compute and report (``build.natural_frequencies_hz``).
    cache : a :class:`~femrub.app.cache.ModelCache` of assembled and reduced models.
    builds : a :class:`~femrub.app.simulation.SceneBuilds` that builds the scene (with its
        own cache, in place of ``cache``) from what it built before (the points of a sweep).
    keep_build : ``False``: ``built`` without its full model and reductor
        (:meth:`~femrub.app.simulation.Simulation.released`), let go before the run and its
        output, which do not read them (``femrub run``: on Rotor 37 they are over a
        gigabyte).
    """
    out = Path(out)
    check_run(scene)
    _check_not_the_scene(scene, out)
    with claim(out, "run", overwrite=overwrite):
        make = builds or functools.partial(build, cache=cache)
        return _run_claimed(scene, out, progress, log, on_built, modes, make, keep_build)


def _check_not_the_scene(scene: Scene, out: Path) -> None:
    """Refuse an output folder whose ``scene.toml`` is the scene file being run."""
    source = Path(scene.source)
    dump = out / "scene.toml"
    if source.is_file() and dump.exists() and dump.resolve() == source.resolve():
        raise FolderError(
            f"{dump} is the scene being run; femrub would replace it with its own dump: "
            "copy it elsewhere or use another -o"
        )


def _run_claimed(scene, out, progress, log, on_built, modes, make, keep_build=True):
    try:
        built = make(scene, log=log, modes=modes)
    except OSError as exc:  # a read error: the folder says so too
        write_json(out / "summary.json", {"status": "failed", "message": describe_os_error(exc)})
        raise
    if on_built is not None:
        on_built(built)
    n_full = built.full.n_dofs
    if not keep_build:
        built = built.released()
    write_atomic(out / "scene.toml", _resolved(scene).dumps())
    write_atomic(out / "explain.txt", built.explain() + "\n")
    o = scene["outputs"]
    stride = o["vtk_stride"] if built.fields is not None else 0
    inputs = {
        "scene": _finite(scene.data),
        "build": _finite(built.report),
        "versions": versions(),
        "scene_sha256": scene_hash(scene),
    }
    if log:
        log(f"running {built.stepper.name} on {built.model.n_dofs} dofs -> {out}/")
    res = run_to_folder(
        built.stepper,
        scene["scheme"]["t_end"],
        out,
        fields=built.fields if stride else None,
        vtk_stride=stride,
        inputs=inputs,
        limits=built.limits or None,
        progress=progress,
        overwrite=True,
        snapshot=o["plots"],
        plots=o["plots"],
        timings=built.timings,
        n_full=n_full,
        rotation_speed=scene["loads"]["rotation_speed"],
        merge_time=merge_time(scene),
        claimed=True,
        reduction_error=built.report["reduction"].get("error"),
        step_error=built.report.get("time_step"),
        ran=built.ran,  # stepped by the error estimate: not twice
        csv_stride=o["csv_stride"],
        history_npz=o["history_npz"],
    )
    if log:
        t = res.info.get("timings", {})
        per_step = 1e6 * t.get("stepping", 0.0) / max(res.steps, 1)
        log(
            f"stepping done in {t.get('stepping', 0.0):.2f} s ({res.steps} steps, "
            f"{per_step:.0f} µs/step wall), output {t.get('output', 0.0):.2f} s"
        )
    info = built.model.info
    contact = res.contact_history  # the run's own history (wear map, casing heat)
    if info.get("kind") == "bladed-disk" and res.impulse.size:
        from ..output.blades import write_blades

        wear = contact.wear if contact is not None else None
        incursion = None if wear is None else wear.incursion
        res.info["blades"] = write_blades(res, info["n_blades"], out, incursion)
    if contact is not None and contact.wear is not None:
        from ..output.wear import write_wear

        res.info.update(write_wear(contact.wear, out))
    if contact is not None and contact.casing_heat is not None:
        from ..output.wear import write_casing_heat

        res.info.update(write_casing_heat(contact.casing_heat, float(res.t[-1]), out))
    return res, built
