"""Exact flows of a first-order model between contact events (matrix exponentials).

Between events a model ``A Ẋ = B X + F(t) + H λ`` is linear. With ``L = A⁻¹ B``, the load
columns ``G = A⁻¹ [F_1 … F_m]`` and the load signals ``s(t)`` interpolated linearly over an
interval of length ``τ`` (``s(a + σ τ) = u0 + σ (u1 − u0)``, σ ∈ [0, 1]), the *free* flow is
exact::

    X(a + τ) = e^{τL} X(a) + τ φ1(τL) G u0 + τ φ2(τL) G (u1 − u0)

with ``φ1(z) = (e^z − 1)/z`` and ``φ2(z) = (e^z − 1 − z)/z²``. All three blocks are read
off one exponential of an augmented matrix (Al-Mohy & Higham's ``scipy.linalg.expm``)::

    expm([[τK, τE, 0], [0, 0, I], [0, 0, 0]]) = [[e^{τK}, τφ1(τK) E, τφ2(τK) E], …]

A set ``S`` of *held* contacts (closed, gap velocity zero, obstacle fixed) is kept closed by
the multiplier that holds their gap acceleration at zero, ``Gv_Sᵀ Ẋ = 0``::

    λ_S = −W_S⁻¹ Gv_Sᵀ (L X + G s),        W_S = Gv_Sᵀ A⁻¹ H_S,  H_S = Hm_S + Ht_S diag α_S

so the held flow is again linear, ``Ẋ = Π (L X + G s)`` with ``Π = I − A⁻¹ H_S W_S⁻¹ Gv_Sᵀ``,
and its impulse ``P_S = ∫ λ_S dt`` is integrated exactly by appending ``P_S`` to the state
(``K = [[ΠL, 0], [Λx, 0]]``, ``E = [[ΠG], [Λs]]``). ``S = ()`` is the free flow.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

__all__ = ["Flow", "FlowFamily"]


class Flow:
    """Exact flow of one held set over one duration: ``(X, u0, u1) -> (X_end, P_S)``."""

    def __init__(self, K: np.ndarray, E: np.ndarray, n: int, tau: float):
        nz, m = K.shape[0], E.shape[1]
        M = np.zeros((nz + 2 * m, nz + 2 * m))
        M[:nz, :nz] = tau * K
        M[:nz, nz : nz + m] = tau * E
        M[nz : nz + m, nz + m :] = np.eye(m)
        ex = sla.expm(M)
        self.n, self.tau = n, tau
        self.Phi = np.ascontiguousarray(ex[:nz, :n])  # e^{τK} restricted to X inputs
        Y0, Y1 = ex[:nz, nz : nz + m], ex[:nz, nz + m :]
        self.Ya, self.Yb = np.ascontiguousarray(Y0 - Y1), np.ascontiguousarray(Y1)

    def __call__(self, X, u0, u1):
        z = self.Phi @ X
        if self.Ya.shape[1]:
            z += self.Ya @ u0 + self.Yb @ u1
        return z[: self.n], z[self.n :]


class FlowFamily:
    """Generators of the free and held flows of a model; exact flows built on demand.

    Parameters
    ----------
    L : (N, N) dense ``A⁻¹ B``.
    G : (N, m) dense ``A⁻¹ F`` (load columns).
    AinvH : (N, n_c) ``A⁻¹ (Hm + Ht diag α)`` (constant α), or ``None`` without contact.
    GvT : (n_c, N) gap-velocity rows.
    h : the constant step (s): its flows are cached per held set.
    """

    def __init__(self, L, G, AinvH, GvT, h):
        self.L, self.G, self.AinvH, self.GvT, self.h = L, G, AinvH, GvT, h
        self._gen: dict[tuple, tuple] = {}
        self._step: dict[tuple, Flow] = {}  # (S, τ) -> Flow
        self._probe: dict[tuple, tuple] = {}

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
                lam = -np.linalg.solve(W, Gv @ np.hstack([L, G]))  # λ_S = Λx X + Λs s
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
        if key in self._step:
            return self._step[key]
        K, E, _ = self.generator(S)
        f = Flow(K, E, self.L.shape[0], tau)
        if cache or tau == self.h:
            self._step[key] = f
        return f

    def multiplier(self, S: tuple, X, u) -> np.ndarray:
        """``λ_S`` (N) holding the set ``S`` at state ``X`` and load signals ``u``."""
        _, _, lam = self.generator(S)
        n = self.L.shape[0]
        out = lam[:, :n] @ X
        if lam.shape[1] > n:
            out += lam[:, n:] @ u
        return out

    def probe(self, S: tuple, GT: np.ndarray, q: int) -> tuple[np.ndarray, ...]:
        """Gaps ``Gᵀ X`` and held multipliers ``λ_S`` at ``τ_j = j h / q``, j = 1 .. q − 1.

        Returns ``(Rx, R0, R1)`` with rows ``[Gᵀ X(τ_j); λ_S(τ_j)]`` stacked over ``j``
        (``n_c + |S|`` rows each) ``= Rx X + R0 s_k + R1 s_{k+1}`` over a full step (cached).
        """
        if S not in self._probe:
            K, E, lam = self.generator(S)
            n, h = self.L.shape[0], self.h
            rx, r0, r1 = [], [], []
            for j in range(1, q):
                w = j / q
                f = Flow(K, E, n, w * h)
                Px, Pa, Pb = f.Phi[:n], f.Ya[:n], f.Yb[:n]
                A0, A1 = Pa + Pb * (1.0 - w), Pb * w  # u(τ_j) = (1 − w) s_k + w s_{k+1}
                rows_x, rows_0, rows_1 = [GT @ Px], [GT @ A0], [GT @ A1]
                if lam is not None:
                    lx, ls = lam[:, :n], lam[:, n:]
                    rows_x.append(lx @ Px)
                    rows_0.append(lx @ A0 + ls * (1.0 - w))
                    rows_1.append(lx @ A1 + ls * w)
                rx += rows_x
                r0 += rows_0
                r1 += rows_1
            self._probe[S] = tuple(np.ascontiguousarray(np.vstack(r)) for r in (rx, r0, r1))
        return self._probe[S]
