"""The displacement gradient at the quadrature points, as one sparse operator.

:func:`gradient_operator` returns ``B`` with ``(B u)[q] = ∇u(x_q)`` (the 3 × 3 gradient
``g_ik = ∂u_i/∂X_k`` at every quadrature point ``q`` of every element, rows ordered
``(q, i, k)``) and the quadrature weights ``w_q`` (``|J| × weight``, m³). Every form of
:mod:`femrub.fem.centrifugal` is then a product with ``B`` and ``Bᵀ``; for the Saint
Venant–Kirchhoff material (``F = I + g``, ``E = ½ (Fᵀ F − I)``, ``S = λ tr(E) I + 2 μ E``)::

    f_int(u) = Bᵀ (w F S)                                    (internal force, N)
    K_T(u) x = Bᵀ (w [F S'[δ] + g_x S]),  δ = sym(Fᵀ g_x),  g_x = B x   (tangent action)

(``S'[δ] = λ tr(δ) I + 2 μ δ``). This is what makes the reduced prestress of
:mod:`femrub.fem.prestress_rom` cheap: the projection ``Wᵀ K_T(u) W`` of the tangent on a
basis ``W`` is ``(B W)ᵀ (w K_T-stress of B W)``, evaluated quadrature point by quadrature
point without assembling a sparse matrix, and the same product applied to a few vectors
gives the residuals of Ritz pairs on the full mesh.

``linear=True`` gives the small-displacement forms of :mod:`femrub.fem.centrifugal`
(``F = I``, ``E = sym(g)``, the geometric term ``g_x S`` kept).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

try:  # numba is a dependency; the fallback keeps a broken install importable
    import numba
except ImportError:  # pragma: no cover
    numba = None

__all__ = ["GradientOperator", "gradient_operator"]

#: quadrature points per chunk of the products with many vectors (a chunk's ``9 × m``
#: gradients of 30 vectors take 8.4 MiB)
CHUNK = 4096
#: threads sharing the quadrature points or the speeds (the cores this process may use,
#: at most 4)
THREADS = max(1, min(4, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1))


@dataclass(frozen=True)
class GradientOperator:
    """``B`` (``9 n_q × N``), weights ``w`` (``n_q``) and the Lamé parameters (Pa)."""

    B: sp.csr_matrix
    w: np.ndarray
    lam: float
    mu: float
    linear: bool = False
    #: dofs of each element by component and local node (``n_el × 3 × n_loc``)
    element_dofs: np.ndarray | None = None
    #: shape-function gradients ``∂φ_a/∂X_k`` (``n_el × n_qp × 3 × n_loc``, 1/m)
    shape_gradients: np.ndarray | None = None

    @property
    def n_points(self) -> int:
        return self.w.size

    def gradients(self, u: np.ndarray) -> np.ndarray:
        """``∇u`` at every quadrature point, ``(n_q, 3, 3)``; ``u`` on all dofs."""
        return (self.B @ u).reshape(-1, 3, 3)

    def internal_force(self, u: np.ndarray) -> np.ndarray:
        """``f_int(u) = ∫ F S : ∇v dX`` on all dofs (N)."""
        g = np.ascontiguousarray(self.gradients(u))
        P = np.empty_like(g)
        _stress_kernel(g, self.w, self.lam, self.mu, self.linear, P)
        return self.B.T @ P.reshape(-1)

    def moduli(self, g: np.ndarray, w=None, out=None) -> np.ndarray:
        """``w D`` (``n_q × 9 × 9``): the tangent's integrand ``g_xᵀ D g_y`` at the state of
        the gradients ``g`` (module docstring; ``w``: the weights of those points; ``out``:
        an array to write ``D`` into)."""
        g = np.ascontiguousarray(g)
        D = np.empty((g.shape[0], 9, 9)) if out is None else out
        _moduli_kernel(g, self.w if w is None else w, self.lam, self.mu, self.linear, D)
        return D

    def apply(self, D: np.ndarray, X: np.ndarray) -> np.ndarray:
        """``Bᵀ (D (B X))``: the tangent whose moduli are ``D`` (:meth:`moduli`) applied to
        the columns of ``X`` (all dofs; a vector gives a vector)."""
        X = np.asarray(X, dtype=float)
        cols = X.reshape(self.B.shape[1], -1)
        gx = (self.B @ cols).reshape(-1, 9, cols.shape[1])
        return (self.B.T @ np.matmul(D, gx).reshape(-1, cols.shape[1])).reshape(X.shape)

    def tangent_action(self, u: np.ndarray, X: np.ndarray) -> np.ndarray:
        """``K_T(u) X`` (no spin softening) for the columns of ``X`` (all dofs)."""
        return self.apply(self.moduli(self.gradients(u)), X)

    def projected_tangent(self, u: np.ndarray, BW: np.ndarray) -> np.ndarray:
        """``Wᵀ K_T(u) W`` (no spin softening) from ``BW = B @ W`` (``9 n_q × m``)."""
        return self.project(self.gradients(u), BW)

    def chunks(self) -> list[tuple[int, int]]:
        """Bounds ``(lo, hi)`` of the quadrature points taken :data:`CHUNK` at a time."""
        return [(lo, min(lo + CHUNK, self.n_points)) for lo in range(0, self.n_points, CHUNK)]

    def project(self, g: np.ndarray, BW: np.ndarray) -> np.ndarray:
        """``Wᵀ K W = Σ_q (B W)_qᵀ D_q (B W)_q`` at the state of the gradients ``g``
        (``n_q × 3 × 3``), summed by chunks of :data:`CHUNK` points: each chunk's moduli
        ``D`` (:meth:`moduli`) and ``D (B W)`` in two buffers written again by every chunk,
        so that no ``n_q``-long temporary is made and the chunk stays in cache."""
        m = BW.shape[1]
        out = np.zeros((m, m))
        chunks = self.chunks()
        D = np.empty((max(hi - lo for lo, hi in chunks), 9, 9))
        DG = np.empty((D.shape[0], 9, m))
        for lo, hi in chunks:
            gx = BW[9 * lo : 9 * hi]
            Dc = self.moduli(g[lo:hi], self.w[lo:hi], out=D[: hi - lo])
            np.matmul(Dc, gx.reshape(-1, 9, m), out=DG[: hi - lo])
            out += gx.T @ DG[: hi - lo].reshape(-1, m)
        return 0.5 * (out + out.T)

    def add_transposed(self, lo: int, V: np.ndarray, out: np.ndarray) -> None:
        """``out += B_cᵀ V`` for the rows ``B_c`` of the points from ``lo`` (``V``: ``(9 c,
        m)``, ``out``: ``(N, m)``), compiled on ``B``'s own arrays (no slice of it made)."""
        B = self.B
        _transposed_kernel(B.indptr, B.indices, B.data, 9 * lo, V, out)

    def assemble(self, D: np.ndarray) -> sp.csr_matrix:
        """The sparse matrix ``Bᵀ D B`` (``N × N``) for the moduli ``D`` (:meth:`moduli`):
        element by element, ``K_e[(i,a),(j,b)] = Σ_q Σ_kl ∂_kφ_a D_q[(i,k),(j,l)] ∂_lφ_b``
        (compiled), then summed into CSR."""
        n_el, _, n_loc = self.element_dofs.shape
        Ke = np.empty((n_el, 3 * n_loc, 3 * n_loc))
        _assembly_kernel(self.shape_gradients, np.ascontiguousarray(D), Ke)
        idx = self.element_dofs.reshape(n_el, -1)
        rows = np.broadcast_to(idx[:, :, None], Ke.shape).ravel()
        cols = np.broadcast_to(idx[:, None, :], Ke.shape).ravel()
        N = self.B.shape[1]
        return sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(N, N))

    def quadratic_forms(self, g: np.ndarray, GX: np.ndarray, w=None) -> np.ndarray:
        """``xᵀ K_T x`` (no spin softening) for each column ``x`` whose gradients are
        ``GX`` (``n_q × 9 × m``), at the state of the gradients ``g``: the integrand of
        :meth:`moduli` evaluated on the columns without forming ``D`` (J per unit
        amplitude²; ``w``: the weights of those points, when not all of them)."""
        out = np.zeros(GX.shape[2])
        _form_kernel(
            np.ascontiguousarray(g),
            self.w if w is None else w,
            self.lam,
            self.mu,
            self.linear,
            np.ascontiguousarray(GX),
            out,
        )
        return out


