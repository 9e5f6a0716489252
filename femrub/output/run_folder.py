"""A run's results folder: history, summary, plots and (for 3D) the VTK series.

:func:`run_to_folder` integrates a model with a stepper and writes, into ``out``:
``history.csv`` and ``history.npz`` (every observed signal, gaps, contact forces and
impulses, friction forces, slip velocities and contact states, energy balance),
``summary.json`` (inputs, versions, timings, energy balance, friction, status),
``signals.png``, on a rotating blade ``response.png``, ``spectrum.png`` and
``contact_forces.png`` (:mod:`femrub.output.rub_plots`) and, when a
:class:`~femrub.model.rub.FieldMap` is given, ``vtk/`` (``.pvd`` + ``.vtu``, written as the
run goes) and ``snapshot.png``. A run that is
interrupted or fails keeps everything written so far and says so in ``summary.json``.
A finished result (status ok, unstable or diverged-physically) is not overwritten unless
``overwrite=True``; an interrupted or failed one is simply run again.
"""

from __future__ import annotations

import json
import platform
import time
from pathlib import Path

import numpy as np

from .. import __version__
from .plots import savefig, tip_panels

__all__ = ["STAGES", "run_to_folder", "ResultExists"]

#: Pipeline stages timed in ``summary.json["timings"]`` (seconds).
STAGES = ("mesh", "assembly", "reduction", "stepping", "output")


class ResultExists(FileExistsError):
    """The output folder already holds a finished result."""


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, float | int | str | bool) or x is None:
        return x
    return str(x)


def _write_json(path: Path, doc: dict) -> None:
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(_jsonable(doc), indent=2))
    tmp.replace(path)


def _friction_summary(res) -> dict:
    """``max_friction_force`` (N), ``friction_work``, ``heat_to_blade``, ``heat_to_casing`` (J)
    and the Coulomb check of every recorded step (:func:`femrub.contact.friction.coulomb_check`).
    """
    e = res.energy
    ff = res.friction_force
    out = {
        "max_friction_force": float(np.linalg.norm(ff, axis=-1).max())
        if ff is not None and ff.size
        else 0.0,
        "friction_work": float(e["friction_work"][-1]) if "friction_work" in e else 0.0,
        "heat_to_blade": float(e["friction_heat"][-1]) if "friction_heat" in e else 0.0,
        "heat_to_casing": float(e["heat_to_casing"][-1]) if "heat_to_casing" in e else 0.0,
    }
    if ff is not None and ff.size and res.friction_limit is not None:
        from ..contact.friction import coulomb_check

        out["coulomb_check"] = coulomb_check(
            res.force, ff, res.slip_velocity, res.contact_state, res.friction_limit
        )
    return out


#: relative tolerance of the Coulomb check (|λ_t| <= μ λ, equality and direction when sliding)
COULOMB_TOL = 1e-8


def _coulomb_violated(check) -> str:
    """A message when the recorded friction forces break Coulomb's law, else ``""``."""
    if not check:
        return ""
    worst = max(check["cone"], check["slip_equality"], check["direction"])
    if worst <= COULOMB_TOL and check["force_without_normal"] == 0.0:
        return ""
    return (
        f"Coulomb law violated beyond {COULOMB_TOL:g} (cone {check['cone']:.2g}, sliding "
        f"{check['slip_equality']:.2g}, direction {check['direction']:.2g})"
    )


