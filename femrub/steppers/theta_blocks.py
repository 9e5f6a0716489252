"""Blocks of θ-method steps in one compiled call (dense models).

:meth:`ThetaMethod.run` hands the recorder a *block* writer: ``block(m, rows)`` advances
``m`` steps with :func:`femrub.contact.theta_block.one_contact_block`,
:func:`~femrub.contact.theta_block.friction_block` (contacts without history) or
:func:`femrub.contact.rub_block.rub_block` (the ``"power"`` heat fixed point on a
thermoelastic model, an abradable coating) and writes each step's state, time and impulses
into the recorder's rows, then leaves the stepper, and the coating, as ``m`` calls of
``step()`` would (state, time, warm start, memoised casing terms, load signals; the wear
map, its history and the start of the next sweep). Which steps it serves is
:func:`block_kind`; ``step()``/``iterate()`` and the other models keep the per-step path,
and so do contacts with casing heat (:mod:`femrub.contact.casing_heat`: its lumped cells
are not compiled) and a heat coefficient ``α(t)`` of the ``"alpha"`` law.

The casing terms and the load signals of the block's times are evaluated here, before the
call (the casing's swept gap in one vectorised call, ``Contact.gap_at``/``rate_at`` on an
array of times), at the same times the per-step path uses (``t_k + h``); the worn surface
under the contacts changes inside the block and is added by the kernel.
"""

from __future__ import annotations

import math

import numpy as np

from ..contact.activation import compile_kernels
from ..contact.coulomb import MAX_HEAT_ITERATIONS
from ..contact.friction import check_status
from ..contact.gap import _over_times
from ..contact.rub_block import rub_block
from ..contact.theta_block import ONE_RULES, friction_block, one_contact_block
from .record import Friction

__all__ = ["block_kind", "prepare", "advance_block"]


def block_kind(st) -> str | None:
    """``"one"`` (the one-contact fast path), ``"friction"`` (no history), ``"rub"`` (the
    ``"power"`` heat fixed point and/or an abradable coating) or ``None`` (per step).

    Per step: sparse models, frictionless contacts (but the one-contact fast path), casing
    heat, a heat coefficient ``α(t)`` of the ``"alpha"`` law, and the ``"power"`` law on a
    thermoelastic model with a frictionless contact (its heat iteration solves those with
    the pivoting LCP of :func:`femrub.contact.friction.solve_frictional_contact`).
    """
    m, c = st.model, st.model.contact
    if c is None or not st._lu.dense:
        return None
    if st._fast:
        return "one"
    if not st._friction or c.casing_heat is not None:
        return None
    power = c.heat_law == "power" and m.layout.n_t > 0
    if c.heat_law == "alpha" and callable(c.heat_coefficient):
        return None
    if power and not np.all(c.friction > 0.0):
        return None
    return "rub" if (power or c.wear is not None) else "friction"


def prepare(st) -> None:
    """Constant arguments of the block kernels (contiguous, writable, one signature)."""
    kind = st._block_kind = block_kind(st)
    if kind is None:
        return
    compile_kernels((kind,))  # not in the first block's time
    N = st.model.n_dofs
    ns = len(st._signals)
    st._bY1 = np.zeros((N, 0)) if st._Y1 is None else np.ascontiguousarray(st._Y1)
    st._bY0 = np.zeros((N, 0)) if st._Y0 is None else np.ascontiguousarray(st._Y0)
    st._bns = ns if st._Y1 is not None else 0
    st._bT = np.ascontiguousarray(st._T)
    if kind in ("friction", "rub"):
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
    if kind == "rub":
        _prepare_rub(st)


def _prepare_rub(st) -> None:
    """Constant arguments of :func:`~femrub.contact.rub_block.rub_block`."""
    c, m = st.model.contact, st.model
    n = c.n
    st._bpower = bool(c.heat_law == "power" and m.layout.n_t > 0)
    st._bZt = np.ascontiguousarray(st._Zt)
    st._bW3t = np.ascontiguousarray(st._W3t)
    st._beta = np.array(c.heat_partition, dtype=float)
    st._bGT = np.ascontiguousarray(c.GT)
    w = c.wear
    st._bwear = w is not None
    if w is None:  # placeholders of the same types
        st._bgrid, st._bdims = np.zeros(5), np.ones(2, dtype=np.int64)
        st._bangles, st._baxial = np.zeros(n), np.zeros(n, dtype=np.int64)
        return
    g = w.grid
    st._bgrid = np.array(
        [g.omega, g.n_angle / (2 * math.pi), w.thickness, st.h * w.yield_force, g.beta],
        dtype=float,
    )
    st._bdims = np.array([g.n_angle, g.n_axial], dtype=np.int64)
    st._bangles = np.ascontiguousarray(g.angles, dtype=float)
    st._baxial = np.ascontiguousarray(g.axial_cell, dtype=np.int64)


def _signals(st, t1: np.ndarray) -> np.ndarray:
    """Load signals ``(m + 1, n_s)``: the carried ``s_k``, then at each step's end."""
    sig = np.empty((t1.size + 1, st._bns))
    if st._bns:
        sig[0] = st._sk
        for j, t in enumerate(t1):
            sig[j + 1] = st._signal_values(t)
    return sig


