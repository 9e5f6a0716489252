"""The phase of an orbit's time grid relative to its impacts.

The θ-method's period map runs ``N`` steps from ``t0``; an impact takes its impulse in the
step where the gap closes. While that step stays the same the map is smooth in ``X0`` and
in the parameter; when the closing moves to the neighbouring step the map jumps by
``O(h |ġ|)``. A fixed point whose impacts close near a grid node therefore sits next to a
jump, and Newton's method stalls there. The orbit's start ``t0`` is free (every ``t0``
samples the same periodic orbit), so a branch moves it to put the main impact in the
middle of its step. For a step ``k`` that closes an open gap, the fraction of the step
travelled before contact is, to first order in ``h``::

    φ_k = g_k / (h |ġ_k|)        (g_k > 0, ġ_k < 0: gap and gap velocity before it)  (1)

and the new start is ``t0' = t_k + (φ_k − LEAD) h``: the contact closes in the middle of the
step ``LEAD − 1/2`` of the new grid, near its start, where the step ``h = T(p) / N``
changing with the parameter moves it least.
"""

from __future__ import annotations

import numpy as np

from ..steppers.theta import ThetaMethod

__all__ = ["CENTRED", "LEAD", "new_start"]

#: a main impact closer than this fraction of a step to a grid node moves the start
CENTRED = 0.25
#: the main impact closes at ``t0 + (LEAD − 1/2 + 1/2) h``: in the middle of step 1
LEAD = 1.5


def new_start(model, orbit, h: float) -> tuple | None:
    """``(j, δ)``: the new start is ``t_j + δ`` of ``orbit`` (:class:`~femrub.periodic.period.
    Orbit`), ``0 <= δ < h``, for its largest impulse that closes an open gap (module
    docstring); ``None`` when that impulse already closes in the middle half of step 1, or
    when no impulse closes a gap."""
    c = model.contact
    if c is None or not np.any(orbit.P > 0.0):
        return None
    n = len(orbit.t)
    g = np.asarray(c.gap(orbit.t, orbit.X)).reshape(n, -1)
    gd = np.asarray(c.gap_velocity(orbit.t, orbit.X)).reshape(n, -1)
    closing = (orbit.P[1:] > 0.0) & (g[:-1] > 0.0) & (gd[:-1] < 0.0)
    if not closing.any():
        return None
    k, i = np.unravel_index(np.argmax(np.where(closing, orbit.P[1:], -1.0)), closing.shape)
    phi = min(float(g[k, i] / (h * -gd[k, i])), 1.0)  # Eq. (1)
    if k == 1 and CENTRED <= phi <= 1.0 - CENTRED:
        return None
    shift = (k + phi - LEAD) % (n - 1)  # in steps, from t0
    j = int(np.floor(shift))
    return j, (shift - j) * h


def state_later(model, X, t: float, delta: float, gamma: float, activation) -> np.ndarray:
    """The state ``delta`` (s) after ``X`` at ``t``: one θ-method step of that size."""
    if delta <= 0.0:
        return np.array(X, dtype=float)
    st = ThetaMethod(model, delta, gamma=gamma, activation=activation, t0=t)
    st.restart(np.asarray(X, dtype=float), t)
    return st.step().X.copy()
