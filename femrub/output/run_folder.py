"""A run's results folder: history, summary, plots and (for 3D) the VTK series.

:func:`run_to_folder` integrates a model with a stepper and writes, into ``out``:
``history.csv`` and ``history.npz`` (every observed signal, gaps, contact forces and
impulses, energy balance), ``summary.json`` (inputs, versions, timings, energy balance,
status), ``signals.png`` and, when a :class:`~femrub.model.rub.FieldMap` is given, ``vtk/``
(``.pvd`` + ``.vtu``, written as the run goes) and ``snapshot.png``. A run that is
interrupted (Ctrl-C or SIGTERM) or fails keeps everything written so far and says so in
``summary.json``: ``history.csv`` is appended block by block as the run goes
(:class:`~femrub.output.history_file.HistoryCSV`), each VTK frame is complete or absent,
and the final files are written with signals held back (:func:`~femrub.output.interrupts.
deferred`). The folder is claimed first (:func:`~femrub.output.folder.claim`: writable,
locked, not another command's folder); a finished result (status ok, inaccurate, unstable
or diverged-physically) or an unreadable summary is not overwritten unless
``overwrite=True``; an interrupted or failed one is simply run again.
"""

from __future__ import annotations

import platform
import sys
import time
from contextlib import nullcontext
from functools import partial
from pathlib import Path

import numpy as np

from .. import __version__
from ..steppers.record import State
from .folder import OUTPUTS, ResultExists, claim
from .history_file import HistoryCSV, NoHistoryCSV
from .interrupts import deferred, interruptible
from .jsonfile import write_json as _write_json
from .plots import savefig, tip_panels
from .results import PROBE_PREFIX, signal_units
from .safe_write import describe_os_error, naming
from .verdict import assess

__all__ = ["STAGES", "run_to_folder", "ResultExists"]

#: Pipeline stages timed in ``summary.json["timings"]`` (seconds).
STAGES = ("mesh", "assembly", "reduction", "stepping", "output")
#: stages timed only when the scene asks for them (``scheme.step_check``)
OPTIONAL_STAGES = ("step_check",)


#: most probe panels of signals.png (the first probes; every probe is in history.npz/.csv):
#: a bladed disk's probe on every blade has a history per blade
MAX_PROBE_PANELS = 12
#: what each curve of signals.png is, for several contact points
SIGNAL_TITLES = {
    "tip_displacement": "mean normal displacement of the contact points",
    "tip_temperature": "mean temperature rise of the contact points "
    "(summary: signals_max_abs.tip_temperature)",
    "contact_force": "sum over the contact points of impulse / h "
    "(summary: max_total_contact_force; one point: max_contact_force)",
}


def _max_or_none(arr) -> float | None:
    return float(np.max(arr)) if arr is not None and np.size(arr) else None


def _friction_summary(res) -> dict:
    """``max_friction_force`` (N), ``friction_work``, ``heat_to_blade``, ``heat_to_casing`` (J)
    and the Coulomb check of every recorded step (:func:`femrub.contact.friction.coulomb_check`).
    """
    e = res.energy
    ff = res.friction_force
    out = {
        "max_friction_force": float(res.friction_magnitude().max())
        if ff is not None and ff.size
        else 0.0,
        "friction_work": float(e["friction_work"][-1]) if "friction_work" in e else 0.0,
        "heat_to_blade": float(e["friction_heat"][-1]) if "friction_heat" in e else 0.0,
        "heat_to_casing": float(e["heat_to_casing"][-1]) if "heat_to_casing" in e else 0.0,
    }
    if ff is not None and ff.size and res.friction_limit is not None:
        out["coulomb_check"] = res.coulomb  # measured once, with the verdict's
    return out