def _stress_kernel(g, w, lam, mu, linear, P):  # pragma: no cover (compiled)
    """``P = w F S`` (first Piola–Kirchhoff stress × weight) at every point of ``g``."""
    F, S = np.empty((3, 3)), np.empty((3, 3))
    for q in range(g.shape[0]):
        _point_state(g[q], lam, mu, linear, F, S)
        for i in range(3):
            for j in range(3):
                P[q, i, j] = w[q] * (F[i, 0] * S[0, j] + F[i, 1] * S[1, j] + F[i, 2] * S[2, j])


def _point_state(g, lam, mu, linear, F, S):  # pragma: no cover (compiled)
    """``F``, ``S`` (3 × 3, filled in place) of one point (module docstring)."""
    trace = 0.0
    for i in range(3):
        for j in range(3):
            e = 0.5 * (g[i, j] + g[j, i])
            F[i, j] = 1.0 if i == j else 0.0
            if not linear:
                F[i, j] += g[i, j]
                e += 0.5 * (g[0, i] * g[0, j] + g[1, i] * g[1, j] + g[2, i] * g[2, j])
            S[i, j] = 2.0 * mu * e
            if i == j:
                trace += e
    for i in range(3):
        S[i, i] += lam * trace


def _moduli_kernel(g, w, lam, mu, linear, D):  # pragma: no cover (compiled)
    """``w D`` at every point of ``g``: ``g_xᵀ D g_y = λ tr(Fᵀ g_x) tr(Fᵀ g_y) + 2 μ
    sym(Fᵀ g_x) : sym(Fᵀ g_y) + g_x S : g_y``, rows ``(i, k)`` and columns ``(j, l)`` of the
    flattened gradients."""
    F, S, C = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    for q in range(g.shape[0]):
        _point_state(g[q], lam, mu, linear, F, S)
        for i in range(3):
            for j in range(3):
                C[i, j] = mu * (F[i, 0] * F[j, 0] + F[i, 1] * F[j, 1] + F[i, 2] * F[j, 2])
        wq = w[q]
        for i in range(3):
            for k in range(3):
                lam_ik = lam * F[i, k]
                for j in range(3):
                    for l in range(3):
                        # λ tr(Fᵀg) tr(Fᵀh) + 2μ sym(Fᵀg):sym(Fᵀh) + g S : h, with
                        # (Fᵀg)_kl = Σ_i F_ik g_il: the coefficient of g_ik h_jl is
                        # λ F_ik F_jl + μ F_il F_jk + μ (F Fᵀ)_ij δ_kl + δ_ij S_kl
                        v = lam_ik * F[j, l] + mu * F[i, l] * F[j, k]
                        if k == l:
                            v += C[i, j]
                        if i == j:
                            v += S[k, l]
                        D[q, 3 * i + k, 3 * j + l] = wq * v


