"""Exact flows of a first-order model between contact events (matrix exponentials).

Between events a model ``A Ẋ = B X + F(t) + H λ`` is linear. With ``L = A⁻¹ B``, the load
columns ``G = A⁻¹ [F_1 … F_m]`` and the load signals written over an interval of length
``τ`` as a polynomial in the normalised time σ ∈ [0, 1],
``s(a + σ τ) = Σ_i w_i σ^i / i!`` (degree ``p``), the *free* flow is exact::

    X(a + τ) = e^{τL} X(a) + Σ_i τ φ_{i+1}(τL) G w_i,      φ_1(z) = (e^z − 1)/z, …

(``p = 1`` is the linear interpolant: ``τ φ1 G s_a + τ φ2 G (s_b − s_a)``). All blocks are
read off one exponential of an augmented matrix (``scipy.linalg.expm``, Al-Mohy & Higham),
a chain of ``p + 1`` integrators driving the load::

    expm([[τK, τE, 0, …], [0, 0, I, …], …, [0, …, 0]]) = [[e^{τK}, Ψ_0, …, Ψ_p], …]

A set ``S`` of *held* contacts (closed, gap velocity zero, obstacle fixed) is kept closed by
the multiplier that holds their gap acceleration at zero, ``Gv_Sᵀ Ẋ = 0``::

    λ_S = −W_S⁻¹ Gv_Sᵀ (L X + G s),        W_S = Gv_Sᵀ A⁻¹ H_S,  H_S = Hm_S + Ht_S diag α_S

so the held flow is again linear, ``Ẋ = Π (L X + G s)`` with ``Π = I − A⁻¹ H_S W_S⁻¹ Gv_Sᵀ``,
and its impulse ``P_S = ∫ λ_S dt`` is integrated exactly by appending ``P_S`` to the state
(``K = [[ΠL, 0], [Λx, 0]]``, ``E = [[ΠG], [Λs]]``). ``S = ()`` is the free flow. On a
moving casing the held contacts keep ``ġ = ġ0(t) + Gvᵀ X = 0`` and ``λ_S`` gets
``−W_S⁻¹ g̈0_S(t)``: the casing's accelerations are extra inputs (``n_acc``). A held contact
sliding with Coulomb friction along a fixed direction has its tangential force in its column
``H_S`` (:mod:`~.friction`); its slip along that direction, ``σ = R_σ X + σ0``,
is checked with the multipliers (:attr:`FlowFamily.slip`: rows after ``λ_S``, must stay > 0).

Event times are found on these flows by :func:`first_zero` (safeguarded Newton), the states
at arbitrary times by :meth:`FlowFamily.advance` (cached dyadic sub-step flows).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla

from .kernels import compose, next_iterate, square_levels

__all__ = ["Flow", "FlowFamily", "LEVEL_MIN", "held_set", "first_zero", "shift"]

#: Smallest sub-step flow, ``unit 2^LEVEL_MIN`` (events are located to this resolution).
LEVEL_MIN = -36
_FLUSH = 1e-150  # entries of sub-step flows below this are set to zero (no subnormals)


def held_set(key: tuple) -> tuple:
    """The held set of a cache key: the key itself, or its first tuple (``(S, τ)``, ...)."""
    if all(isinstance(k, (int, np.integer)) for k in key):
        return key
    return next(k for k in key if isinstance(k, tuple))


def shift(b: np.ndarray, alpha: float, delta: float) -> np.ndarray:
    """Chain inputs ``w`` (p+1, m) of ``u(σ) = Σ b_i σ^i`` on ``[α, α + δ]`` (σ' ∈ [0, 1]).

    ``u(α + δ σ') = Σ_l σ'^l Σ_{i>=l} C(i, l) α^{i−l} δ^l b_i``, and ``w_l = l! ×`` that.
    """
    p = b.shape[0] - 1
    C, E = _binomials(p)
    T = C * (float(alpha) ** np.arange(p + 1))[E]  # C = 0 where i < l
    if delta != 1.0:
        T *= (float(delta) ** np.arange(p + 1))[:, None]
    return T @ b


_BINOMIALS: dict[int, tuple] = {}


def _binomials(p: int) -> tuple[np.ndarray, np.ndarray]:
    """``C[l, i] = C(i, l) l!`` and the exponents ``E[l, i] = max(i − l, 0)``."""
    if p not in _BINOMIALS:
        i, j = np.meshgrid(np.arange(p + 1), np.arange(p + 1))
        C = np.array(
            [
                [math.comb(c, r) * math.factorial(r) if c >= r else 0 for c in range(p + 1)]
                for r in range(p + 1)
            ],
            dtype=float,
        )
        _BINOMIALS[p] = (C, np.maximum(i - j, 0))
    return _BINOMIALS[p]


class Flow:
    """Exact flow of one held set over one duration: ``(X, w) -> (X_end, P_S)``."""

    def __init__(self, K: np.ndarray, E: np.ndarray, n: int, tau: float, degree: int):
        nz, m = K.shape[0], E.shape[1]
        k = (degree + 1) * m
        M = np.zeros((nz + k, nz + k))
        M[:nz, :nz] = tau * K
        M[:nz, nz : nz + m] = tau * E
        for i in range(degree):
            r = nz + i * m
            M[r : r + m, r + m : r + 2 * m] = np.eye(m)
        ex = sla.expm(M)
        self.n, self.tau = n, tau
        self.Phi = np.ascontiguousarray(ex[:nz, :n])
        self.Psi = np.ascontiguousarray(ex[:nz, nz:])  # [Ψ_0 … Ψ_p]

    def __call__(self, X, w):
        z = self.Phi @ X
        if self.Psi.shape[1]:
            z += self.Psi @ w.ravel()
        return z[: self.n], z[self.n :]


class FlowFamily:
    """Generators of the free and held flows of a model; exact flows built on demand.

    Parameters
    ----------
    L : (N, N) dense ``A⁻¹ B``.
    G : (N, m) dense ``A⁻¹ F`` (load columns).
    AinvH : (N, n_c) ``A⁻¹ (Hm + Ht diag α)`` (constant α), or ``None`` without contact.
    GvT : (n_c, N) gap-velocity rows.
    h : the constant step (s).
    n_acc : the last ``n_acc`` columns of ``G`` are zero and their inputs are the casing's
        gap accelerations ``g̈0`` (one per contact): a held contact on a moving casing keeps
        ``ġ = ġ0 + Gvᵀ X = 0`` with ``λ_S = −W_S⁻¹ (Gv_Sᵀ (L X + G s) + g̈0_S)``.
    degree : polynomial degree of the load signals over a step.
    """

    def __init__(self, L, G, AinvH, GvT, h, degree, n_acc=0):
        self.L, self.G, self.AinvH, self.GvT, self.n_acc = L, G, AinvH, GvT, n_acc
        self.h, self.degree = h, degree
        self._chain0 = np.array([math.factorial(i) / h**i for i in range(degree + 1)])
        self._gen: dict[tuple, tuple] = {}
        self._flows: dict[tuple, Flow] = {}  # (S, τ) -> Flow
        self._probe: dict[tuple, tuple] = {}
        self._levels: dict[tuple, list] = {}
        #: ``(R_σ (n_c, N), σ0 (n_c,), sliding (n_c,) bool)``: the slip rows of held contacts
        #: that slide (checked with λ_S, > 0 while they slide), or ``None``
        self.slip = None

    def caches(self) -> list[dict]:
        """The caches keyed by held set (generators, flows, probe rows, levels)."""
        return [self._gen, self._flows, self._probe, self._levels]

    def sliding(self, S: tuple) -> tuple:
        """The contacts of ``S`` that slide (their slip rows follow ``λ_S`` in the checks)."""
        if self.slip is None:
            return ()
        return tuple(i for i in S if self.slip[2][i])

    def check_offsets(self, S: tuple) -> np.ndarray:
        """Constant parts of the check rows after the gaps: 0 for ``λ_S``, ``σ0`` for slips."""
        f = self.sliding(S)
        return np.r_[np.zeros(len(S)), self.slip[1][list(f)] if f else np.zeros(0)]

    def generator(self, S: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """``(K, E, Λ)`` of held set ``S``; ``Λ = [Λx, Λs]`` gives ``λ_S = Λx X + Λs s``."""
        if S not in self._gen:
            L, G, n = self.L, self.G, self.L.shape[0]
            if not S:
                self._gen[S] = (L, G, None)
            else:
                idx = list(S)
                AH, Gv = self.AinvH[:, idx], self.GvT[idx]
                W = Gv @ AH
                lam = -np.linalg.solve(W, Gv @ np.hstack([L, G]))
                if self.n_acc:  # the casing's acceleration g̈0 (last n_acc inputs)
                    cols = L.shape[1] + G.shape[1] - self.n_acc + np.array(idx)
                    lam[:, cols] -= np.linalg.inv(W)
                s = len(idx)
                K = np.zeros((n + s, n + s))
                K[:n, :n] = L + AH @ lam[:, :n]
                K[n:, :n] = lam[:, :n]
                E = np.vstack([G + AH @ lam[:, n:], lam[:, n:]])
                self._gen[S] = (K, E, lam)
        return self._gen[S]

    def flow(self, S: tuple, tau: float, cache: bool = False) -> Flow:
        """Exact flow of held set ``S`` over ``tau`` (cached for ``h`` and when ``cache``)."""
        key = (S, tau)
        if key in self._flows:
            return self._flows[key]
        K, E, _ = self.generator(S)
        f = Flow(K, E, self.L.shape[0], tau, self.degree)
        if cache or tau == self.h:
            self._flows[key] = f
        return f

    def levels(self, S: tuple, unit: float) -> np.ndarray:
        """Exact flows ``Z_e`` of held set ``S`` over ``unit 2^e``, e = ``LEVEL_MIN`` … ``e_max``
        (``unit 2^e_max >= h``), on the augmented state ``z = [X; P_S; s, ṡ, …, s^(p)]`` (load
        derivatives in physical units): ``z(τ + unit 2^e) = Z_e z(τ)`` (cached per ``S``).

        One augmented matrix ``M = [[K, E, 0, …], [0, 0, I, …], …]``; the smallest level from
        its Taylor series, the others by squaring its increment (``Z = I + D``,
        ``D_{e+1} = 2 D_e + D_e²``: no cancellation against the identity; compiled,
        :func:`~.kernels.square_levels`). Returns the stack (levels, N, N)."""
        key = (S, unit)
        if key not in self._levels:
            M = self.generator_z(S)
            N = M.shape[0]
            e_max = max(math.ceil(math.log2(self.h / unit)), 0)
            T = unit * 2.0**LEVEL_MIN * M
            T[np.abs(T) < _FLUSH] = 0.0
            if np.linalg.norm(T, 1) < 0.5:  # Taylor series of e^T − I to round-off
                D, term = T.copy(), T
                for k in range(2, 40):
                    term = term @ T / k
                    term[np.abs(term) < _FLUSH] = 0.0
                    D += term
                    if np.max(np.abs(term)) <= 1e-18 * np.max(np.abs(D)):
                        break
            else:  # a very stiff model: the exponential itself
                D = sla.expm(T) - np.eye(N)
            D = np.ascontiguousarray(D)
            self._levels[key] = square_levels(D, e_max - LEVEL_MIN + 1, _FLUSH)
        return self._levels[key]

    def generator_z(self, S: tuple) -> np.ndarray:
        """``M`` of the augmented state ``z = [X; P_S; s, ṡ, …, s^(p)]``: ``ż = M z`` (cached)."""
        key = ("M", S)
        if key not in self._probe:
            self._probe[key] = self._augmented(S)
        return self._probe[key]

    def _augmented(self, S: tuple) -> np.ndarray:
        K, E, _ = self.generator(S)
        nz, m, p = K.shape[0], E.shape[1], self.degree
        N = nz + (p + 1) * m
        M = np.zeros((N, N))
        M[:nz, :nz] = K
        M[:nz, nz : nz + m] = E
        for i in range(p):
            r = nz + i * m
            M[r : r + m, r + m : r + 2 * m] = np.eye(m)
        return M

    def chain(self, b, sigma: float) -> np.ndarray:
        """Load derivatives ``[s, ṡ, …, s^(p)]`` (physical units) at the fraction ``sigma`` of
        the step, for the step's polynomial ``s = Σ b_i σ^i``."""
        if sigma == 0.0:  # s^(l)(0) = l! b_l / h^l
            return (b * self._chain0[: b.shape[0], None]).ravel()
        w = shift(b, sigma, 1.0)  # w_l = d^l s / dσ^l
        return (w / (self.h ** np.arange(b.shape[0]))[:, None]).ravel()

    def advance_z(self, S: tuple, z, rest: float, unit: float):
        """Augmented state ``z`` (see :meth:`levels`) advanced by ``rest`` on the flow of ``S``:
        composed of the flows over ``unit 2^e`` of the binary expansion of ``rest / unit``
        down to ``2^LEVEL_MIN`` (the remainder, below ``unit 2^LEVEL_MIN``, is dropped)."""
        Z = self.levels(S, unit)
        k = int(rest / unit * 2.0**-LEVEL_MIN * (1.0 + 1e-12)) if rest > 0.0 else 0
        k = min(k, (1 << len(Z)) - 1)
        return compose(Z, np.ascontiguousarray(z, dtype=float), k) if k else z

    def advance(self, S: tuple, X, tau0: float, tau1: float, b, unit: float):
        """Flow of ``S`` from ``tau0`` to ``tau1`` in the step (:meth:`advance_z`); ``b``: the
        step's load polynomial. Returns ``(X, P_S)``."""
        n, s = self.L.shape[0], len(S)
        z = np.concatenate([X, np.zeros(s), self.chain(b, tau0 / self.h)])
        z = self.advance_z(S, z, tau1 - tau0, unit)
        return z[:n], z[n : n + s]

    def rate(self, S: tuple, X, u) -> np.ndarray:
        """``Ẋ`` (N) of the held-set-``S`` flow at state ``X`` and load signals ``u``."""
        K, E, _ = self.generator(S)
        n = self.L.shape[0]
        out = K[:n, :n] @ X
        if E.shape[1]:
            out += E[:n] @ u
        return out

    def multiplier(self, S: tuple, X, u) -> np.ndarray:
        """``λ_S`` holding the set ``S`` at state ``X`` and load signals ``u`` (m,)."""
        _, _, lam = self.generator(S)
        n = self.L.shape[0]
        out = lam[:, :n] @ X
        if lam.shape[1] > n:
            out += lam[:, n:] @ u
        return out

    def end_rows(self, S: tuple, GT: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """``(Ex, Eu)``: ``[Gᵀ X; λ_S; R_σ X] = Ex X + Eu u`` at a state ``X`` and load
        signals ``u`` (``Eu`` is ``None`` without held contacts or loads; cached)."""
        key = ("ends", S)
        if key not in self._probe:
            _, _, lam = self.generator(S)
            if lam is None:
                self._probe[key] = (GT, None)
            else:
                n, f = self.L.shape[0], self.sliding(S)
                m = lam.shape[1] - n
                Eu = np.vstack([np.zeros((GT.shape[0], m)), lam[:, n:], np.zeros((len(f), m))])
                Ex = np.vstack([GT, lam[:, :n], self.slip[0][list(f)] if f else np.zeros((0, n))])
                self._probe[key] = (Ex, Eu if Eu.shape[1] else None)
        return self._probe[key]

    def check_rows(self, S: tuple, GT: np.ndarray, q: int) -> tuple[np.ndarray, np.ndarray]:
        """``(R, Rz)``: the rows of :meth:`probe` on the augmented state ``z`` of
        :meth:`levels` (loads as the chain's physical derivatives): ``R z`` are the gaps,
        multipliers and slips at ``z``, ``Rz z`` those at ``j h / q`` later, j = 1 .. q − 1."""
        self.probe(S, GT, q)
        return self._probe[("z", S)]

    def probe(self, S: tuple, GT: np.ndarray, q: int) -> tuple[np.ndarray, np.ndarray]:
        """Gaps ``Gᵀ X``, held multipliers ``λ_S`` and slips at ``τ_j = j h / q``, j = 1 .. q − 1.

        Returns ``(Rx, Rb)``: rows ``[Gᵀ X(τ_j); λ_S(τ_j); R_σ X(τ_j)]`` (slip rows without
        their constant ``σ0``, :meth:`check_offsets`) stacked over ``j`` equal
        ``Rx X(0) + Rb b`` for the load polynomial ``s(σ) = Σ b_i σ^i`` (σ in units of h)
        from time 0. Built by doubling: the rows at ``j < 2^e`` times the sub-step flow over
        ``2^e h / q`` are those at ``2^e <= j < 2^(e+1)`` (cached).
        """
        if S not in self._probe:
            _, _, lam = self.generator(S)
            n, h, p, m = self.L.shape[0], self.h, self.degree, self.G.shape[1]
            levels = self.levels(S, h / q)  # levels[-LEVEL_MIN]: the flow over h / q
            nz, nc, f = n + len(S), GT.shape[0], self.sliding(S)
            R = np.zeros((nc + (0 if lam is None else lam.shape[0]) + len(f), levels.shape[1]))
            R[:nc, :n] = GT
            if lam is not None:  # λ_S = Λx X + Λs s, s: the chain's first block
                R[nc : nc + len(S), :n] = lam[:, :n]
                R[nc : nc + len(S), nz : nz + m] = lam[:, n:]
                if f:  # slip rows of sliding held contacts
                    R[nc + len(S) :, :n] = self.slip[0][list(f)]
            # b -> chain at σ = 0: s^(l) = l! b_l / h^l
            scale = np.repeat([math.factorial(i) / h**i for i in range(p + 1)], m)
            r, Rz, e = R.shape[0], R, 0
            while Rz.shape[0] < q * r:  # rows at j = 0 .. 2^e − 1, doubled by Z^(2^e)
                Rz = np.vstack([Rz, Rz @ levels[-LEVEL_MIN + e]])
                e += 1
            Rz = Rz[r : q * r]
            self._probe[("z", S)] = (R, np.ascontiguousarray(Rz))
            self._probe[S] = (
                np.ascontiguousarray(Rz[:, :n]),
                np.ascontiguousarray(Rz[:, nz:] * scale),
            )
        return self._probe[S]


def first_zero(at, f_lo: float, lo: float, hi: float, tol: float, df_lo=None):
    """First zero of ``f`` in ``(lo, hi]`` with ``f(hi) < 0``, by safeguarded Newton.

    ``at(τ) -> (X, P, f, df/dτ)`` evaluates the exact flow. Newton steps leaving the bracket
    fall back to regula falsi, then bisection. When ``f(lo) <= 0`` (a contact at the surface
    at ``lo``, just released) the bracket is first halved towards ``lo`` until ``f > 0``.
    With the slope ``df_lo`` the first iterate is the zero of the cubic Hermite interpolant
    on the bracket (the exact flow is then evaluated near the zero from the start).
    Returns ``(τ, X(τ), P(τ))`` with ``f(τ) <= 0`` within ``tol`` of the zero, or ``None``.
    """
    if f_lo <= 0.0:
        x = hi
        for _ in range(40):
            x = lo + 0.5 * (x - lo)
            _, _, fx, _ = at(x)
            if fx > 0.0:
                break
        else:
            return None
        a, f_a = x, fx
    else:
        a, f_a = lo, f_lo
    x = hi
    X, P, fx, dfx = at(x)
    best, bh, f_bh, df_bh = (x, X, P), hi, fx, dfx
    width, slow = bh - a, 0
    hermite = df_lo is not None
    for it in range(60):
        x_new, slow = next_iterate(
            it == 0 and hermite,
            float(lo),
            float(f_lo),
            float(df_lo) if hermite else 0.0,
            float(x),
            float(fx),
            float(dfx),
            float(a),
            float(f_a),
            float(bh),
            float(f_bh),
            float(df_bh),
            slow,
        )
        if abs(x_new - x) <= tol:  # converged
            if fx > 0.0 and bh - x > tol:  # from the open side: step just past the zero
                x = min(x + 2.0 * tol, bh)
                X, P, fx, dfx = at(x)
                if fx <= 0.0:
                    best = (x, X, P)
            break
        x = x_new
        X, P, fx, dfx = at(x)
        if fx > 0.0:
            a, f_a = x, fx
        else:
            bh, f_bh, df_bh, best = x, fx, dfx, (x, X, P)
        if bh - a <= tol:
            break
        slow = slow + 1 if bh - a > 0.5 * width else 0
        width = min(width, bh - a) if slow == 0 else width
    return best