def signal_measures(signals: dict) -> dict:
    """``{"signals_max_abs": ..., "signals_rms": ...}``: the largest magnitude and the root
    mean square of each recorded signal and probe over the run's rows (in its unit,
    ``summary.json["units"]``; ``None`` for an empty one): what a map reads of a run, with or
    without its ``history.npz``."""
    peak, rms = {}, {}
    for name, arr in signals.items():
        a = np.asarray(arr, dtype=float)
        peak[name] = float(np.abs(a).max()) if a.size else 0.0
        rms[name] = float(np.sqrt(np.mean(a**2))) if a.size else None
    return {"signals_max_abs": peak, "signals_rms": rms}


def run_to_folder(  # noqa: PLR0913 (keyword-only output options)
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
    merge_time: float | None = None,
    claimed: bool = False,
    reduction_error: dict | None = None,
    ran=None,
    step_error: dict | None = None,
    csv_stride: int = 1,
    history_npz: bool = True,
):
    """Run ``stepper`` to ``t_end`` and write the results folder ``out`` (module docstring).

    ``timings`` holds the seconds of the stages before the run (``mesh``, ``assembly``,
    ``reduction``); ``summary.json["timings"]`` adds ``stepping`` (the run without the
    output it streams) and ``output`` (VTK frames, histories, plots). ``n_full``: state dofs
    of the full model when ``stepper.model`` is reduced; ``rotation_speed`` (rad/s) counts the
    ``revolutions`` reached; ``merge_time`` (s) enables the resolution check
    (:func:`~femrub.output.verdict.assess`); ``claimed``: the caller already holds
    :func:`~femrub.output.folder.claim` on ``out``. ``reduction_error``: the estimate of a
    reduced run (:mod:`femrub.reduction.estimate`, with its ``tolerance``), written as
    ``summary.json["reduction_error"]`` and judged by the ``reduction`` rule of
    :mod:`~femrub.output.verdict` (``inaccurate`` above the tolerance); ``step_error``: the
    time-step error estimate (:mod:`femrub.analysis.step_check`), written as
    ``summary.json["time_step_error"]`` and judged by the ``time_step`` rule. ``ran``: ``(results,
    wall seconds)`` of this very run already stepped (``stepper.model`` from its initial state
    to ``t_end`` with ``limits``, e.g. by the reduction error estimate): it is judged and
    written instead of stepped again (its VTK frames from its states, stored every
    ``vtk_stride`` steps). ``csv_stride``:
    ``history.csv`` at one row every that many steps
    (:meth:`~femrub.output.results.Results.save_csv`'s ``every``; ``history.npz`` keeps every
    step), 0: no ``history.csv``; ``history_npz``: False writes no ``history.npz`` (the
    summary's ``signals_max_abs`` and ``signals_rms`` keep each signal's measures). Returns
    the :class:`~femrub.output.results.Results`.
    """
    out = Path(out)
    with nullcontext() if claimed else claim(out, "run", overwrite=overwrite):
        return _run(
            stepper,
            t_end,
            out,
            fields,
            vtk_stride,
            inputs,
            limits,
            progress,
            snapshot,
            plots,
            timings,
            n_full,
            rotation_speed,
            merge_time,
            reduction_error,
            ran,
            step_error,
            (csv_stride, history_npz),
        )


def _frames_of(res, series, contact) -> None:
    """Feed ``series`` the frames of a run already stepped: its states stored at every
    ``series.stride``-th step (``Results.states``), with the impulses of those steps."""
    if res.states is None or not np.allclose(np.diff(res.state_times), series.stride * res.h):
        raise ValueError(
            "run_to_folder: a run already stepped writes VTK frames only from its states "
            f"stored every vtk_stride = {series.stride} steps"
        )
    empty = np.zeros(res.impulse.shape[1])
    for X, t in zip(res.states, res.state_times, strict=True):
        k = int(round((t - res.t[0]) / res.h))
        ff = res.friction_force
        fi = None if ff is None or contact.frames is None else contact.to_local(ff[k]) * res.h
        series(State(k, float(t), X, res.impulse[k], empty, empty, fi))