def run_to_folder(
    stepper,
    t_end: float,
    out,
    *,
    fields=None,
    vtk_stride: int = 0,
    inputs: dict | None = None,
    limits: dict | None = None,
    progress: bool = False,
    overwrite: bool = False,
    snapshot: bool = True,
    plots: bool = True,
    timings: dict | None = None,
    n_full: int | None = None,
    rotation_speed: float = 0.0,
):
    """Run ``stepper`` to ``t_end`` and write the results folder ``out`` (module docstring).

    ``timings`` holds the seconds of the stages before the run (``mesh``, ``assembly``,
    ``reduction``); ``summary.json["timings"]`` adds ``stepping`` (the run without the
    output it streams) and ``output`` (VTK frames, histories, plots). ``n_full``: state dofs
    of the full model when ``stepper.model`` is reduced; ``rotation_speed`` (rad/s) counts the
    ``revolutions`` reached. Returns the
    :class:`~femrub.output.results.Results`.
    """
    out = Path(out)
    summary_path = out / "summary.json"
    if summary_path.exists() and not overwrite:
        prev = json.loads(summary_path.read_text()).get("status")
        if prev not in (None, "running", "interrupted", "failed"):
            raise ResultExists(
                f"{out} already holds a finished result (status {prev}); "
                "use another folder or --overwrite"
            )
    out.mkdir(parents=True, exist_ok=True)
    model = stepper.model
    doc = {
        "femrub_version": __version__,
        "python": platform.python_version(),
        "scheme": stepper.name,
        "h": stepper.h,
        "t_end": t_end,
        "n_dofs": model.n_dofs,
        "n_full": model.n_dofs if n_full is None else int(n_full),
        "n_contacts": model.n_contacts,
        "model": model.info,
        "inputs": inputs or {},
        "status": "running",
    }
    _write_json(summary_path, doc)
    series = None
    if fields is not None and vtk_stride:
        from .vtk import VTKSeries

        series = VTKSeries(out / "vtk", model, fields, h=stepper.h, stride=vtk_stride)
    t0 = time.perf_counter()
    res = stepper.run(t_end, progress=progress, limits=limits, on_state=series)
    wall = time.perf_counter() - t0
    vtk_wall, vtk_cpu = (series.seconds, series.cpu_seconds) if series is not None else (0.0, 0.0)
    t_out = time.perf_counter()
    res.save_csv(out / "history.csv")
    res.save_npz(out / "history.npz")
    panels = [k for k in ("tip_displacement", "tip_temperature") if k in res.signals]
    if plots:
        savefig(
            tip_panels(
                [(stepper.name, res, {})],
                panels=(*panels, "contact_force"),
                title=f"{stepper.name}, h = {stepper.h:g} s: {res.status}",
            ),
            out / "signals.png",
        )
    if plots and rotation_speed and res.impulse.shape[1] and res.steps > 1:
        from .rub_plots import contact_force_panel, response_panels, spectrum_panel

        omega_ = float(rotation_speed)
        savefig(response_panels(res, omega_), out / "response.png")
        savefig(spectrum_panel(res, omega_), out / "spectrum.png")
        savefig(contact_force_panel(res, omega_), out / "contact_forces.png")
    if series is not None and series.frames and snapshot and plots:
        from .vtk import snapshot_png

        try:
            snapshot_png(series.dir / series.frames[-1][1], out / "snapshot.png")
        except Exception as exc:  # rendering is optional (no OpenGL on the machine)
            doc["snapshot_error"] = f"{type(exc).__name__}: {exc}"
    e = res.energy
    stepping_cpu = max(res.cpu_seconds - vtk_cpu, 0.0)
    omega = float(rotation_speed)
    stages = {k: 0.0 for k in STAGES} | dict(timings or {})
    stages.update(stepping=wall - vtk_wall, output=vtk_wall + time.perf_counter() - t_out)
    res.info["timings"] = {k: stages[k] for k in STAGES}
    doc.update(
        status=res.status,
        message=res.message,
        steps=res.steps,
        t_reached=float(res.t[-1]),
        revolutions=float(res.t[-1]) * omega / (2.0 * np.pi),
        cpu_seconds=res.cpu_seconds,
        wall_seconds=wall,
        cpu_per_step_us=1e6 * stepping_cpu / max(res.steps, 1),
        timings=res.info["timings"],
        first_contact_time=res.first_contact_time(),
        max_contact_force=float(res.force.max()) if res.force.size else 0.0,
        energy_error=res.energy_error(),
        heat_error=res.heat_error(),
        energy={k: float(v[-1]) for k, v in e.items()} if e else {},
        vtk=str(series.pvd_path.relative_to(out)) if series is not None else None,
        vtk_frames=len(series.frames) if series is not None else 0,
    )
    doc.update(_friction_summary(res))
    bad = _coulomb_violated(doc.get("coulomb_check"))
    if bad and doc["status"] == "ok":  # not trustworthy: the friction law is not met
        doc.update(status="inaccurate", message=bad)
    for name, arr in res.signals.items():
        doc.setdefault("signals_max_abs", {})[name] = float(np.abs(arr).max()) if arr.size else 0.0
    _write_json(summary_path, doc)
    return res