def _form_kernel(g, w, lam, mu, linear, GX, out):  # pragma: no cover (compiled)
    """``out_c = Σ_q w_q (λ tr(A)² + 2 μ sym(A) : sym(A) + h S : h)`` with ``h`` the
    gradient ``GX[q, :, c]`` and ``A = Fᵀ h`` (the integrand of :func:`_moduli_kernel`)."""
    A, F, S = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    for q in range(g.shape[0]):
        _point_state(g[q], lam, mu, linear, F, S)
        for c in range(GX.shape[2]):
            for k in range(3):
                for l in range(3):
                    A[k, l] = F[0, k] * GX[q, l, c] + F[1, k] * GX[q, 3 + l, c]
                    A[k, l] += F[2, k] * GX[q, 6 + l, c]
            trace, sym2, geometric = 0.0, 0.0, 0.0
            for k in range(3):
                trace += A[k, k]
                for l in range(3):
                    e = 0.5 * (A[k, l] + A[l, k])
                    sym2 += e * e
            for i in range(3):
                for k in range(3):
                    hs = 0.0
                    for l in range(3):
                        hs += S[k, l] * GX[q, 3 * i + l, c]
                    geometric += GX[q, 3 * i + k, c] * hs
            out[c] += w[q] * (lam * trace * trace + 2.0 * mu * sym2 + geometric)


