"""Blocks of a full first-order model (paper Eq. 9), its boundary and interior dofs.

A full :class:`~femrub.model.first_order.FirstOrderModel` built by :func:`femrub.first_order_model` has::

        [I  0   0  ]        [ 0      I      0    ]
    A = [0  M   0  ],   B = [−K^uu  −C^uu  −K^uθ ],   X = [u, v, θ]          (Eq. 9)
        [0  0  C^θθ]        [ 0     −C^θu  −K^θθ ]

:func:`split_blocks` reads ``M, C^uu, K^uu, K^uθ, C^θu, C^θθ, K^θθ`` back from ``A`` and ``B``
(and refuses a model that is not of this form, e.g. an already reduced one).
:func:`contact_boundary` finds the boundary dofs of the paper's Eq. (10) from the contact
data. :class:`InteriorSolver` solves ``B_ii x = r`` and ``B_iiᵀ y = r`` (paper Eq. 11) by
block elimination with two sparse LU factorisations (``K^uu_ii`` and ``K^θθ_ii``), never
forming a dense inverse. SI units: m, m/s, K; forces in N, heat rates in W.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..fem.linalg import sparse_lu
from ..model.first_order import FirstOrderModel

__all__ = ["ModelBlocks", "split_blocks", "contact_boundary", "InteriorSolver"]


@dataclass
class ModelBlocks:
    """The matrices of Eq. (2)/(9) of a full first-order model (all sparse CSR)."""

    M: sp.csr_matrix
    C: sp.csr_matrix
    K: sp.csr_matrix
    Kut: sp.csr_matrix
    Ctu: sp.csr_matrix
    Ctt: sp.csr_matrix
    Ktt: sp.csr_matrix

    @property
    def n_u(self) -> int:
        return self.M.shape[0]

    @property
    def n_t(self) -> int:
        return self.Ctt.shape[0]


def _nnz(a) -> int:
    a = sp.csr_matrix(a)
    a.eliminate_zeros()
    return a.nnz


def split_blocks(model: FirstOrderModel) -> ModelBlocks:
    """Read the Eq. (9) blocks of ``model``; ``ValueError`` if it is not of that form."""
    L = model.layout
    if L.n_u != L.n_v:
        raise ValueError("a full model needs as many displacement as velocity dofs (Eq. 9)")
    A, B = model.A.tocsr(), model.B.tocsr()
    u, v, t = L.u, L.v, L.t
    blk = lambda X, r, c: X[r][:, c].tocsr()  # noqa: E731
    checks = [
        _nnz(blk(A, u, u) - sp.identity(L.n_u)) == 0,
        _nnz(blk(B, u, v) - sp.identity(L.n_u)) == 0,
        _nnz(blk(B, u, u)) == 0,
        _nnz(blk(A, u, v)) == 0 and _nnz(blk(A, v, u)) == 0,
    ]
    if L.n_t:
        checks += [
            _nnz(blk(B, u, t)) == 0,
            _nnz(blk(B, t, u)) == 0,
            _nnz(blk(A, u, t)) == 0 and _nnz(blk(A, t, u)) == 0,
            _nnz(blk(A, v, t)) == 0 and _nnz(blk(A, t, v)) == 0,
        ]
    if not all(checks):
        raise ValueError(
            "the model is not a full first-order model of the form of paper Eq. (9) "
            "(A = diag(I, M, C^θθ), B = [[0, I, 0], [-K, -C, -K^uθ], [0, -C^θu, -K^θθ]]); "
            "was it already reduced?"
        )
    nt = L.n_t
    z = lambda r, c: sp.csr_matrix((r, c))  # noqa: E731
    return ModelBlocks(
        M=blk(A, v, v),
        C=-blk(B, v, v),
        K=-blk(B, v, u),
        Kut=-blk(B, v, t) if nt else z(L.n_u, 0),
        Ctu=-blk(B, t, v) if nt else z(0, L.n_u),
        Ctt=blk(A, t, t) if nt else z(0, 0),
        Ktt=-blk(B, t, t) if nt else z(0, 0),
    )


def _rows(M: np.ndarray, sl: slice) -> np.ndarray:
    return np.flatnonzero(np.any(np.asarray(M)[sl] != 0.0, axis=1))


def contact_boundary(model: FirstOrderModel) -> tuple[np.ndarray, np.ndarray]:
    """Boundary dofs of the paper's Eq. (10) from the contact data.

    Returns ``(mech, theta)``: positions inside the u-block (the same positions are used in
    the v-block, so ``u_b`` and ``v_b`` describe the same physical dofs) and inside the
    θ-block. ``mech`` is the union of the nonzero u-rows of ``contact.G`` and the nonzero
    v-rows of ``contact.Gv`` and ``contact.Hm``; ``theta`` the nonzero θ-rows of
    ``contact.Ht``.
    """
    c, L = model.contact, model.layout
    if c is None:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    mech = np.union1d(_rows(c.G, L.u), _rows(c.Gv, L.v))
    mech = np.union1d(mech, _rows(c.Hm, L.v))
    theta = _rows(c.Ht, L.t) if L.n_t else np.zeros(0, dtype=int)
    return mech.astype(int), theta.astype(int)


class InteriorSolver:
    """Solve with the interior block ``B_ii`` of Eq. (9) and its transpose.

    ``B_ii`` has the rows ``[u_i, v_i, θ_i]``::

        [ 0      I       0     ] [x_u]   [r_u]
        [−K_ii  −C_ii   −K^uθ_ii] [x_v] = [r_v]
        [ 0     −C^θu_ii −K^θθ_ii] [x_θ]   [r_θ]

    solved by block elimination (``x_v = r_u``, then ``x_θ``, then ``x_u``) with sparse LU
    factorisations of ``K_ii`` and ``K^θθ_ii``; the transposed system likewise.
    ``solve_K`` is also the shift-invert operator of the clamped modal problem.
    """

    def __init__(self, blocks: ModelBlocks, mech_i: np.ndarray, theta_i: np.ndarray):
        sub = lambda X, r, c: sp.csr_matrix(X)[r][:, c].tocsc()  # noqa: E731
        mi, ti = mech_i, theta_i
        self.K = sub(blocks.K, mi, mi)
        self.M = sub(blocks.M, mi, mi)
        self.C = sub(blocks.C, mi, mi)
        self.Kut = sub(blocks.Kut, mi, ti)
        self.Ctu = sub(blocks.Ctu, ti, mi)
        self.Ctt = sub(blocks.Ctt, ti, ti)
        self.Ktt = sub(blocks.Ktt, ti, ti)
        self.n_u, self.n_t = mi.size, ti.size
        self._lu_K = _splu(self.K, "interior stiffness K_ii (is the structure clamped?)")
        self._lu_T = _splu(self.Ktt, "interior conductivity K^θθ_ii (is a temperature fixed?)")

    def solve_K(self, rhs, trans: bool = False) -> np.ndarray:
        """``K_ii⁻¹ rhs`` (or ``K_ii⁻ᵀ rhs``)."""
        if self._lu_K is None:
            return np.zeros_like(np.asarray(rhs, dtype=float))
        return self._lu_K.solve(np.ascontiguousarray(rhs), trans="T" if trans else "N")

    def solve_T(self, rhs, trans: bool = False) -> np.ndarray:
        """``(K^θθ_ii)⁻¹ rhs`` (or its transpose)."""
        if self._lu_T is None:
            return np.zeros_like(np.asarray(rhs, dtype=float))
        return self._lu_T.solve(np.ascontiguousarray(rhs), trans="T" if trans else "N")

    def _split(self, r):
        nu, nt = self.n_u, self.n_t
        return r[:nu], r[nu : 2 * nu], r[2 * nu : 2 * nu + nt]

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``B_ii⁻¹ rhs`` for a (n_i,) vector or (n_i, k) columns (paper Eq. 11)."""
        rhs = np.asarray(rhs, dtype=float)
        ru, rv, rt = self._split(rhs)
        xv = ru.copy()
        xt = -self.solve_T(rt + self.Ctu @ xv)
        xu = -self.solve_K(rv + self.C @ xv + self.Kut @ xt)
        return np.concatenate([xu, xv, xt], axis=0)

    def solve_transposed(self, rhs: np.ndarray) -> np.ndarray:
        """``B_ii⁻ᵀ rhs``: the interior problem of the adjoint system."""
        rhs = np.asarray(rhs, dtype=float)
        ru, rv, rt = self._split(rhs)
        yv = -self.solve_K(ru, trans=True)
        yt = -self.solve_T(rt + self.Kut.T @ yv, trans=True)
        yu = rv + self.C.T @ yv + self.Ctu.T @ yt
        return np.concatenate([yu, yv, yt], axis=0)


def _splu(M, what: str):
    if M.shape[0] == 0:
        return None
    return sparse_lu(M, symmetric=True, what=what)
