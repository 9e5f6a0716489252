"""Exact work and heat integrals along the exact flows of :mod:`~.flows`.

Between events the augmented state ``z = [X; P_S; s, ṡ, …, s^(p)]`` of a held set ``S`` obeys
``ż = M z`` (:meth:`~.flows.FlowFamily.levels`). Every power of the energy balance
(:mod:`femrub.output.energy`) is a quadratic form of ``z`` and every heat rate a linear one::

    external   Σ_j s_j p_jᵀ X               thermal   Xᵀ P_th X   (or Ẋᵀ W_th X, reduced)
    damping    Xᵀ P_d X                     held contacts  λ_Sᵀ Gv_Sᵀ X   (λ_S = Λ z)
    held friction, tangential   Σ_i λ_i T_i X     (T_i = −μ_i ŝ_iᵀ Gvt_iᵀ: λ_t · Gvtᵀ X)
    held friction heat (rest)   Σ_i λ_i R_i X     (R_i = −η_i T_i, "power" heat law)
    heat load  Σ_j s_j q_j                  heat outflow   rᵀ X

so their integrals over ``[0, τ]`` are exact (Van Loan)::

    ∫ zᵀ Q z = z(0)ᵀ Γ(τ) z(0),   Γ(τ) = ∫_0^τ e^{Mᵀσ} Q e^{Mσ} dσ,
    ∫ cᵀ z   = cᵀ J(τ) z(0),      J(τ) = ∫_0^τ e^{Mσ} dσ,

on the same dyadic levels ``τ_e = unit 2^e`` as the flows: ``Γ_{e+1} = Γ_e + Z_eᵀ Γ_e Z_e``,
``J_{e+1} = J_e + J_e Z_e``, from the first level beyond the range where their Taylor series
(eight terms) is exact to round-off; shorter durations use the series directly (a model too
stiff for it at the smallest level starts from Van Loan's exponential there). A
segment of any length is composed like its state (:meth:`WorkIntegrals.over`). The exact
flight then closes the balance: the meter's midpoint rule does not see the structure's
oscillation inside a step, nor heat entering at an event inside it.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .flows import _FLUSH, LEVEL_MIN
from .kernels import double_integrals, form_values, integrals_over

__all__ = ["QUADRATIC", "LINEAR", "METER_ORDER", "NQ", "WorkIntegrals"]

#: the quadratic (works, J) and linear (heats, J) integrals, in this order
QUADRATIC = (
    "contact_work",
    "external_work",
    "thermal_work",
    "damping_work",
    "tangential_work",
    "held_friction_heat",
)
LINEAR = ("heat_load", "heat_outflow")
NQ = len(QUADRATIC)
#: ``(QUADRATIC + LINEAR)[METER_ORDER]`` is the meter's
#: :data:`~femrub.steppers.record.WORK_KEYS` (the held friction heat goes to the state)
METER_ORDER = np.array([0, 1, 2, 3, NQ, NQ + 1, 4])
_TERMS = 8  # terms of the Taylor series of the integrals over short durations
_FACTORIALS = np.array([math.factorial(k + 1) for k in range(_TERMS)], dtype=float)


def _dense(Q):
    return np.asarray(Q.toarray() if sp.issparse(Q) else Q, dtype=float)


class WorkIntegrals:
    """Exact integrals of the energy balance's powers and heat rates on the flows of a
    :class:`~.flows.FlowFamily` (see module docstring).

    Parameters
    ----------
    flows : the stepper's :class:`~.flows.FlowFamily`.
    energy : the model's :class:`~femrub.model.first_order.EnergyForms`.
    powers : (N, m0) load power vectors ``p_j``; ``heats`` (m0,) their heat ``q_j``.
    GvT : (n_c, N) gap-velocity rows (held contacts' normal work), or ``None``.
    tangential : (n_c, N) rows ``T_i``: a held contact's tangential work rate ``λ_i T_i X``
        (sliding with friction), or ``None``.
    rest_heat : (n_c, N) rows ``R_i``: the part ``λ_i R_i X`` of a held contact's frictional
        heat rate that is not in its flow, or ``None``.
    """

    def __init__(self, flows, energy, powers, heats, GvT=None, tangential=None, rest_heat=None):
        self.flows, self.GvT = flows, GvT
        self.tangential, self.rest_heat = tangential, rest_heat
        self.Pth = _dense(energy.Pth)
        self.Wth = None if energy.Wth is None else _dense(energy.Wth)
        self.Pd = _dense(energy.Pd)
        self.damped = bool(np.any(self.Pd))
        self.powers, self.heats = powers, np.asarray(heats, dtype=float)
        self.outflow = np.asarray(energy.heat_outflow, dtype=float)
        self._levels: dict[tuple, tuple] = {}
        self._full: dict[tuple, tuple] = {}
        self._flight: dict[tuple, tuple] = {}
        #: (S, unit) -> (forms, their base forms, factors): a form proportional to an earlier
        #: one (the held friction heat and the tangential work of one sliding contact) is
        #: integrated as that one, times its factor
        self._alias: dict[tuple, tuple] = {}

    def caches(self) -> list[dict]:
        """The caches keyed by held set (levels, whole-step forms, flight matrices, aliases)."""
        return [self._levels, self._full, self._flight, self._alias]

    def expand(self, S: tuple, unit: float, w: np.ndarray) -> np.ndarray:
        """``w`` (NQ + 2,) with the forms proportional to integrated ones filled in (place)."""
        dst, src, coef = self._alias.get((S, unit), _NO_ALIAS)
        if dst.size:
            w[dst] = coef * w[src]
        return w

    # -- forms on the augmented state -----------------------------------------------------------
    def forms(self, S: tuple, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(Q (NQ, N, N), C (2, N))``: the powers and heat rates of :data:`QUADRATIC` and
        :data:`LINEAR` on ``z`` of held set ``S`` (``M``: its generator)."""
        n, s, m0 = self.Pth.shape[0], len(S), self.powers.shape[1]
        N, nz = M.shape[0], n + s
        Q, C = np.zeros((NQ, N, N)), np.zeros((2, N))
        if S:  # λ_S = Λ z, structure velocity Gv_Sᵀ X
            _, _, lam = self.flows.generator(S)
            Lz = np.zeros((s, N))
            Lz[:, :n] = lam[:, :n]
            Lz[:, nz : nz + lam.shape[1] - n] = lam[:, n:]
            for k, rows in ((0, self.GvT), (4, self.tangential), (5, self.rest_heat)):
                if rows is not None:
                    Q[k, :, :n] = Lz.T @ rows[list(S)]
        if m0:
            Q[1, :n, nz : nz + m0] = self.powers
            C[0, nz : nz + m0] = self.heats
        if self.Wth is None:
            Q[2, :n, :n] = self.Pth
        else:  # Ẋ = M[:n] z: the work on the state's rate
            Q[2, :, :n] = M[:n].T @ self.Wth
        Q[3, :n, :n] = self.Pd
        C[1, :n] = self.outflow
        return 0.5 * (Q + Q.transpose(0, 2, 1)), C

    def levels(self, S: tuple, unit: float) -> tuple:
        """``(Y, lo, forms, A, B)`` of held set ``S`` (cached): per level ``e >= lo`` of
        :meth:`~.flows.FlowFamily.levels` the stacked ``[Γ_e; C J_e]`` (one product per level
        in :meth:`over`, with the level's flow; ``Γ`` of the non-zero ``forms`` only), and the
        Taylor coefficients ``A_k, C M^k`` (k < :data:`_TERMS`) that give the integrals over
        any duration below ``unit 2^lo`` to round-off."""
        key = (S, unit)
        if key not in self._levels:
            Z = self.flows.levels(S, unit)
            M = self.flows.generator_z(S)
            Q, C = self.forms(S, M)
            act = np.flatnonzero(np.any(Q, axis=(1, 2)))  # forms that are not zero
            act, self._alias[key] = _proportional(Q, act)
            Q = Q[act]
            # Γ(τ) = Σ τ^{k+1}/(k+1)! A_k, A_{k+1} = Mᵀ A_k + A_k M
            # C J(τ) = Σ τ^{k+1}/(k+1)! C M^k
            N = M.shape[0]
            A, B = np.empty((_TERMS, *Q.shape)), np.empty((_TERMS, *C.shape))
            A[0], B[0] = Q, C
            for k in range(_TERMS - 1):  # A_k symmetric: Mᵀ A_k = (A_k M)ᵀ (one product)
                AM = (A[k].reshape(-1, N) @ M).reshape(-1, N, N)
                np.add(AM, AM.transpose(0, 2, 1), out=A[k + 1])
                np.matmul(B[k], M, out=B[k + 1])
            size = np.maximum(
                np.abs(A).reshape(_TERMS, -1).max(axis=1, initial=0.0),
                np.abs(B).reshape(_TERMS, -1).max(axis=1),
            )
            tau = unit * 2.0 ** np.arange(LEVEL_MIN, LEVEL_MIN + len(Z))
            # the series' last term is round-off against its first up to level lo - 1
            ok = tau ** (_TERMS - 1) / _FACTORIALS[-1] * size[-1] <= 1e-16 * size[0]
            lo = len(Z) if ok.all() else int(np.argmin(ok))
            Y = np.zeros((0, _level_rows(act.size, N), N))
            if lo < len(Z):  # the first level after the series' range, then doubling
                g, j = self._van_loan(M, Q, C, tau[0]) if lo == 0 else _series(A, B, tau[lo])
                g, j = np.ascontiguousarray(g), np.ascontiguousarray(j)
                Y = double_integrals(g, j, np.ascontiguousarray(Z[lo:]), _FLUSH)
            self._levels[key] = (Y, lo, act, A, B)
        return self._levels[key]

    @staticmethod
    def _van_loan(M, Q, C, tau):
        """``Γ(τ)`` (per form) and ``C J(τ)`` by the exponentials of block matrices."""
        N = M.shape[0]
        E = sla.expm(tau * M)
        gam = np.empty_like(Q)
        for k, Qk in enumerate(Q):
            big = np.zeros((2 * N, 2 * N))
            big[:N, :N], big[:N, N:], big[N:, N:] = -tau * M.T, tau * Qk, tau * M
            gam[k] = E.T @ sla.expm(big)[:N, N:]
        big = np.zeros((2 * N, 2 * N))
        big[:N, :N], big[:N, N:] = tau * M, tau * np.eye(N)
        return 0.5 * (gam + gam.transpose(0, 2, 1)), C @ sla.expm(big)[:N, N:]

    # -- integrals over segments ----------------------------------------------------------------
    def over(self, S: tuple, z, rest: float, unit: float, state: bool = False):
        """The integrals (NQ + 2,) of :data:`QUADRATIC` + :data:`LINEAR` over ``rest`` from ``z``,
        on the segments of :meth:`~.flows.FlowFamily.advance_z` (binary expansion of
        ``rest / unit`` down to ``2^LEVEL_MIN``): its levels from ``lo`` up, then the series
        for the rest. With ``state``: ``(z(rest), integrals)``, ``z`` composed exactly as
        :meth:`~.flows.FlowFamily.advance_z` does."""
        Y, lo, act, A, B = self.levels(S, unit)
        k = int(rest / unit * 2.0**-LEVEL_MIN * (1.0 + 1e-12)) if rest > 0.0 else 0
        k = min(k, (1 << (lo + len(Y))) - 1)
        # per level from the top bit: [Γ_e z; C J_e z] and Z_e z, the bits below lo by the
        # series on the Krylov vectors of z, the state with them (compiled)
        wq, wl, z = integrals_over(
            Y,
            lo,
            A[0],
            B[0],
            self.flows.generator_z(S),
            self.flows.levels(S, unit),
            np.ascontiguousarray(z, dtype=float),
            k,
            _TERMS,
            unit * 2.0**LEVEL_MIN,
            state,
        )
        w = np.zeros(NQ + 2)
        w[act], w[NQ:] = wq, wl
        self.expand(S, unit, w)
        return (z, w) if state else w

    def step(self, S: tuple, z, q: int, unit: float) -> np.ndarray:
        """The integrals (NQ + 2,) over a whole step ``h = q unit`` from ``z`` (one form each)."""
        Y, act = self._step_forms(S, q, unit)
        y, k_q = Y @ z, act.size
        w = np.zeros(NQ + 2)
        w[act], w[NQ:] = y[: k_q * z.size].reshape(k_q, z.size) @ z, y[k_q * z.size :]
        return self.expand(S, unit, w)

    def _step_forms(self, S: tuple, q: int, unit: float) -> tuple[np.ndarray, np.ndarray]:
        """``[Γ(h) (non-zero forms); C J(h)]`` stacked, and the forms' indices (cached)."""
        key = (S, unit)
        if key not in self._full:
            Y, lo, act, A, B = self.levels(S, unit)
            Z = self.flows.levels(S, unit)
            N, k_q = Z[0].shape[0], act.size
            g, j = np.zeros((k_q, N, N)), np.zeros((2, N))
            P = np.eye(N)  # the flow over the part composed so far
            for e in range(q.bit_length() - 1, -1, -1):
                if q >> e & 1:
                    i = e - LEVEL_MIN
                    if i >= lo:
                        ge = Y[i - lo][: k_q * N].reshape(k_q, N, N)
                        je = Y[i - lo][k_q * N : k_q * N + 2]
                    else:
                        ge, je = _series(A, B, unit * 2.0**e)
                    g += P.T @ ge @ P
                    j += je @ P
                    P = Z[i] @ P
            self._full[key] = (np.vstack([g.reshape(-1, N), j]), act)
        return self._full[key]

    def flight(self, S: tuple, X, w, q: int, unit: float):
        """A whole step ``h = q unit`` of held set ``S`` and its integrals in one product:
        ``(X(h), P_S, integrals (NQ + 2,))`` for the flow's inputs ``(X, w)``
        (:class:`~.flows.Flow`; ``w_l = h^l s^(l)``)."""
        big, _, n, nz = self.flight_matrix(S, q, unit)
        u = np.concatenate([X, w.ravel()])
        y = big @ u
        return y[:n], y[n:nz], self.flight_integrals(S, q, unit, y, u)

    def flight_matrix(self, S: tuple, q: int, unit: float) -> tuple:
        """``(F, act, n, nz)``: ``y = F u`` on the flow's inputs ``u = [X; w]`` stacks the
        state ``[X(h); P_S]`` (``nz`` rows), ``E ᵀ Γ(h) E u`` per non-zero form ``act`` and
        ``C J(h) E u`` (``E``: the inputs to ``z``; see :meth:`flight_integrals`; cached)."""
        key = (S, unit)
        if key not in self._flight:
            f = self.flows.flow(S, self.flows.h)
            Y, act = self._step_forms(S, q, unit)
            N, n, nz = Y.shape[1], f.n, f.Phi.shape[0]
            n_in = n + f.Psi.shape[1]
            E = np.zeros((N, n_in))  # z = E [X; w]: chain s^(l) = w_l / h^l, P_S = 0
            E[:n, :n] = np.eye(n)
            p1 = self.flows.degree + 1
            scale = np.repeat(self.flows.h ** -np.arange(p1), f.Psi.shape[1] // p1)
            E[nz:, n:] = np.diag(scale)
            kn = act.size * N
            gam = E.T @ Y[:kn].reshape(-1, N, N) @ E
            big = np.vstack([np.hstack([f.Phi, f.Psi]), gam.reshape(-1, n_in), Y[kn:] @ E])
            self._flight[key] = (big, act, n, nz)
        return self._flight[key]

    def flight_integrals(self, S: tuple, q: int, unit: float, y, u) -> np.ndarray:
        """The integrals (NQ + 2,) of a whole step from ``y = F u`` (:meth:`flight_matrix`;
        rows of ``y`` past ``F``'s are ignored): the forms ``uᵀ (EᵀΓE) u``, the heats as read."""
        _, act, _, nz = self._flight[(S, unit)]
        out = np.zeros(NQ + 2)
        form_values(y, u, nz, act, out)
        return self.expand(S, unit, out)


_NO_ALIAS = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0))


