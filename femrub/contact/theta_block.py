"""Compiled blocks of θ-method steps on dense models, and the one-contact impulse.

A run's steps are recorded in chunks (:mod:`femrub.output.recorder`); on a dense model
whose contact terms do not depend on the run's history (no wear, no casing heat, constant
heat coefficient, no ``"power"`` heat law; those with a history:
:mod:`femrub.contact.rub_block`, on :func:`friction_step`)
:class:`~femrub.steppers.theta.ThetaMethod` advances a whole chunk with one call of a
kernel below, writing each step's state and
impulses into the recorder's rows. The step is the θ-method's (paper Eq. 16a)::

    X_p     = T X_k + Y1 s_{k+1} + Y0 s_k          free prediction (T = I + D⁻¹ h B)
    X_{k+1} = X_p + Z P                             Z = D⁻¹ H (α folded into H's columns)

with the impulse ``P`` of the contact algebra: the closed form of one frictionless contact
(:func:`impulse_one_code`, the paper's prox formula Eq. 25b inside the activation rules of
:mod:`femrub.contact.activation`), or the frictional active-set fixed point
:func:`femrub.contact.coulomb.frictional_fixed_point` on the local rows
``[g, ġ, w_t] = S X + o(t)`` (``o``: the casing terms, evaluated by the caller for the whole
chunk). These are the same functions the per-step path calls: there is no second copy of
the algebra, and with ``NUMBA_DISABLE_JIT=1`` everything runs as Python.
"""

from __future__ import annotations

import numpy as np

from .coulomb import frictional_fixed_point
from .jit import njit
from .wear_map import entry_bounds

__all__ = [
    "ONE_RULES",
    "impulse_one_code",
    "one_contact_block",
    "friction_step",
    "friction_block",
]

#: codes of the activation rules for :func:`impulse_one_code`
ONE_RULES = {"position": 0, "capped": 1, "paper": 2, "plain": 3, "predicted": 4}


@njit
def impulse_one_code(code, g_k, gd_k, g_p, gd_p, w, gz, e, h, gamma):
    """Impulse of a single contact under rule ``code`` (:data:`ONE_RULES`).

    ``w = ∂ġ_{k+1}/∂P > 0``, ``gz = ∂g_{k+1}/∂P > 0``. ``"position"``: Signorini at
    ``t_{k+1}`` relative to ``g* = min(g_k, 0) + e max(g_k, 0)``, ``P = max(0, (g* − g_p)/gz)``;
    ``"capped"``: Newton's law ``P = −(ġ_p + e ġ_k)/w`` capped at that; the others: Newton's
    law on the active contact (``e = 1`` when separating), active by the rule's test.
    """
    if code == 0 or code == 1:
        if g_k > 0.0 and g_p >= 0.0:  # open, and the free step does not reach the casing
            return 0.0
        p_cap = (min(g_k, 0.0) + e * max(g_k, 0.0) - g_p) / gz
        if code == 0:
            return max(0.0, p_cap)
        return max(0.0, min(-(gd_p + e * gd_k) / w, p_cap))
    if code == 3:
        return max(0.0, -(gd_p + e * gd_k) / w) if g_p <= 0.0 else 0.0
    if code == 4:
        active = g_k + gamma * h * gd_k <= 0.0
    else:  # paper: the fixed point for one contact is "closed at t_k or predicted closed"
        active = g_k <= 0.0 or g_p <= 0.0
    if not active:
        return 0.0
    if gd_k > 0.0:
        e = 1.0
    return max(0.0, -(gd_p + e * gd_k) / w)


@njit
def _predict(T, Y1, Y0, sig, j, X):
    """``X_p = T X + Y1 s_{j+1} + Y0 s_j``."""
    Xp = np.dot(T, X)
    if sig.shape[1] > 0:
        Xp += np.dot(Y1, sig[j + 1]) + np.dot(Y0, sig[j])
    return Xp