def _offsets(st, t1: np.ndarray, profile: bool = False) -> np.ndarray:
    """Casing terms ``o`` (m + 1, 4 n_c) of ``[g, ġ, w_t] = S X + o``: the memoised ``o(t_k)``,
    then at each step's end (as ``ThetaMethod._casing``); ``profile``: the casing profile's
    alone, without the worn surface (the kernel adds it)."""
    c = st.model.contact
    n, m = c.n, t1.size
    off = np.empty((m + 1, 4 * n))
    off[0] = st._casing(st.k, st.t)
    loc = off[1:, n:].reshape(m, n, 3)
    if profile:
        off[1:, :n] = _profile_gap(c, t1)
        loc[:, :, 0] = 0.0 if c.gap_rate is None else _over_times(c.gap_rate, t1, n)
    else:
        off[1:, :n] = c.gap_at(t1)
        loc[:, :, 0] = c.rate_at(t1)
    loc[:, :, 1:] = -c.casing_velocity
    return off


def _profile_gap(c, t: np.ndarray) -> np.ndarray:
    """``g0(t)`` (m, n_c) of the casing profile, without the worn surface."""
    if callable(c.gap0):
        return _over_times(c.gap0, t, c.n)
    return np.broadcast_to(c.gap0, (t.size, c.n))


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
            st.X,
            st._bT,
            st._bY1,
            st._bY0,
            sig,
            ONE_RULES[st.activation],
            st._g0,
            st._gr,
            st._gv,
            st._z,
            st._w,
            st._gz,
            st._e,
            h,
            st.gamma,
            np.inf,
            X,
            P,
        )
        done, friction = m, False
    else:
        rub = st._block_kind == "rub"
        off = _offsets(st, t1, profile=rub)
        use_warm = st._warm3 is not None
        warm = st._warm3 if use_warm else st._warm0
        if rub:
            done, status, res, warm = _rub(st, sig, t1, off, warm, use_warm, X, P, Pt, heat, state)
        else:
            done, status, res, warm = friction_block(
                st.X,
                st._bT,
                st._bY1,
                st._bY0,
                sig,
                st._bS,
                off,
                st._bZ,
                st._bW,
                st._bGZ,
                st._rule3,
                st._mu3,
                st._e3,
                st._U3,
                warm,
                use_warm,
                h,
                st.gamma,
                st._balpha,
                1e-12,
                60,
                X,
                P,
                Pt,
                heat,
                state,
            )
        if done:
            st._warm3 = warm  # the last step's impulse
            st._memo = (k0 + done, t1[done - 1], off[done].copy())
            st.friction = Friction(
                Pt[done - 1].copy(), heat[done - 1].copy(), state[done - 1].copy()
            )
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


def _rub(st, sig, t1, off, warm, use_warm, X, P, Pt, heat, state) -> tuple:
    """:func:`~femrub.contact.rub_block.rub_block` over the ``m = t1.size`` steps; the coating
    (wear map cut in place, history, the next sweep's start) left as ``m`` calls of
    ``Contact.after_step`` leave it."""
    c, h, m = st.model.contact, st.h, t1.size
    w = c.wear
    ta = st.t0 + np.arange(st.k + 1, st.k + m + 1) * h  # the per-step path's after_step times
    hist = np.empty(m)
    if w is None:
        depth, g0a, wstate = np.zeros(1), np.zeros((m, c.n)), np.zeros(3)
        last_r = np.zeros((2, c.n))
    else:
        depth = w.depth.reshape(-1)  # a view: cut in place
        g0a = np.ascontiguousarray(_profile_gap(c, ta))
        last = w._last
        last_r = np.zeros((2, c.n))  # the last reach and the incursion so far
        last_r[0] = 0.0 if last is None else np.asarray(last[1], dtype=float)
        last_r[1] = w.incursion
        wstate = np.array(
            [last is not None, 0.0 if last is None else last[0], w.history[-1][1]], dtype=float
        )
    prediction = (st._bT, st._bY1, st._bY0, sig, h, st.gamma)
    contact = (
        st._bS,
        off,
        st._bZ,
        st._bW,
        st._bGZ,
        st._rule3,
        st._mu3,
        st._e3,
        st._U3,
        st._balpha,
        1e-12,
        60,
    )
    heating = (st._bpower, st._bZt, st._bW3t, st._beta, MAX_HEAT_ITERATIONS)
    wearing = (
        st._bwear,
        t1,
        ta,
        g0a,
        st._bGT,
        depth,
        st._bangles,
        st._baxial,
        st._bgrid,
        st._bdims,
        last_r,
        wstate,
    )
    out = (X, P, Pt, heat, state, hist)
    done, status, res, warm = rub_block(
        st.X, prediction, contact, warm, use_warm, heating, wearing, out
    )
    if w is not None and done:
        cut = np.flatnonzero(~np.isnan(hist[:done]))
        w.history.extend(zip(ta[cut].tolist(), hist[cut].tolist(), strict=True))
        w._last = (float(ta[done - 1]), last_r[0].copy())
        w.incursion = last_r[1].copy()
    return done, status, res, warm