def _judged(ran, tolerances, merge_time):
    """``(results, wall)`` of a run stepped elsewhere, judged as ``femrub.analysis.run`` judges.

    Its results were judged without these ``tolerances`` and ``merge_time``; the recorder
    ends a run ``ok`` or with a stop status and only the verdict turns ``ok`` into
    ``inaccurate``, so an ``inaccurate`` run is judged again from ``ok``.
    """
    res, wall = ran
    if res.status == "inaccurate":
        res.status, res.message = "ok", ""
    res.states = res.state_times = None  # the estimate's checkpoints, not the run's output
    res.snapshots = []
    return assess(res, tolerances=tolerances, merge_time=merge_time), wall


def _run(  # noqa: PLR0913 (run_to_folder's options passed on)
    stepper,
    t_end,
    out,
    fields,
    vtk_stride,
    inputs,
    limits,
    progress,
    snapshot,
    plots,
    timings,
    n_full,
    rotation_speed,
    merge_time,
    reduction_error,
    ran,
    step_error=None,
    histories=(1, True),
):
    csv_stride = histories[0]
    summary_path = out / "summary.json"
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
    if reduction_error is not None:
        doc["reduction_error"] = reduction_error
    if step_error is not None:
        doc["time_step_error"] = step_error
    _write_json(summary_path, doc)
    series = None
    if fields is not None and vtk_stride:
        from .vtk import VTKSeries

        if hasattr(fields, "vtk_series"):  # several meshes (a bladed disk and its casing)
            series = fields.vtk_series(out / "vtk", model, h=stepper.h, stride=vtk_stride)
        else:
            series = VTKSeries(out / "vtk", model, fields, h=stepper.h, stride=vtk_stride)
    for stale in ("history.csv", "history.npz", "signals.png", "snapshot.png"):
        (out / stale).unlink(missing_ok=True)  # results of an earlier, unfinished run
    history = (
        HistoryCSV(out / "history.csv", every=csv_stride, units=signal_units(model))
        if csv_stride
        else NoHistoryCSV()
    )
    t0 = time.perf_counter()
    tolerances = {"reduction": reduction_error, "time_step": step_error}
    try:
        with interruptible():
            if ran is not None:
                if series is not None:  # its frames, from the states it stored
                    _frames_of(ran[0], series, stepper.model.contact)
                res, wall = _judged(ran, tolerances, merge_time)
            else:
                res = stepper.run(
                    t_end,
                    progress=progress,
                    limits=limits,
                    on_state=series,
                    on_rows=history if csv_stride else None,
                    merge_time=merge_time,
                    tolerances=tolerances,
                )
    except KeyboardInterrupt:  # before the recorder took over: say so, keep the folder
        _write_json(summary_path, {**doc, "status": "interrupted", "message": "interrupted"})
        raise
    finally:
        history.close()
        if series is not None:
            series.close()  # every frame taken is on disk, the writer thread stopped
    if ran is None:
        wall = time.perf_counter() - t0
    finish = partial(
        _finish,
        stepper,
        res,
        out,
        doc,
        series,
        history,
        wall,
        snapshot,
        plots,
        timings,
        rotation_speed,
        summary_path,
        histories,
    )
    return _close(finish, res, out, doc, history, summary_path)


def _close(finish, res, out, doc, history, summary_path):
    """``finish()`` (the final files of a stepped run) with signals held back; a write
    error (a full disk) fails the run with a line naming the file (:func:`_write_failed`);
    a signal received while a finished result was written leaves it finished (a notice
    says so)."""
    if history.error is not None:  # a full disk: the run stopped, its rows are in memory
        res.status, res.message = "failed", describe_os_error(history.error, "write")
    with deferred(reraise=False) as held:
        try:
            res = finish()
        except OSError as exc:
            _write_failed(res, exc, out, doc, summary_path)
    if held and res.status == "interrupted":
        raise KeyboardInterrupt("signal received while writing results")
    if held:  # the result was finished: its files are complete, the status stands
        print(
            f"femrub: signal received while the results were written; they are complete "
            f"(status {res.status}) in {out}/",
            file=sys.stderr,
        )
    return res


