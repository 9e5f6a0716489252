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

**Impact time.** Under a velocity rule the state after the step that closes an open gap
does not depend on where in the step the gap closes, so ``J_k`` misses how the impact time
moves with the state: across grid nodes that dependence shows up only as the jumps. The
orbit's monodromy as a flow with impacts has it, through the saltation matrix
``S = R' + (f⁺ − R' f⁻) nᵀ / (nᵀ f⁻)`` (Leine & Nijmeijer, *Dynamics and Bifurcations of
Non-Smooth Mechanical Systems*, Springer 2004, Sec. 7.3; ``R`` the impact law, ``f`` the
vector field, ``n = G``). With the step's own quantities (``A⁻¹ B ≈ (T − I) / h``, the
velocity jump ``z P_k``, the gap acceleration before contact ``(ġ_p − ġ_k) / h``) and the
impact time ``t_k − g_k / ġ_k`` to first order, this adds to ``J_k``::

    J_k += c_k r_kᵀ,   c_k = [(T − I) z P_k + (1 + e) z (ġ_p − ġ_k) / w] / h,
                       r_k = G / ġ_k − (g_k / ġ_k²) G_v                              (2)

on each step that closes an open gap (``g_k > 0``, ``P_k > 0``) at a resolved approach
velocity (``−ġ_k > |ġ_p − ġ_k|``: faster than the step changes it; not a grazing one) under
``"paper"``, ``"plain"`` or ``"predicted"``, and after which the contact opens (a bounce).
A landing that the next step holds (a plastic impact onto a sustained contact) leaves the
contact on the obstacle wherever in its step it landed: the product of Eq. (1) is then the
orbit's monodromy (on a clamped rod and a damped oscillator held on a wall it equals the
decay of perturbations in time integration; Eq. (2) there would be wrong). Newton keeps
Eq. (1) alone, the exact derivative of the map it solves; the Floquet multipliers and the
branch's tangent take Eq. (2), the orbit's monodromy up to ``O(h)`` (a fold of an
impacting branch then shows a real multiplier at +1 and a turning tangent).
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
    oc = st.one_contact
    gr, gv, g0, e = oc.gr, oc.gv, oc.g0, oc.e
    grT, gvT = gr @ oc.T, gv @ oc.T
    g_k, gd_k = g0 + Xk @ gr, Xk @ gv
    if code in (0, 1):
        rows = _position_rows(g_k, gr, grT, e, oc.gz)
        if code == 1:  # capped: Newton's law where it is below the position target
            g_p, gd_p = g0 + Xp @ gr, Xp @ gv
            target = np.minimum(g_k, 0.0) + e * np.maximum(g_k, 0.0)
            newton = -(gd_p + e * gd_k) / oc.w < (target - g_p) / oc.gz
            rows[newton] = _newton_rows(np.full(int(newton.sum()), e), gv, gvT, oc.w)
    else:
        e_k = np.where(gd_k > 0.0, 1.0, e) if code in (2, 4) else np.full(g_k.size, e)
        rows = _newton_rows(e_k, gv, gvT, oc.w)
    rows[~act] = 0.0
    return rows


def _saltation(st, Xk, Xp, P, act):
    """Columns ``c_k`` (m, N) and rows ``r_k`` (m, N) of Eq. (2) on the steps that close an
    open gap under a velocity rule (zero elsewhere)."""
    oc, h = st.one_contact, st.h
    gr, gv, g0, e, w, z = oc.gr, oc.gv, oc.g0, oc.e, oc.w, oc.z
    g_k, gd_k, gd_p = g0 + Xk @ gr, Xk @ gv, Xp @ gv
    # a resolved approach: faster than the step changes it (a grazing one has no impact
    # time to first order, and its 1 / ġ_k would be the map's noise, not its slope)
    closing = act & (g_k > 0.0) & (gd_k < -np.abs(gd_p - gd_k))
    # ... after which the contact opens: a landing that the next step holds (a plastic
    # impact onto a sustained contact) leaves the tip on the obstacle whatever its time
    closing &= ~np.roll(act, -1)
    cols, rows = np.zeros_like(Xk), np.zeros_like(Xk)
    if ONE_RULES[st.activation] < 2 or not closing.any():
        return cols, rows
    T = oc.T
    jump = P[closing, None] * ((T - np.eye(T.shape[0])) @ z)[None, :]
    accel = (1.0 + e) * ((gd_p - gd_k)[closing] / w)[:, None] * z[None, :]
    cols[closing] = (jump + accel) / h
    gdc = gd_k[closing, None]
    rows[closing] = gr[None, :] / gdc - (g_k[closing, None] / gdc**2) * gv[None, :]
    return cols, rows


def step_monodromy(st, orbit, saltation: bool = False) -> np.ndarray | None:
    """``M`` of the module docstring for the orbit ``orbit`` of the stepper ``st`` (a
    :class:`~femrub.steppers.theta.ThetaMethod`), or ``None`` when its step is not the
    one-contact path (then the finite differences of :mod:`femrub.periodic.shooting`).
    ``saltation``: with the impact-time terms of Eq. (2) on the steps where a velocity rule
    closes an open gap."""
    oc = getattr(st, "one_contact", None)
    if oc is None:
        return None
    X, P = orbit.X, orbit.P[1:, 0]
    Xk = X[:-1]
    Xp = X[1:] - P[:, None] * oc.z[None, :]
    act = P > 0.0
    rows = _impulse_rows(st, Xk, Xp, act)
    cols, times = _saltation(st, Xk, Xp, P, act) if saltation else (None, None)
    T, z = oc.T, oc.z
    M = np.eye(X.shape[1])
    for k in range(P.size):  # the product of Eq. (1)'s step Jacobians
        Mk = T @ M + np.outer(z, rows[k] @ M) if act[k] else T @ M
        if saltation and times[k].any():
            Mk += np.outer(cols[k], times[k] @ M)
        M = Mk
    return M
