"""The reduction error estimate and the automatic sizes: reduced models stepped and compared.

:mod:`femrub.reduction` builds reduced models only (:func:`~femrub.reduction.sizes.prepare`
and :func:`~femrub.reduction.sizes.finish`) and compares given results
(:func:`~femrub.reduction.estimate.estimate`); here the runs are made. With the scene's
stepper, :func:`reduce_checked` picks the sizes a posteriori: the sub-basis models of
:func:`~femrub.reduction.sizes.ladder` (``n_uv = n_θ = n``) are stepped in increasing order
and the first whose estimated error (against the reductor's largest model) is within
:data:`SAFETY` × ``reduction.tolerance`` is kept. With given sizes (``"craig-bampton"``)
the reductor is built at :func:`~femrub.reduction.estimate.reference_sizes` and the run's
model is one of its sub-bases, so its error is estimated too (``report["error"]``). Both
models stop at the run's stop limits (the estimate covers what the run itself can reach);
a sensitive response is measured by a round-off twin of the reference (:func:`twin`).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..contact.casing import lobe_passing_frequency
from ..progress import phase
from ..reduction.estimate import estimate, field_norms, perturbed
from ..reduction.sizes import finish, ladder, prepare, reduce_model
from .windows import estimate_on_windows, snapshot_steps, step_windows, window_plan

__all__ = ["SAFETY", "lobe_passage", "reduce_checked", "simulate", "twin"]

#: ``"auto"`` keeps the first size whose estimate is within this share of the tolerance.
SAFETY = 0.5


def lobe_passage(scene) -> float:
    """Duration (s) of one lobe passage of the casing (0 without lobes or rotation)."""
    omega = scene["loads"]["rotation_speed"]
    if scene.get("rotor.sectors") is not None:  # a bladed disk: the casing ring's lobes
        lobes = scene["casing"]["ring"]["lobes"]
        return 2.0 * np.pi / (lobes * omega) if lobes and omega > 0 else 0.0
    w = lobe_passing_frequency(scene["contact"]["casing"], omega)
    return 2.0 * np.pi / w if w else 0.0


def simulate(
    reductor,
    sizes,
    make_stepper,
    t_end,
    checkpoints=5,
    limits=None,
    twin=False,
    lean=0,
    snapshots=(),
    store_every=0,
):
    """Step ``reductor.reduce(*sizes)``; return the results and the full states stored.

    ``limits``: the run's stop limits: the estimate compares the models over what the run
    itself can reach, not past a physical stop. ``twin``: the initial state perturbed
    (:func:`~femrub.reduction.estimate.perturbed`). ``lean = 1``: a run that is only
    compared, recorded with what :func:`~femrub.reduction.estimate.estimate` reads
    (``RunOptions.lean`` and ``compared``: no balance, Coulomb check, gaps or slip rows;
    stopped by the stop limits as the run is). ``snapshots``: ``RunOptions.snapshots``;
    ``store_every``: the states stored every that many steps instead of at ``checkpoints``.
    """
    what = "twin" if twin else "run"
    with phase(f"reduction error estimate: {what} of sizes {list(sizes)} to {t_end:g} s") as p:
        m = reductor.reduce(*sizes)
        res, states = _simulate(
            perturbed(m) if twin else m,
            reductor,
            sizes,
            make_stepper,
            t_end,
            checkpoints,
            limits,
            lean,
            snapshots,
            store_every,
        )
        p["detail"] = f"{res.steps} steps, {m.n_dofs} coordinates"
    return res, states


def _simulate(
    m, reductor, sizes, make_stepper, t_end, checkpoints, limits, lean, snapshots=(), store_every=0
):
    st = make_stepper(m)
    every = store_every or max(1, st.steps_to(t_end) // checkpoints)
    res = st.run(
        t_end, store_every=every, limits=limits, lean=lean, compared=lean > 0, snapshots=snapshots
    )
    return res, reductor.reconstruct(res.states, *sizes)


def twin(reductor, sizes, make_stepper, t_end, checkpoints=5, limits=None, lean=0):
    """:func:`simulate` with the displacement perturbed by
    :data:`~femrub.reduction.estimate.PERTURBATION` (m)."""
    return simulate(reductor, sizes, make_stepper, t_end, checkpoints, limits, True, lean)


def _timed(*args, **kw):
    """:func:`simulate`, with its wall seconds appended."""
    t0 = time.perf_counter()
    return (*simulate(*args, **kw), time.perf_counter() - t0)


def _largest(err, tried) -> dict:
    """The estimate of the largest model: its difference to the next smaller one tried."""
    if not tried:
        return {"estimate": 0.0, "note": "the run's model is the reference (no estimate)"}
    return dict(
        err,
        judged="largest model: difference to "
        f"the next smaller one {tried[-1]['sizes']} (pessimistic)",
    )


def checked_sizes(
    red, model, want, make_stepper, scene, report, log, limits, on_run=None, reuse_run=True
):
    """Sizes to run and their a-posteriori estimate (``report["error"]``).

    ``want``: the sizes asked for (``None`` for ``"auto"``: the smallest of
    :func:`~femrub.reduction.sizes.ladder` whose estimate is within ``SAFETY × tolerance``).
    The reference is the reductor's largest model; the largest model itself is judged by its
    difference to the next smaller one. ``on_run(results, seconds, full states)`` receives
    the estimate's run of the chosen sizes (the run itself: same model, stepper and initial
    state, stepped to ``t_end`` with ``limits``; its states at the estimate's checkpoints,
    reconstructed). ``reuse_run = False``: the caller steps the scene's run again (e.g. to
    write VTK frames as it steps), so every run here is only compared (recorded lean).
    """
    t0 = time.perf_counter()
    tol, t_end = scene["reduction"]["tolerance"], scene["scheme"]["t_end"]
    window = lobe_passage(scene)
    most = (red.n_uv, red.n_theta)
    # a run the caller does not reuse (it steps the scene's run again): every run here
    # recorded lean (only what estimate() reads, so that the runs it holds together stay
    # small, and none of the checks of a run's own verdict); otherwise those that are never
    # the run. A run that carries a history outside X (wear, casing heat) hands it on with
    # its results (``Results.contact_history``).
    whole = reuse_run
    plan = None if want is None or want == most else window_plan(scene)
    if plan is not None:
        ref_stepper = make_stepper(red.reduce(*most))
        if ref_stepper.restartable:
            *kept, err = _on_windows(
                red, model, want, ref_stepper, make_stepper, scene, limits, plan
            )
            if len(err["windows"]) == len(plan):
                tried = [{"sizes": list(want), "estimate": err["estimate"]}]
                return _chosen(want, err, tried, kept, tol, report, log, on_run, t0)
            # the run stopped before its last window (a stop limit): checked whole below
    cands = [want] if want is not None else ladder(most)
    lean = int(not whole or (want is not None and want != most))  # the reference
    *ref, ref_wall = _timed(red, most, make_stepper, t_end, limits=limits, lean=lean)
    chosen, err, tried, tw = most, None, [], None
    kept = (ref[0], ref_wall, ref[1])
    for c in cands:
        if c == most:
            break
        *run, wall = _timed(red, c, make_stepper, t_end, limits=limits, lean=int(not whole))
        err = estimate((c, *run), (most, *ref), model, window=window)
        if err["estimate"] > SAFETY * tol:  # measure how sensitive the response is
            tw = tw or twin(red, most, make_stepper, t_end, limits=limits, lean=1)
            err = estimate((c, *run), (most, *ref), model, window=window, twin=tw, tolerance=tol)
        tried.append({"sizes": list(c), "estimate": err["estimate"]})
        if want is not None or err["estimate"] <= SAFETY * tol:
            chosen, kept = c, (run[0], wall, run[1])
            break
    if chosen == most:
        err = _largest(err, tried)
    return _chosen(chosen, err, tried, kept, tol, report, log, on_run, t0)


def _chosen(chosen, err, tried, kept, tol, report, log, on_run, t0):
    """Report the estimate of the sizes ``chosen``, hand their run (``kept``: results, wall
    seconds, full states) to ``on_run``; return the sizes."""
    err.update(tolerance=tol, tried=tried, seconds=time.perf_counter() - t0)
    report["error"] = err
    if on_run is not None:
        on_run(*kept)
    if log:
        log(f"reduction error estimate {100 * err['estimate']:.2g} % at sizes {list(chosen)}")
    return chosen


def _on_windows(red, model, sizes, ref_stepper, make_stepper, scene, limits, plan):
    """The run of ``sizes`` (its snapshots kept at the windows' ends; recorded whole, its
    states stored at the scene's VTK stride, so that it is the scene's run even when that
    writes frames) and its estimate on the windows of ``plan`` against the reductor's largest
    model (``ref_stepper``): ``(results, wall seconds, full states, estimate)``."""
    most = (red.n_uv, red.n_theta)
    s = scene["scheme"]
    stride = scene["outputs"]["vtk_stride"]  # the frames' states: written from the run
    res, states, wall = _timed(
        red,
        sizes,
        make_stepper,
        s["t_end"],
        limits=limits,
        snapshots=snapshot_steps(plan),
        store_every=stride,
    )
    refs = step_windows(
        ref_stepper,
        res,
        plan,
        lift=lambda X: red.lift(X, *sizes),
        limits=limits,
        label=f"reduction error estimate: sizes {list(most)}, ",
    )
    err = estimate_on_windows(
        res,
        refs,
        plan,
        lambda X: red.reconstruct(X, *sizes),
        lambda X: red.reconstruct(X, *most),
        field_norms(model),
        lobe_passage(scene),
    )
    err.update(
        sizes=list(sizes),
        reference_sizes=list(most),
        checkpoints=[float(x) for x in res.state_times],
    )
    return res, wall, states, err


def reduce_checked(
    model,
    scene,
    log=None,
    make_stepper=None,
    reductor=None,
    limits=None,
    on_run=None,
    stiffness=None,
    reuse_run=True,
    on_bases=None,
):
    """Reduce ``model`` as ``scene["reduction"]`` asks; return ``(model, reductor, report)``.

    Without ``make_stepper``: :func:`~femrub.reduction.sizes.reduce_model` (a-priori sizes).
    With it (``model -> stepper`` of the scene's scheme) the run's error is estimated
    (``report["error"]``) and ``"auto"`` picks the sizes from that estimate
    (:func:`checked_sizes`). ``reductor``, ``stiffness``: see
    :func:`~femrub.reduction.sizes.prepare` (a reused reductor: only the estimate runs
    again). ``limits``: the run's stop limits, applied to the estimate's runs.
    ``on_run(results, seconds, states)``: called with the estimate's run of the returned
    model's sizes (its :class:`~femrub.output.results.Results`, judged without the reduction
    rule, with the history its contact carried outside ``X``, and its wall time), which is
    the scene's run: the caller need not step it again (lean, and to be stepped again, when
    ``reuse_run`` is false: the caller steps the run again). ``on_bases(reductor)``: called
    with the reductor once its bases are built, before any run (e.g. to store them: with
    given sizes the reductor is then released for the checks).
    """
    if make_stepper is None or scene["reduction"]["method"] == "none":
        return reduce_model(model, scene, log, reductor, stiffness)
    prepared = prepare(model, scene, log, reductor, stiffness, reference=True)
    if on_bases is not None:
        on_bases(prepared.reductor)
    prepared = _models_made(prepared)
    red, report = prepared.reductor, prepared.report
    sizes = checked_sizes(
        red, model, prepared.want, make_stepper, scene, report, log, limits, on_run, reuse_run
    )
    return finish(prepared, sizes), red, report


def _models_made(prepared):
    """Given sizes: their model and the reference's made, the reductor released
    (:meth:`~femrub.reduction.craig_bampton.ThermoelasticCraigBampton.released`: the left
    basis, a Petrov–Galerkin projection's, is not held through the estimate's runs). The
    ``"auto"`` ladder projects as it goes: kept as it is."""
    red, want = prepared.reductor, prepared.want
    if want is None:
        return prepared
    red.reduce(*want)
    red.reduce(red.n_uv, red.n_theta)
    return dataclasses.replace(prepared, reductor=red.released())