def _write_failed(res, exc: OSError, out: Path, doc: dict, summary_path: Path) -> None:
    """After a write error (a full disk) in the final files: status ``failed`` with a line
    naming the file and the fix, femrub's temporaries removed, the summary written if the
    disk takes it (the rows streamed to ``history.csv`` stay)."""
    res.status, res.message = "failed", describe_os_error(exc, "write")
    for name in OUTPUTS["run"]:
        for tmp in (*out.glob(f"{name}.tmp*"), *out.glob(f".{name}.*.tmp")):
            tmp.unlink(missing_ok=True)
    doc.update(
        status=res.status,
        message=res.message,
        steps=res.steps,
        t_reached=float(res.t[-1]) if len(res.t) else 0.0,
    )
    try:
        _write_json(summary_path, doc)
    except OSError:
        print(f"femrub: {summary_path} not written either: {res.message}", file=sys.stderr)


def _finish(  # noqa: PLR0913 (run_to_folder's options passed on)
    stepper,
    res,
    out,
    doc,
    series,
    history,
    wall,
    snapshot,
    plots,
    timings,
    rotation_speed,
    summary_path,
    histories=(1, True),
):
    csv_stride, history_npz = histories
    vtk_wall, vtk_cpu = (series.seconds, series.cpu_seconds) if series is not None else (0.0, 0.0)
    t_out = time.perf_counter()
    if csv_stride and history.received != len(res.t) and history.error is None:  # not streamed
        with naming(out / "history.csv"):
            res.save_csv(out / "history.csv", every=csv_stride)
    if history_npz:
        with naming(out / "history.npz"):
            res.save_npz(out / "history.npz")
    panels = [k for k in ("tip_displacement", "tip_temperature") if k in res.signals]
    panels += [k for k in res.signals if k.startswith(PROBE_PREFIX)][:MAX_PROBE_PANELS]
    if plots:
        savefig(
            tip_panels(
                [(stepper.name, res, {})],
                panels=(*panels, "contact_force"),
                title=f"{stepper.name}, h = {stepper.h:g} s: {res.status}",
                titles=SIGNAL_TITLES if stepper.model.n_contacts > 1 else None,
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
            snapshot_png(
                series.dir / series.frames[-1][1],
                out / "snapshot.png",
                scalars=series.snapshot_scalars,
            )
        except Exception as exc:  # rendering is optional (no OpenGL on the machine)
            doc["snapshot_error"] = f"{type(exc).__name__}: {exc}"
            print(
                f"femrub: snapshot.png not written ({doc['snapshot_error']}); "
                f"open {series.pvd_path} in ParaView instead",
                file=sys.stderr,
            )
    e = res.energy
    stepping_cpu = max(res.cpu_seconds - vtk_cpu, 0.0)
    omega = float(rotation_speed)
    stages = {k: 0.0 for k in STAGES} | dict(timings or {})
    stages.update(stepping=wall - vtk_wall, output=vtk_wall + time.perf_counter() - t_out)
    res.info["timings"] = {k: stages[k] for k in STAGES + OPTIONAL_STAGES if k in stages}
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
        max_total_contact_force=float(res.force.sum(axis=1).max()) if res.force.size else 0.0,
        max_contact_temperature=_max_or_none(res.signals.get("contact_temperature")),
        energy_error=res.energy_error(),
        heat_error=res.heat_error(),
        warnings=[*doc["inputs"].get("build", {}).get("warnings", []), *res.warnings],
        units=res.units(),
        energy={k: float(v[-1]) for k, v in e.items()} if e else {},
        vtk=str(series.pvd_path.relative_to(out)) if series is not None else None,
        vtk_frames=len(series.frames) if series is not None else 0,
    )
    doc.update(_friction_summary(res))
    doc.update(signal_measures(res.signals))
    with naming(summary_path):
        _write_json(summary_path, doc)
    return res
