"""Blocks of θ-method steps in one compiled call (dense models, history-free contacts).

:meth:`ThetaMethod.run` hands the recorder a *block* writer: ``block(m, rows)`` advances
``m`` steps with :func:`femrub.contact.theta_block.one_contact_block` or
:func:`~femrub.contact.theta_block.friction_block` and writes each step's state, time and
impulses into the recorder's rows, then leaves the stepper as ``m`` calls of ``step()``
would (state, time, warm start, memoised casing terms, load signals). Which steps it serves
is :func:`block_kind`; ``step()``/``iterate()`` and the other models keep the per-step path.

The casing terms and the load signals of the block's times are evaluated here, before the
call (the casing's swept gap in one vectorised call, ``Contact.gap_at``/``rate_at`` on an
array of times), at the same times the per-step path uses (``t_k + h``).
"""

from __future__ import annotations

import numpy as np

from ..contact.activation import compile_blocks
from ..contact.friction import check_status
from ..contact.theta_block import ONE_RULES, friction_block, one_contact_block

__all__ = ["block_kind", "prepare", "advance_block"]


def block_kind(st) -> str | None:
    """``"one"`` (the one-contact fast path), ``"friction"`` or ``None`` (per step)."""
    m, c = st.model, st.model.contact
    if c is None or not st._lu.dense:
        return None
    if st._fast:
        return "one"
    if not st._friction or c.wear is not None or c.casing_heat is not None:
        return None
    if callable(c.heat_coefficient) or (c.heat_law == "power" and m.layout.n_t > 0):
        return None
    return "friction"


def prepare(st) -> None:
    """Constant arguments of the block kernels (contiguous, writable, one signature)."""
    kind = st._block_kind = block_kind(st)
    if kind is None:
        return
    compile_blocks()  # not in the first block's time
    N = st.model.n_dofs
    ns = len(st._signals)
    st._bY1 = np.zeros((N, 0)) if st._Y1 is None else np.ascontiguousarray(st._Y1)
    st._bY0 = np.zeros((N, 0)) if st._Y0 is None else np.ascontiguousarray(st._Y0)
    st._bns = ns if st._Y1 is not None else 0
    st._bT = np.ascontiguousarray(st._T)
    if kind == "friction":
        c = st.model.contact
        alpha = c.alpha_at(st.t) if c.heat_law == "alpha" else np.zeros(c.n)
        Z, W, GZ = st._Z3.copy(), st._W3.copy(), st._GZ3.copy()
        if np.any(alpha):  # as ThetaMethod._step_friction, once for a constant α
            Z[:, ::3] += st._Zt * alpha
            W[:, ::3] += st._W3t * alpha
            GZ[:, ::3] += st._GZt * alpha
        st._bZ, st._bW, st._bGZ = (np.ascontiguousarray(a) for a in (Z, W, GZ))
        st._balpha = np.array(alpha, dtype=float)
        st._bS = np.ascontiguousarray(st._S)


def _signals(st, t1: np.ndarray) -> np.ndarray:
    """Load signals ``(m + 1, n_s)``: the carried ``s_k``, then at each step's end."""
    sig = np.empty((t1.size + 1, st._bns))
    if st._bns:
        sig[0] = st._sk
        for j, t in enumerate(t1):
            sig[j + 1] = st._signal_values(t)
    return sig


def _offsets(st, t1: np.ndarray) -> np.ndarray:
    """Casing terms ``o`` (m + 1, 4 n_c) of ``[g, ġ, w_t] = S X + o``: the memoised ``o(t_k)``,
    then at each step's end (as ``ThetaMethod._casing``)."""
    c = st.model.contact
    n, m = c.n, t1.size
    off = np.empty((m + 1, 4 * n))
    off[0] = st._casing(st.k, st.t)
    off[1:, :n] = c.gap_at(t1)
    loc = off[1:, n:].reshape(m, n, 3)
    loc[:, :, 0] = c.rate_at(t1)
    loc[:, :, 1:] = -c.casing_velocity
    return off


def advance_block(st, m: int, X, t, P, Pt, heat, state) -> tuple:
    """Advance ``m`` steps into the rows ``X`` (m, N), ``t`` (m,), ``P`` (m, n_c) and, with
    friction, ``Pt`` (m, n_c, 2), ``heat`` and ``state`` (m, n_c). Returns ``(steps done,
    friction rows written, error)``: a failed contact solve ends the block with the error
    ``step()`` would raise (``None`` otherwise), the steps before it kept."""
    k0, h = st.k, st.h
    t1 = (st.t0 + np.arange(k0, k0 + m) * h) + h  # the per-step path's t_k + h
    t1[0] = st.t + h
    sig = _signals(st, t1)
    if st._block_kind == "one":
        one_contact_block(
            st.X, st._bT, st._bY1, st._bY0, sig, ONE_RULES[st.activation], st._g0, st._gr,
            st._gv, st._z, st._w, st._gz, st._e, h, st.gamma, np.inf, X, P,
        )  # fmt: skip
        done, friction = m, False
    else:
        off = _offsets(st, t1)
        use_warm = st._warm3 is not None
        warm = st._warm3 if use_warm else st._warm0
        done, status, res, warm = friction_block(
            st.X, st._bT, st._bY1, st._bY0, sig, st._bS, off, st._bZ, st._bW, st._bGZ,
            st._rule3, st._mu3, st._e3, st._U3, warm, use_warm, h, st.gamma, st._balpha,
            1e-12, 60, X, P, Pt, heat, state,
        )  # fmt: skip
        if done:
            st._warm3 = warm  # the last step's impulse
            st._memo = (k0 + done, t1[done - 1], off[done].copy())
            st.extra = {"friction_impulse": Pt[done - 1].copy(), "heat": heat[done - 1].copy(),
                        "state": state[done - 1].copy()}  # fmt: skip
        friction = True
    if done:
        st.k = k0 + done
        st.t = st.t0 + st.k * h
        t[:done] = st.t0 + np.arange(k0 + 1, k0 + done + 1) * h
        st.X, st.impulse = X[done - 1].copy(), P[done - 1].copy()
        if st._bns:
            st._sk = sig[done].copy()
    if done < m:  # what step() would raise, with the steps before it kept
        try:
            check_status(status, res)
        except FloatingPointError as exc:
            return done, friction, exc
    return done, friction, None