@njit
def one_contact_block(
    X, T, Y1, Y0, sig, code, g0, gr, gv, z, w, gz, e, h, gamma, upper, Xout, Pout
):
    """``Xout.shape[0]`` steps of one frictionless contact with constant gap ``g0``;
    ``sig`` (m + 1, n_s): the load signals at ``t_k`` and at each step's end."""
    Xk = X
    for j in range(Xout.shape[0]):
        Xp = _predict(T, Y1, Y0, sig, j, Xk)
        P = min(
            impulse_one_code(
                code,
                g0 + np.dot(gr, Xk),
                np.dot(gv, Xk),
                g0 + np.dot(gr, Xp),
                np.dot(gv, Xp),
                w,
                gz,
                e,
                h,
                gamma,
            ),
            upper,
        )
        Xk = Xp if P == 0.0 else Xp + P * z
        Xout[j] = Xk
        Pout[j, 0] = P


@njit
def friction_step(
    Xk, Xp, S, ok, o1, GZ, W, code, mu, e3, U, warm, use_warm, h, gamma, tol, max_iter
):
    """The frictional contact solve of one step from ``X_k`` with the prediction ``X_p``.

    Local rows ``y = S X + o`` (``[g, ġ, w_t]``, casing terms ``o_k``, ``o_{k+1}``), Newton's
    law with ``e = 1`` on separating contacts (``ġ_k > 0``), then the active-set fixed point
    :func:`~femrub.contact.coulomb.frictional_fixed_point` with the bounds ``U``, reduced in
    place for contacts entering a coating within the step
    (:func:`~femrub.contact.wear_map.entry_bounds`).

    Returns ``(y_k, q, e, ġ_k, active, P, u, state, residual, status)`` (``q`` (n, 3): the
    free local velocities at ``t_{k+1}``).
    """
    n = mu.size
    yk = np.dot(S, Xk) + ok
    yp = np.dot(S, Xp) + o1
    gdk, e = np.empty(n), np.empty(n)
    for i in range(n):
        gdk[i] = yk[n + 3 * i]
        e[i] = 1.0 if gdk[i] > 0.0 else e3[i]
    q = yp[n:].copy().reshape((n, 3))
    entry_bounds(U, yk[:n], yp[:n])  # a coating's bound: the part of the step on it
    active, P, u, st, res, it, status = frictional_fixed_point(  # reads these, never writes
        code,
        yk[:n],
        gdk,
        yp[:n],
        GZ,
        W,
        q,
        mu,
        e,
        gdk,
        U,
        warm,
        use_warm,
        h,
        gamma,
        tol,
        max_iter,
    )
    return yk, q, e, gdk, active, P, u, st, res, status


@njit
def friction_block(
    X,
    T,
    Y1,
    Y0,
    sig,
    S,
    off,
    Z,
    W,
    GZ,
    code,
    mu,
    e3,
    U,
    warm,
    use_warm,
    h,
    gamma,
    alpha,
    tol,
    max_iter,
    Xout,
    Pout,
    Ptout,
    heat_out,
    state_out,
):
    """``Xout.shape[0]`` frictional steps (``off`` (m + 1, 4 n_c): the casing terms at
    ``t_k`` and at each step's end). Returns ``(steps done, status, residual, warm)``: a
    step whose solve failed (status ≠ 0) is not written, and the block stops there."""
    n = mu.size
    Xk = X
    for j in range(Xout.shape[0]):
        Xp = _predict(T, Y1, Y0, sig, j, Xk)
        yk, q, e, gdk, active, P, u, st, res, status = friction_step(
            Xk,
            Xp,
            S,
            off[j],
            off[j + 1],
            GZ,
            W,
            code,
            mu,
            e3,
            U,
            warm,
            use_warm,
            h,
            gamma,
            tol,
            max_iter,
        )
        if status != 0:
            return j, status, res, warm
        warm, use_warm = P, True
        Xk = Xp + np.dot(Z, P.reshape(-1)) if active.any() else Xp
        Xout[j] = Xk
        for i in range(n):
            Pout[j, i] = P[i, 0]
            Ptout[j, i, 0], Ptout[j, i, 1] = P[i, 1], P[i, 2]
            heat_out[j, i] = alpha[i] * P[i, 0]
            state_out[j, i] = st[i]
    return Xout.shape[0], 0, 0.0, warm
