"""The checks of a long run on windows of it: references stepped from the run's own states.

A reduction error estimate or time-step check that steps its reference over the whole run
costs a run or two more (three or more with the round-off twin of a sensitive response).
On a long rub (many revolutions) both checks step their reference over :data:`N_WINDOWS`
windows of one revolution instead, spread from the run's start to its end: each reference
window starts from the run's own state there (:class:`~femrub.output.results.Snapshot`: the
state and the wear map or casing heat its contact carries) and is compared with the run over
the same window (:func:`~femrub.reduction.estimate.compare_windows`). A window measures the
error the run makes over it from an exact start, not that error amplified by a sensitive
response afterwards, so no twin is needed: windows of one revolution lie within the
predictability horizon (on Rotor 37 a difference grows tenfold in 1.5 to 5 revolutions,
from round-off). The windows cost :data:`N_WINDOWS` revolutions of the reference; a run
shorter than :data:`N_WINDOWS` / :data:`WINDOW_SHARE` revolutions, or without rotation, is
checked whole.
"""

from __future__ import annotations

import math

import numpy as np

from ..progress import phase
from ..reduction.estimate import DECISIVE, compare_windows

__all__ = ["N_WINDOWS", "WINDOW_SHARE", "estimate_on_windows", "step_windows", "window_plan"]

#: windows of one revolution a long run is checked on
N_WINDOWS = 5
#: ... when they are at most this share of the run
WINDOW_SHARE = 0.25


def window_plan(scene) -> list[tuple[int, int]] | None:
    """The windows ``[(first step, last step)]`` a run of ``scene`` is checked on, or
    ``None`` when it is checked whole (too short, or no rotation)."""
    s, omega = scene["scheme"], abs(scene["loads"]["rotation_speed"])
    if not omega:
        return None
    n = round(s["t_end"] / s["h"])
    w = max(1, round(2.0 * math.pi / omega / s["h"]))
    if N_WINDOWS * w > WINDOW_SHARE * n:
        return None
    starts = np.round(np.linspace(0, n - w, N_WINDOWS)).astype(int)
    return [(int(k), int(k) + w) for k in starts]


def snapshot_steps(plan) -> tuple[int, ...]:
    """The steps whose snapshots the run keeps for ``plan``: each window's ends."""
    return tuple(sorted({k for window in plan or () for k in window}))


def step_windows(stepper, run, plan, *, lift=None, factor: int = 1, limits=None, label=""):
    """The reference over each window of ``plan``: ``stepper`` restarted from ``run``'s
    snapshot at the window's first step (its state through ``lift``), stepped to the time of
    its last step and recorded on the run's steps (``lean = factor``: ``stepper`` steps
    ``factor`` times finer), only compared; its states at both ends. Windows the run did not
    reach are left out."""
    snaps = {s.step: s for s in run.snapshots}
    out = []
    for k0, k1 in plan:
        if k0 not in snaps or k1 not in snaps:
            break
        start = snaps[k0]
        with phase(f"{label}window at t = {start.t:.6g} s"):
            stepper.restart(start.X if lift is None else lift(start.X), start.t, start.history)
            every = (k1 - k0) * factor
            out.append(
                stepper.run(
                    snaps[k1].t, store_every=every, limits=limits, lean=factor, compared=True
                )
            )
    return out


def estimate_on_windows(run, refs, plan, fields_run, fields_ref, norms, lobe: float) -> dict:
    """:func:`~femrub.reduction.estimate.compare_windows`'s measures, the largest decisive
    one as ``estimate``, and what they were measured on."""
    errs = compare_windows(run, refs, plan, fields_run, fields_ref, norms, lobe)
    decisive = [errs[k] for k in DECISIVE if k in errs]
    statuses = [r.status for r in refs]
    return {
        **errs,
        "estimate": float(max(decisive)) if decisive else 0.0,
        "method": (
            f"on {len(refs)} windows of one revolution: the reference stepped from the run's "
            "own state at each window's start, compared over the window"
        ),
        "windows": [[float(r.t[0]), float(r.t[-1])] for r in refs],
        "window": float(lobe),
        "status_run": run.status,
        "status_reference": next((s for s in statuses if s != "ok"), "ok"),
    }
