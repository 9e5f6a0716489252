"""Run a scene into a results folder (:func:`femrub.output.run_folder.run_to_folder`).

Besides what :func:`~femrub.output.run_folder.run_to_folder` writes (``history.csv``/``.npz``,
``summary.json``, ``signals.png``, ``vtk/``, ``snapshot.png``), the folder gets
``scene.toml`` (the normalised scene, paths made absolute: ``femrub run`` reruns it) and
``explain.txt``. ``summary.json["inputs"]`` holds the scene, the build report and the
versions of the libraries. A folder with a finished result is never overwritten silently.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

from ..output.run_folder import ResultExists, run_to_folder
from ..scene.scene import Scene
from .simulation import build

__all__ = ["FINISHED", "folder_status", "run_scene", "versions"]

#: statuses of a finished run; any other (running, interrupted, failed) may be rerun
FINISHED = ("ok", "unstable", "diverged-physically")


def folder_status(out) -> str | None:
    """Status in ``out/summary.json`` (``None`` when there is no readable summary)."""
    try:
        return json.loads((Path(out) / "summary.json").read_text()).get("status")
    except (OSError, ValueError):
        return None


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
    scene: Scene, out, *, overwrite=False, progress=False, log=None, on_built=None, modes=0
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
    """
    out = Path(out)
    status = folder_status(out)
    if status in FINISHED and not overwrite:
        raise ResultExists(
            f"{out} already holds a finished result (status {status}); "
            "use another folder or --overwrite"
        )
    built = build(scene, log=log, modes=modes)
    if on_built is not None:
        on_built(built)
    out.mkdir(parents=True, exist_ok=True)
    (out / "scene.toml").write_text(_resolved(scene).dumps())
    (out / "explain.txt").write_text(built.explain() + "\n")
    o = scene["outputs"]
    stride = o["vtk_stride"] if built.fields is not None else 0
    inputs = {"scene": _finite(scene.data), "build": _finite(built.report), "versions": versions()}
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
        timings=built.timings,
        n_full=built.full.n_dofs,
        rotation_speed=scene["loads"]["rotation_speed"],
    )
    contact = built.model.contact
    if contact is not None and contact.wear is not None:
        from ..output.wear import write_wear

        res.info.update(write_wear(contact.wear, out))
    if contact is not None and contact.casing_heat is not None:
        from ..output.wear import write_casing_heat

        res.info.update(write_casing_heat(contact.casing_heat, float(res.t[-1]), out))
    return res, built
