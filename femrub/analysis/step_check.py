"""A-posteriori time-step error of a run: the same model stepped again at ``h/2``.

A run is trustworthy only if its step is fine enough. ``scheme.step_check = true`` measures
it the way the reduction error is measured (:mod:`femrub.analysis.reduction_check`): by the
difference with a richer run, here the run's own model at half the step, from the same
initial state to the same end time and stop limits. The fine run is recorded coarsened to
the run's steps (``RunOptions.lean = 2``, the rows :func:`coarsen` would keep: its impulses
summed over each pair of steps, its signals at the run's times; fields at the same
checkpoints: :mod:`femrub.output.kept_rows`) as a run only compared
(``RunOptions.compared``: its gaps, friction rows, energy balance and Coulomb check never
evaluated; its status, ``status_reference``, says how it ended) and both are compared with
the estimate's measures
(contact impulse per lobe passage, contact temperature history, displacement and
temperature fields; a round-off twin of the fine run splits a sensitive response into a
pointwise and a statistical part, as :func:`~femrub.reduction.estimate.estimate` does)::

    d = ‖y_h − y_{h/2}‖ / ‖y_{h/2}‖

The steppers converge at order ``p ≈ 1`` on rubs (velocity jumps at impacts, switches of
the contact and friction state, wear: docs/performance.md §2), so the run's own error is
estimated by Richardson's rule with the nominal order :data:`ORDER`::

    e_h ≈ d 2^p / (2^p − 1) = 2 d      (p = 1)

which is what ``estimate`` holds; the verdict rule ``time_step``
(:mod:`femrub.output.verdict`) makes a run above ``scheme.step_tolerance`` ``inaccurate``.
It doubles the stepping cost at least (three times when the twin is needed).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..progress import phase
from ..reduction.estimate import DECISIVE, estimate, field_norms, perturbed
from .reduction_check import SAFETY, lobe_passage
from .windows import estimate_on_windows, snapshot_steps, step_windows, window_plan

__all__ = ["ORDER", "check_step", "coarsen", "full_states"]

#: nominal convergence order of the steppers on nonsmooth rubs (Richardson's factor 2)
ORDER = 1.0
#: checkpoints of the fields compared (as the reduction error estimate)
CHECKPOINTS = 5


def coarsen(res, factor: int):
    """The results ``res`` of a run at ``h / factor`` seen on the steps of ``h``.

    Times and signals every ``factor`` rows; the impulse of each coarse step is the sum of
    the fine impulses in it (so impulses per window and mean forces are preserved); the
    checkpoint states are kept (the fine run stores them at the same times). Every array is
    a copy: none keeps the fine run's per-step arrays alive. A run recorded with
    ``RunOptions.lean = factor`` gives ``coarsen(res, factor).lean()`` without the fine rows.
    """
    factor = int(factor)
    if factor == 1:
        return res
    n = (len(res.t) - 1) // factor
    rows = slice(0, n * factor + 1, factor)
    impulse = res.impulse[1 : n * factor + 1].reshape(n, factor, -1).sum(axis=1)
    return dataclasses.replace(
        res.lean(),
        h=res.h * factor,
        t=res.t[rows].copy(),
        impulse=np.vstack([res.impulse[:1], impulse]),
        gap=res.gap[rows].copy(),
        signals={k: v[rows].copy() for k, v in res.signals.items()},
    )


def full_states(model, full):
    """``X -> full states`` of the rows of ``X`` (states of ``model``): ``Pᵀ (T Xᵀ)`` with
    ``T = model.to_full`` (reduced: the mesh map of ``R``) and ``P = full.to_full`` (the
    full model's injection of its free dofs into the mesh, ``Pᵀ P = I``), i.e. ``R X̄``."""
    if model is full or model.to_full is None or full.to_full is None:
        return lambda X: X
    P, T = full.to_full, model.to_full
    return lambda X: np.asarray(P.T @ (T @ np.asarray(X).T)).T


def _simulate(stepper, t_end, every, limits, fields, lean=0, snapshots=()):
    """Run ``stepper`` to ``t_end``, full states stored every ``every`` steps (``lean``,
    ``snapshots``: :class:`~femrub.analysis.options.RunOptions`')."""
    res = stepper.run(
        t_end, store_every=every, limits=limits, lean=lean, compared=lean > 0, snapshots=snapshots
    )
    return res, fields(res.states)


def check_step(scene, model, full, make_stepper, limits, run=None, reuse_run=True):
    """The run's time-step error estimate (``summary.json["time_step_error"]``).

    Parameters
    ----------
    scene : the scene (``scheme.h``, ``scheme.t_end``, ``scheme.step_tolerance``, the lobe
        passage of the casing).
    model : the model that runs (reduced or full); ``full``: the full model (field norms).
    make_stepper : ``(model, h) -> stepper`` of the scene's scheme at step ``h``.
    limits : the run's stop limits.
    run : ``(results, full states at checkpoints)`` of the run at ``h`` when already stepped
        (the reduction error estimate's run of these sizes), else ``None``: stepped here.
    reuse_run : whether the caller may keep the run at ``h`` stepped here as the scene's run
        (``False``: it is only compared, recorded lean).

    Returns
    -------
    (dict, run, wall) : the estimate (:func:`~femrub.reduction.estimate.estimate`'s
        measures, ``difference``: the largest decisive one, ``estimate``: Richardson's error
        of the run, ``tolerance``, ``h``, ``reference_h``, ``order``, ``seconds``), the run at
        ``h`` (its results and states) and the wall seconds of that run when stepped here
        (``None`` when given): the caller may keep it as the scene's run.
    """
    t0 = time.perf_counter()
    s = scene["scheme"]
    h, t_end, tol = s["h"], s["t_end"], s["step_tolerance"]
    fields = full_states(model, full)
    fine_h = 0.5 * h
    st = make_stepper(model, fine_h)
    every = max(1, st.steps_to(t_end) // (2 * CHECKPOINTS))  # of the run at h
    plan = window_plan(scene) if st.restartable else None
    wall = None
    if run is None:
        with phase(f"time-step check: run at h = {h:g} s"):
            w0 = time.perf_counter()
            # checked on windows, its states at the VTK frames' stride: it may be the run
            stride = scene["outputs"]["vtk_stride"] if plan is not None else 0
            lean = 0 if reuse_run or stride else 1  # whole when it may be the run
            snaps = snapshot_steps(plan)
            st_h = make_stepper(model, h)
            run = _simulate(st_h, t_end, stride or every, limits, fields, lean, snaps)
            wall = time.perf_counter() - w0
    window = lobe_passage(scene)
    if plan is not None and set(snapshot_steps(plan)) <= {s.step for s in run[0].snapshots}:
        refs = step_windows(
            st, run[0], plan, factor=2, limits=limits, label="time-step check: h/2, "
        )
        err = estimate_on_windows(run[0], refs, plan, fields, fields, field_norms(full), window)
        fine_status = err["status_reference"]
    else:
        every = _stored_every(run[0], every)
        err, fine_status = _whole(scene, model, full, st, make_stepper, limits, run, fields, every)
    for key in ("sizes", "reference_sizes", "status_run", "status_reference"):
        err.pop(key, None)
    split = "predictability_horizon" in err
    measures = {k: err[k] for k in DECISIVE if k in err}
    err.update(
        difference=err["estimate"],
        estimate=_richardson(err["estimate"]),
        decided_by="statistics after the predictability horizon"
        if split
        else max(measures, key=measures.get, default=""),
        method="Richardson (order 1) on the difference to the same model at h/2"
        + (f"; {err['method']}" if split or "windows" in err else ""),
        h=h,
        reference_h=fine_h,
        order=ORDER,
        tolerance=tol,
        status_reference=fine_status,
        seconds=time.perf_counter() - t0,
    )
    return err, run, wall


def _stored_every(res, default: int) -> int:
    """Every how many steps ``res`` stored its states (``default`` when it stored fewer than
    two): the reference at ``h/2`` stores its states at the same times."""
    t = res.state_times
    if t is None or len(t) < 2:
        return default
    return max(1, int(round((t[1] - t[0]) / res.h)))


def _whole(scene, model, full, fine_stepper, make_stepper, limits, run, fields, every):
    """The estimate of the run against the model stepped at ``h/2`` (``fine_stepper``) over
    the whole run (and its round-off twin when the difference is large), and how that run
    ended."""
    s = scene["scheme"]
    fine_h, t_end, tol = 0.5 * s["h"], s["t_end"], s["step_tolerance"]
    with phase(f"time-step check: run at h/2 = {fine_h:g} s") as p:
        fine = _simulate(fine_stepper, t_end, 2 * every, limits, fields, lean=2)
        p["detail"] = f"{fine[0].steps} steps"
    window, label = lobe_passage(scene), ()
    err = estimate((label, *run), (label, *fine), full, window=window)
    if _richardson(err["estimate"]) > SAFETY * tol:  # how sensitive is the response?
        with phase(f"time-step check: twin at h/2 = {fine_h:g} s"):
            twin = _simulate(
                make_stepper(perturbed(model), fine_h), t_end, 2 * every, limits, fields, lean=2
            )
        err = estimate((label, *run), (label, *fine), full, window=window, twin=twin, tolerance=tol)
    return err, fine[0].status


def _richardson(difference: float) -> float:
    """Error of the run at ``h`` from its difference with the run at ``h/2`` (order ORDER)."""
    r = 2.0**ORDER
    return float(difference * r / (r - 1.0))
