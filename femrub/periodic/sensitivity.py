"""The monodromy of the θ-method's period map from the derivatives of its steps.

On a dense model with one frictionless contact on a fixed obstacle (the θ-method's
one-contact path: the paper's bar, an impact oscillator) a step is::

    X_p = T X_k + Y1 s_{k+1} + Y0 s_k,      X_{k+1} = X_p + P_k z                    (1)

with the impulse ``P_k`` of the activation rule (:func:`femrub.contact.theta_block.
impulse_one_code`): ``"position"`` lands the contact on the target gap
``g* = min(g_k, 0) + e max(g_k, 0)``, ``P = (g* − g_p) / g_z``; the velocity rules apply
Newton's law ``P = −(ġ_p + e ġ_k) / w`` (``e = 1`` on a separating contact for
``"paper"``/``"predicted"``); ``"capped"`` takes the smaller. On the contact set of the
orbit (the steps with ``P_k > 0``, the branch of each rule as it ran) the step's Jacobian
is ``J_k = T + z a_kᵀ`` with::

    a_k = (c_k G − Tᵀ G) / g_z,    c_k = 1 (g_k <= 0) or e (g_k > 0)      position law
    a_k = −(Tᵀ G_v + e G_v) / w                                          Newton's law

(``g = g0 + Gᵀ X``, ``ġ = G_vᵀ X``), and the monodromy is ``M = J_{N−1} ⋯ J_1 J_0``. It is
the derivative of the map on the orbit's own contact set, free of the jumps a finite
difference may straddle when a perturbation moves an impact by one step (those jumps are
``O(h |ġ|)``: the map is only piecewise continuous). ``X_p`` is read back from the orbit,
``X_p = X_{k+1} − P_k z``, so the loads need not be evaluated again.
"""

from __future__ import annotations

import numpy as np

from ..contact.theta_block import ONE_RULES

__all__ = ["step_monodromy"]


def _position_rows(g_k, gr, grT, e, gz):
    c = np.where(g_k <= 0.0, 1.0, e)
    return (c[:, None] * gr[None, :] - grT[None, :]) / gz


def _newton_rows(e_k, gv, gvT, w):
    return -(gvT[None, :] + e_k[:, None] * gv[None, :]) / w


def _impulse_rows(st, Xk, Xp, act) -> np.ndarray:
    """``a_k`` (m, N) of Eq. (1)'s rules on the steps ``act`` (module docstring)."""
    code = ONE_RULES[st.activation]
    gr, gv, g0, e = st._gr, st._gv, st._g0, st._e
    T = st._T
    grT, gvT = gr @ T, gv @ T
    g_k, gd_k = g0 + Xk @ gr, Xk @ gv
    if code in (0, 1):
        rows = _position_rows(g_k, gr, grT, e, st._gz)
        if code == 1:  # capped: Newton's law where it is below the position target
            g_p, gd_p = g0 + Xp @ gr, Xp @ gv
            target = np.minimum(g_k, 0.0) + e * np.maximum(g_k, 0.0)
            newton = -(gd_p + e * gd_k) / st._w < (target - g_p) / st._gz
            rows[newton] = _newton_rows(np.full(int(newton.sum()), e), gv, gvT, st._w)
    else:
        e_k = np.where(gd_k > 0.0, 1.0, e) if code in (2, 4) else np.full(g_k.size, e)
        rows = _newton_rows(e_k, gv, gvT, st._w)
    rows[~act] = 0.0
    return rows


def step_monodromy(st, orbit) -> np.ndarray | None:
    """``M`` of the module docstring for the orbit ``orbit`` of the stepper ``st`` (a
    :class:`~femrub.steppers.theta.ThetaMethod`), or ``None`` when its step is not the
    one-contact path (then the finite differences of :mod:`femrub.periodic.shooting`)."""
    if not getattr(st, "_fast", False):
        return None
    X, P = orbit.X, orbit.P[1:, 0]
    Xk = X[:-1]
    Xp = X[1:] - P[:, None] * st._z[None, :]
    act = P > 0.0
    rows = _impulse_rows(st, Xk, Xp, act)
    T, z = st._T, st._z
    M = np.eye(X.shape[1])
    for k in range(P.size):  # the product of Eq. (1)'s step Jacobians
        M = T @ M + np.outer(z, rows[k] @ M) if act[k] else T @ M
    return M
