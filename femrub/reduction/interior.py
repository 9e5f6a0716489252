"""Interior solves of a full first-order model (paper Eq. 11).

A full :class:`~femrub.model.first_order.FirstOrderModel` carries the matrices of Eq. (2) in
``model.blocks`` (a :class:`~femrub.fem.assembly.ThermoelasticMatrices`); its first-order
operators are::

        [I  0   0  ]        [ 0      I      0    ]
    A = [0  M   0  ],   B = [−K^uu  −C^uu  −K^uθ ],   X = [u, v, θ]          (Eq. 9)
        [0  0  C^θθ]        [ 0     −C^θu  −K^θθ ]

:class:`InteriorSolver` solves ``B_ii x = r`` and ``B_iiᵀ y = r`` on the interior dofs (all but
the boundary dofs of Eq. 10) by block elimination with two sparse LU factorisations
(``K^uu_ii`` and ``K^θθ_ii``), never forming a dense inverse. :func:`condensed_solve` reuses
the ``K_ii`` factorisation to solve with the whole stiffness (boundary dofs free) by static
condensation. :class:`InteriorStiffness` is that factorisation alone: it can be made before
the model exists (the modal damping takes the full model's frequencies through it,
:mod:`femrub.reduction.modal_damping`) and handed to the solver, which then does not
factorise ``K_ii`` again. SI units: m, m/s, K; forces in N, heat rates in W.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from ..fem.assembly import ThermoelasticMatrices
from ..fem.linalg import sparse_lu

__all__ = ["InteriorSolver", "InteriorStiffness", "condensed_solve"]


class InteriorStiffness:
    """``K_ii`` (the stiffness without the boundary dofs ``mech_b``) and its factorisation.

    Parameters
    ----------
    K : (n_u, n_u) sparse stiffness (in the reduction's boundary coordinates, if any).
    mech_b : boundary positions in the u-block; the interior ones are the rest.
    """

    def __init__(self, K, mech_b: np.ndarray):
        K = sp.csr_matrix(K)
        self.mech_b = np.asarray(mech_b, dtype=int)
        self.mech_i = np.setdiff1d(np.arange(K.shape[0]), self.mech_b)
        self.K = K[self.mech_i][:, self.mech_i].tocsc()
        self.lu = _splu(self.K, "interior stiffness K_ii (is the structure clamped?)")

    def same(self, K_ii) -> bool:
        """Whether ``K_ii`` (CSC) is this stiffness, entry for entry."""
        A = self.K
        return (
            A is not None
            and A.shape == K_ii.shape
            and A.nnz == K_ii.nnz
            and all(
                np.array_equal(getattr(A, f), getattr(K_ii, f))
                for f in ("indptr", "indices", "data")
            )
        )

    def solve_K(self, rhs, trans: bool = False) -> np.ndarray:
        """``K_ii⁻¹ rhs`` (or ``K_ii⁻ᵀ rhs``)."""
        if self.lu is None:
            return np.zeros_like(np.asarray(rhs, dtype=float))
        return self.lu.solve(np.ascontiguousarray(rhs), trans="T" if trans else "N")

    def free(self) -> None:
        """Release the factorisation (a later solve raises ``RuntimeError``)."""
        if hasattr(self.lu, "free"):
            self.lu.free()
        self.lu, self.K = _Freed(), None


class InteriorSolver:
    """Solve with the interior block ``B_ii`` of Eq. (9) and its transpose.

    ``B_ii`` has the rows ``[u_i, v_i, θ_i]``::

        [ 0      I       0     ] [x_u]   [r_u]
        [−K_ii  −C_ii   −K^uθ_ii] [x_v] = [r_v]
        [ 0     −C^θu_ii −K^θθ_ii] [x_θ]   [r_θ]

    solved by block elimination (``x_v = r_u``, then ``x_θ``, then ``x_u``) with sparse LU
    factorisations of ``K_ii`` and ``K^θθ_ii``; the transposed system likewise.
    ``solve_K`` is also the shift-invert operator of the clamped modal problem.
    ``stiffness``: an :class:`InteriorStiffness` of the same ``K_ii`` (checked entry for
    entry), whose factorisation is then used instead of a new one.
    """

    def __init__(
        self,
        blocks: ThermoelasticMatrices,
        mech_i: np.ndarray,
        theta_i: np.ndarray,
        stiffness: InteriorStiffness | None = None,
    ):
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
        self._stiffness = None
        if stiffness is None:
            self._lu_K = _splu(self.K, "interior stiffness K_ii (is the structure clamped?)")
        elif not stiffness.same(self.K):
            raise ValueError("the interior stiffness given is not this model's K_ii")
        else:  # one copy of K_ii, released with the solver's (free)
            self._lu_K, self.K, self._stiffness = stiffness.lu, stiffness.K, stiffness
        self._lu_T = _splu(self.Ktt, "interior conductivity K^θθ_ii (is a temperature fixed?)")

    def free(self) -> None:
        """Release the two factorisations (about 0.5 GB for a Rotor 37 blade) and the
        interior blocks once no more solves are needed; a later solve raises
        ``RuntimeError``."""
        for name in ("_lu_K", "_lu_T"):
            lu = getattr(self, name)
            if hasattr(lu, "free"):
                lu.free()
            setattr(self, name, _Freed())
        if self._stiffness is not None:  # its copies of K_ii and of the factor's matrix
            self._stiffness.free()
        self.K = self.M = self.C = self.Kut = self.Ctu = self.Ctt = self.Ktt = None

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

    def solve(self, rhs) -> np.ndarray:
        """``B_ii⁻¹ rhs`` for a (n_i,) vector or (n_i, k) columns, dense or sparse (paper
        Eq. 11); many columns are solved :data:`BLOCK` at a time (:func:`_by_blocks`)."""
        if self.K is None:
            _Freed().solve(rhs)
        return _by_blocks(self._solve, rhs)

    def solve_transposed(self, rhs) -> np.ndarray:
        """``B_ii⁻ᵀ rhs``: the interior problem of the adjoint system (columns as in
        :meth:`solve`)."""
        if self.K is None:
            _Freed().solve(rhs)
        return _by_blocks(self._solve_transposed, rhs)

    def _solve(self, rhs: np.ndarray) -> np.ndarray:
        ru, rv, rt = self._split(rhs)
        xv = ru.copy()
        xt = -self.solve_T(rt + self.Ctu @ xv)
        xu = -self.solve_K(rv + self.C @ xv + self.Kut @ xt)
        return np.concatenate([xu, xv, xt], axis=0)

    def _solve_transposed(self, rhs: np.ndarray) -> np.ndarray:
        ru, rv, rt = self._split(rhs)
        yv = -self.solve_K(ru, trans=True)
        yt = -self.solve_T(rt + self.Kut.T @ yv, trans=True)
        yu = rv + self.C.T @ yv + self.Ctu.T @ yt
        return np.concatenate([yu, yv, yt], axis=0)


class _Freed:
    """Stands for a factorisation released by :meth:`InteriorSolver.free`."""

    def solve(self, rhs, trans="N"):
        raise RuntimeError("the interior factorisations were released (InteriorSolver.free)")


#: Columns solved together by :meth:`InteriorSolver.solve`: bounds the dense temporaries of
#: the block elimination (a few (n_i, BLOCK) arrays) for many right-hand sides.
BLOCK = 32


def _by_blocks(solve: Callable, rhs) -> np.ndarray:
    """``solve`` on a vector, or on the columns of a dense or sparse (n, k) ``rhs``
    :data:`BLOCK` at a time into one (n, k) array (a sparse ``rhs`` is never made dense
    whole)."""
    if not sp.issparse(rhs):
        rhs = np.asarray(rhs, dtype=float)
        if rhs.ndim == 1 or rhs.shape[1] <= BLOCK:
            return solve(rhs)
    else:
        rhs = sp.csc_matrix(rhs, dtype=float)
    out = np.empty(rhs.shape)
    for j in range(0, rhs.shape[1], BLOCK):
        block = rhs[:, j : j + BLOCK]
        out[:, j : j + BLOCK] = solve(block.toarray() if sp.issparse(block) else block)
    return out


def _splu(M, what: str):
    if M.shape[0] == 0:
        return None
    return sparse_lu(M, symmetric=True, what=what)


def condensed_solve(K, mech_b: np.ndarray, solver: InteriorSolver) -> Callable:
    """``f ↦ K⁻¹ f`` for the whole stiffness, from the interior factorisation of ``solver``.

    Static condensation on the boundary dofs ``b`` (the static shapes of Eq. 11)::

        Ψ = −K_ii⁻¹ K_ib,   S = K_bb + K_bi Ψ,   y = K_ii⁻¹ f_i,
        x_b = S⁻¹ (f_b − K_bi y),   x_i = y + Ψ x_b

    one ``K_ii`` solve per right-hand side and no factorisation of ``K``: the shift-invert
    operator of the full model's modes once a reductor has factorised ``K_ii``.
    ``mech_b`` are the boundary positions in the u-block; the interior ones are the rest.
    """
    K = sp.csr_matrix(K)
    mb = np.asarray(mech_b, dtype=int)
    mi = np.setdiff1d(np.arange(K.shape[0]), mb)
    K_bi = K[mb][:, mi]
    psi = -solver.solve_K(K[mi][:, mb].toarray())
    S = K[mb][:, mb].toarray() + K_bi @ psi

    def solve(f: np.ndarray) -> np.ndarray:
        y = solver.solve_K(f[mi])
        x_b = np.linalg.solve(S, f[mb] - K_bi @ y)
        x = np.empty(f.shape)
        x[mb], x[mi] = x_b, y + psi @ x_b
        return x

    return solve
