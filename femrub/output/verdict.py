"""The one place where a finished run's status is decided after the recorder's checks.

The recorder ends a run as ``unstable`` (blow-up), ``diverged-physically`` (a stop limit),
``interrupted`` or ``failed``. A run it ends as ``ok`` is then judged here, rule by rule
(:data:`RULES`); the first rule that fires sets the status and the message. Each rule is
``rule(results, tolerances) -> message or None``:

* ``energy_balance``: the mechanical balance residual relative to the energy scale of the
  run (``Results.energy_error``) exceeds ``tolerances["energy"]`` -> ``"inaccurate"``;
* ``heat_balance``: the same for the heat balance and ``tolerances["heat"]``;
* ``reduction``: the a-posteriori estimate of a reduced run, ``tolerances["reduction"]``
  (the dict of :func:`femrub.reduction.estimate.estimate` with its ``tolerance``, as
  ``summary.json["reduction_error"]``), above its tolerance -> ``"inaccurate"``; also when
  the reduced dynamics can create energy: its largest relative energy growth rate
  (``energy_growth_rate``, 1/s) times the run's duration above ``tolerances["energy"]``;
* ``time_step``: the run's estimated time-step error (``tolerances["time_step"]``: the dict
  of :func:`femrub.analysis.step_check.check_step` with its ``tolerance``, as
  ``summary.json["time_step_error"]``) above its tolerance -> ``"inaccurate"``;
* ``coulomb``: the recorded friction forces break Coulomb's law (outside the cone, not on it
  while sliding, or not opposite to the slip velocity) beyond ``tolerances["coulomb"]``
  (relative, :func:`femrub.contact.friction.coulomb_check`) -> ``"inaccurate"``.

A lean record (``RunOptions.lean = k``, :mod:`femrub.output.kept_rows`) keeps neither the
energy balance nor the friction rows; the balance and Coulomb rules read the same measures
taken on its rows as they were recorded (``Results.checks``). A run only compared
(``RunOptions.compared``) takes none: both rules pass it (its status says how it ended).

* ``resolution``: contact episodes (impulses less than ``merge_time`` apart form one
  episode) resolved by fewer than :data:`UNRESOLVED_STEPS` steps (median over the
  episodes) -> ``"inaccurate"`` (on the paper case, 2 steps per episode at h = 5e-3 s
  halve the tip temperature); the message names the step that would resolve them.

Warnings do not change the status; they are listed in ``Results.warnings`` (and
``summary.json["warnings"]``):

* ``resolution``: contact episodes resolved by fewer than :data:`MIN_CONTACT_STEPS` steps
  (median); the warning names the step that would resolve them. Steppers that locate the
  contact events inside a step (``Stepper.locates_events``) skip both resolution checks.

A new rule (e.g. the reduction error of a reduced model) is a function appended to
:data:`RULES`.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "MIN_CONTACT_STEPS",
    "UNRESOLVED_STEPS",
    "RULES",
    "STATUSES",
    "TOLERANCES",
    "assess",
    "coulomb_message",
    "resolution_warning",
]

#: every status a run can end with
STATUSES = ("ok", "inaccurate", "unstable", "diverged-physically", "interrupted", "failed")
#: default tolerances of the balance residuals (relative to the run's energy / heat scale)
TOLERANCES = {"energy": 0.05, "heat": 0.05, "coulomb": 1e-8}
#: fewest steps per contact episode (median) before a resolution warning
MIN_CONTACT_STEPS = 20
#: fewer steps per contact episode (median) than this make a run ``inaccurate``
UNRESOLVED_STEPS = 5


def _balance(kind: str):
    def rule(res, tol):
        err = res.energy_error() if kind == "energy" else res.heat_error()
        bound = tol.get(kind)
        if bound is None or not math.isfinite(err) or err <= bound:
            return None
        return (
            f"{kind} balance residual {err:.3g} exceeds the tolerance {bound:g} "
            "(relative to the run's scale): refine the time step or enlarge the reduced basis"
        )

    rule.__name__ = f"{kind}_balance"
    return rule


def reduction(res, tol):
    """The reduced model's estimated error exceeds ``reduction.tolerance``."""
    err = tol.get("reduction")
    if not err:
        return None
    growth = err.get("energy_growth_rate", 0.0) * float(res.t[-1] - res.t[0])
    if growth > tol.get("energy", math.inf):
        return (
            f"the reduced model can create energy (growth exp({growth:.3g}) over the run, "
            "reduction_error.energy_growth_rate): use reduction.projection = "
            "'petrov-galerkin' or a full model"
        )
    est, bound = err.get("estimate", 0.0), err.get("tolerance")
    if bound is None or est <= bound:
        return None
    return (
        f"estimated reduction error {100 * est:.3g} % exceeds reduction.tolerance "
        f"{100 * bound:.3g} %: raise the reduction sizes or use reduction.method = 'auto'"
    )