def _transposed_kernel(indptr, indices, data, row0, V, out):  # pragma: no cover (compiled)
    """``out += B_cᵀ V`` for the rows ``row0 … row0 + len(V)`` of the CSR matrix
    ``(indptr, indices, data)``."""
    for r in range(V.shape[0]):
        for p in range(indptr[row0 + r], indptr[row0 + r + 1]):
            c, b = indices[p], data[p]
            for j in range(V.shape[1]):
                out[c, j] += b * V[r, j]


def _assembly_kernel(dphi, D, Ke):  # pragma: no cover (compiled)
    """Element matrices ``Ke`` (``n_el × 3 n_loc × 3 n_loc``, rows ``(i, a)``) from the
    shape-function gradients ``dphi`` (``n_el × n_qp × 3 × n_loc``) and the moduli ``D``
    (``n_el n_qp × 9 × 9``, weights included)."""
    n_el, n_qp, _, n_loc = dphi.shape
    T = np.empty((9, 3, n_loc))
    for e in range(n_el):
        Ke[e] = 0.0
        for q in range(n_qp):
            p = e * n_qp + q
            g = dphi[e, q]
            for ik in range(9):
                for j in range(3):
                    for b in range(n_loc):
                        T[ik, j, b] = (
                            D[p, ik, 3 * j] * g[0, b]
                            + D[p, ik, 3 * j + 1] * g[1, b]
                            + D[p, ik, 3 * j + 2] * g[2, b]
                        )
            for i in range(3):
                for a in range(n_loc):
                    row = i * n_loc + a
                    for j in range(3):
                        for b in range(n_loc):
                            Ke[e, row, j * n_loc + b] += (
                                g[0, a] * T[3 * i, j, b]
                                + g[1, a] * T[3 * i + 1, j, b]
                                + g[2, a] * T[3 * i + 2, j, b]
                            )


if numba is not None:
    _assembly_kernel = numba.njit(cache=True, nogil=True)(_assembly_kernel)
    _point_state = numba.njit(cache=True, nogil=True)(_point_state)
    _stress_kernel = numba.njit(cache=True, nogil=True)(_stress_kernel)
    _moduli_kernel = numba.njit(cache=True, nogil=True)(_moduli_kernel)
    _form_kernel = numba.njit(cache=True, nogil=True)(_form_kernel)
    _transposed_kernel = numba.njit(cache=True, nogil=True)(_transposed_kernel)


def gradient_operator(basis, lam: float, mu: float, *, linear: bool = False) -> GradientOperator:
    """:class:`GradientOperator` of a vector scikit-fem ``basis`` (3D displacement).

    Each local basis function of a vector element has one non-zero component ``i``; its
    three derivatives ``∂φ/∂X_k`` at every quadrature point fill rows ``(q, i, k)`` of ``B``,
    which therefore holds as many entries per row as the element has nodes: ``B`` is built
    row-major directly (no sort).
    """
    n_el, n_qp = basis.dx.shape
    comps = [[], [], []]
    for a in range(basis.Nbfun):
        grad = basis.basis[a][0].grad  # (3, 3, n_el, n_qp): ∂φ_i/∂X_k
        comps[int(np.argmax(np.abs(grad[:, :, 0, :]).sum(axis=(1, 2))))].append(a)
    n_loc = len(comps[0])
    data = np.empty((n_el, n_qp, 3, 3, n_loc))
    cols = np.empty((n_el, n_qp, 3, 3, n_loc), dtype=np.int64)
    for i, local in enumerate(comps):
        for j, a in enumerate(local):
            data[:, :, i, :, j] = np.moveaxis(basis.basis[a][0].grad[i], 0, -1)
            cols[:, :, i, :, j] = basis.element_dofs[a][:, None, None]
    n_rows = 9 * n_el * n_qp
    indptr = np.arange(0, n_rows * n_loc + 1, n_loc, dtype=np.int64)
    B = sp.csr_matrix((data.ravel(), cols.ravel(), indptr), shape=(n_rows, basis.N))
    element_dofs = np.ascontiguousarray(cols[:, 0, :, 0, :], dtype=np.int32)
    # every component's rows hold the same scalar shape-function gradients
    shape_gradients = np.ascontiguousarray(data[:, :, 0])
    w = np.asarray(basis.dx, dtype=float).ravel()
    return GradientOperator(B, w, lam, mu, linear, element_dofs, shape_gradients)
