"""Running a stepper: recorded, checked against stop limits and judged.

:func:`run` drives any pure integrator (:class:`~femrub.steppers.base.Stepper`) to ``t_end``:
it hands the stepper's steps (its :meth:`~femrub.steppers.base.Stepper.advance`, or its
compiled block writer when it has one) to a :class:`~femrub.output.recorder.Recorder`, which
checks them chunk by chunk (non-finite states and energy created from nothing: ``unstable``;
the stop limits of :func:`~femrub.output.limits.run_limits`, on by default:
``diverged-physically``), and judges what it recorded with
:func:`~femrub.output.verdict.assess` (balance tolerances -> ``inaccurate``, resolution).
Whatever stops a run (instability, a stop limit, Ctrl-C, SIGTERM, an exception), the results
computed so far are returned. A run longer than :data:`MAX_STEPS` steps is refused before it
starts (the memory of its histories).
"""

from __future__ import annotations

import numpy as np

from ..output.limits import run_limits
from ..output.recorder import Recorder
from ..output.results import Results, Snapshot
from ..output.verdict import assess
from ..scene.run_checks import fractional_steps
from ..scene.validate import MAX_STEPS
from .options import RunOptions

__all__ = ["MAX_STEPS", "RunOptions", "run", "steps_of", "whole_steps_warning"]


def steps_of(stepper, t_end: float) -> int:
    """Steps of ``stepper`` to ``t_end`` (s), at most :data:`MAX_STEPS`."""
    n = stepper.steps_to(t_end)
    if n > MAX_STEPS:
        raise ValueError(
            f"h = {stepper.h:g} s to t_end = {t_end:g} s gives {n:.3g} steps; at most "
            f"{MAX_STEPS:.0e} allowed (raise h or lower t_end)"
        )
    return n


def run(stepper, t_end: float, options: RunOptions | None = None) -> Results:
    """Integrate ``stepper`` to ``t_end`` (s) and collect its judged
    :class:`~femrub.output.results.Results` (see the module docstring)."""
    o = options or RunOptions()
    t0 = stepper.t
    stepper.measure_works(o.energy and not o.compared)
    try:
        recorder = Recorder(
            stepper.model,
            stepper.h,
            steps_of(stepper, t_end),
            scheme=stepper.name,
            stability_limit=stepper.stability_limit(),
            energy=o.energy,
            limits=run_limits(stepper.model, o.limits, o.default_limits),
            store_every=o.store_every,
            on_state=o.on_state,
            on_rows=o.on_rows,
            label=o.label,
            blowup_check=stepper.blowup_check,
            lean=o.lean,
            compared=o.compared,
            snapshots=o.snapshots,
            take_snapshot=lambda step: _snapshot(stepper, step),
        )
        res = recorder.record(
            stepper.state, stepper.advance, progress=o.progress, block=stepper.block_writer()
        )
    finally:
        stepper.measure_works(False)
    del recorder  # its per-step arrays that the results do not hold: before the checks
    c = stepper.model.contact
    if c is not None and c.carried_state:  # the wear map and casing heat this run left
        res.contact_history = c
    merge_time = None if stepper.locates_events else o.merge_time
    res = assess(res, tolerances=o.tolerances, merge_time=merge_time)
    short = whole_steps_warning(t0, stepper.h, t_end)
    if short:
        res.warnings.append(short)
    return res


def _snapshot(stepper, step: int) -> Snapshot:
    """The stepper's whole state after the run's step ``step``."""
    c = stepper.model.contact
    history = c.history_snapshot() if c is not None else ()
    return Snapshot(step, float(stepper.t), np.array(stepper.X, dtype=float), history)


def whole_steps_warning(t0: float, h: float, t_end: float) -> str | None:
    """A run takes ``round((t_end − t0) / h)`` steps of the constant ``h``: when that is not
    a whole number it ends up to half a step from ``t_end``; the warning says where and
    gives both fixes (a scene refuses such a step before any work: scene/run_checks.py)."""
    off = fractional_steps(t_end - t0, h)
    if off is None:
        return None
    n, _, up = off
    return (
        f"t_end = {t_end:g} s is {n:.6g} steps of h = {h:g} s: the run ended at "
        f"t = {t0 + round(n) * h:.6g} s; for t_end exactly use t_end = {t0 + up * h:.6g} s or "
        f"h = {(t_end - t0) / up:.6g} s"
    )