def time_step(res, tol):
    """The run's estimated time-step error exceeds ``scheme.step_tolerance``
    (``scheme.step_check``, :mod:`femrub.analysis.step_check`)."""
    err = tol.get("time_step")
    if not err:
        return None
    est, bound = err.get("estimate", 0.0), err.get("tolerance")
    if bound is None or est <= bound:
        return None
    h = err.get("h", res.h)
    order = err.get("order", 1.0)
    # the step whose error the same rate would bring to the tolerance (never above h/2)
    needed = h * min(0.5, (bound / est) ** (1.0 / order))
    return (
        f"estimated time-step error {100 * est:.3g} % ({err.get('decided_by', '?')}: twice "
        f"the difference to the run at h/2) exceeds scheme.step_tolerance {100 * bound:.3g} "
        f"%: use scheme.h <= {needed:.3g} s if the error falls as h^{order:g} (the check "
        "tells)"
    )


def coulomb_message(check: dict | None, bound: float) -> str | None:
    """Why a :func:`~femrub.contact.friction.coulomb_check` fails at ``bound``, or ``None``."""
    if not check:
        return None
    worst = max(check["cone"], check["slip_equality"], check["direction"])
    if worst <= bound and check["force_without_normal"] == 0.0:
        return None
    return (
        f"Coulomb law violated beyond {bound:g} (cone {check['cone']:.2g}, sliding "
        f"{check['slip_equality']:.2g}, direction {check['direction']:.2g})"
    )


def _coulomb(res, tol):
    bound = tol.get("coulomb")
    return None if bound is None else coulomb_message(res.coulomb, bound)


#: status rules applied in order to a run the recorder ended as ``ok``
RULES = [_balance("energy"), _balance("heat"), reduction, time_step, _coulomb]


def _episodes(res, merge_time: float) -> list[int]:
    """Steps spanned by each contact episode (impulses less than ``merge_time`` apart)."""
    on = np.flatnonzero(np.any(res.impulse > 0.0, axis=1)) if res.impulse.size else []
    if len(on) == 0:
        return []
    gap_steps = max(1, int(round(merge_time / res.h)))
    breaks = np.flatnonzero(np.diff(on) > gap_steps)
    starts = np.r_[on[0], on[breaks + 1]]
    ends = np.r_[on[breaks], on[-1]]
    last = len(res.t) - 1
    return [int(e - s + 1) for s, e in zip(starts, ends) if e < last]  # cut-off one dropped


def _median_steps(res, merge_time: float) -> float:
    return float(np.median(_episodes(res, merge_time)))


def resolution_warning(res, merge_time: float | None) -> str | None:
    """Warning when contact episodes are resolved by too few steps (module docstring)."""
    if merge_time is None or not merge_time > 0:
        return None
    steps = _episodes(res, merge_time)
    if not steps:
        return None
    median = float(np.median(steps))
    if median >= MIN_CONTACT_STEPS:
        return None
    h_needed = res.h * median / MIN_CONTACT_STEPS
    e = math.floor(math.log10(h_needed))
    h_text = f"{math.floor(h_needed / 10**e) * 10**e:.1g}"
    return (
        f"contact episodes are resolved by {median:.0f} steps (median of {len(steps)}); "
        f"results may be off by tens of percent: use scheme.h <= {h_text} s "
        f"(>= {MIN_CONTACT_STEPS} steps per episode)"
    )


def assess(res, *, tolerances: dict | None = None, merge_time: float | None = None):
    """Judge a run in place: status rules (``ok`` -> ``inaccurate``) and warnings.

    Parameters
    ----------
    res : :class:`~femrub.output.results.Results`.
    tolerances : ``{"energy": ..., "heat": ...}`` overriding :data:`TOLERANCES` (``None``
        as a value switches a rule off); ``"reduction"``: the error estimate of a reduced
        run (with its ``tolerance``).
    merge_time : impulses closer than this (s) form one contact episode; ``None`` skips
        the resolution check.
    """
    tol = {**TOLERANCES, **(tolerances or {})}
    if res.status == "ok":  # every rule that fails is named, in the order of RULES
        reasons = [why for why in (rule(res, tol) for rule in RULES) if why]
        if reasons:
            res.status, res.message = "inaccurate", "; ".join(reasons)
    if res.status in ("ok", "inaccurate"):
        warn = resolution_warning(res, merge_time)
        if warn and res.status == "ok" and _median_steps(res, merge_time) < UNRESOLVED_STEPS:
            res.status, res.message = "inaccurate", warn
        elif warn:
            res.warnings.append(warn)
    return res