def _proportional(Q: np.ndarray, act: np.ndarray) -> tuple[np.ndarray, tuple]:
    """The forms of ``act`` to integrate (``Q`` (NQ, N, N)) and ``(dst, src, coef)``: each
    other form ``dst`` is ``coef`` times the integrated form ``src`` to round-off."""
    base, dst, src, coef = [], [], [], []
    for f in act:
        for b in base:
            c = float(np.vdot(Q[f], Q[b]) / np.vdot(Q[b], Q[b]))
            if np.max(np.abs(Q[f] - c * Q[b])) <= 1e-14 * np.max(np.abs(Q[f])):
                dst.append(f)
                src.append(b)
                coef.append(c)
                break
        else:
            base.append(f)
    alias = (np.array(dst, dtype=np.int64), np.array(src, dtype=np.int64), np.array(coef))
    return np.array(base, dtype=np.int64), (alias if dst else _NO_ALIAS)


def _level_rows(n_forms: int, N: int) -> int:
    """Rows of one level's stack ``[Γ_e (n_forms × N); C J_e (2)]``."""
    return n_forms * N + 2


def _series(A, B, tau):
    """``Γ(τ)``, ``C J(τ)`` from their Taylor coefficients (see :meth:`WorkIntegrals.levels`)."""
    c = tau ** np.arange(1, _TERMS + 1) / _FACTORIALS
    return np.tensordot(c, A, 1), np.tensordot(c, B, 1)
