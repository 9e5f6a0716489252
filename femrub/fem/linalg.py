"""Small linear-algebra helpers: dense for small operators, sparse LU for large ones.

A scipy sparse mat-vec costs several microseconds of Python overhead whatever its size; for
the few-dozen-dof models of the paper (and for reduced models) dense numpy arrays are an
order of magnitude faster per step. Large finite-element operators stay sparse.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["DENSE_BELOW", "PARDISO_ABOVE", "compact", "Factorised", "sparse_lu"]

DENSE_BELOW = 600
#: Size above which MKL Pardiso (optional, ``pip install femrub[fast]``) replaces SuperLU:
#: on the 96k-dof Rotor 37 stiffness it factorises in 14 s against 107 s for SuperLU.
PARDISO_ABOVE = 20_000


class _Pardiso:
    """MKL Pardiso factorisation with the ``splu``-like ``solve(rhs, trans)`` interface."""

    def __init__(self, M, symmetric: bool):
        import pypardiso

        self.A = sp.csr_matrix(M, dtype=float)
        self.A.sort_indices()
        self.symmetric = symmetric
        self._s = pypardiso.PyPardisoSolver(mtype=11)
        self._s.set_iparm(8, 20)  # iterative refinement steps: residuals near round-off
        self._s.factorize(self.A)
        self._AT = None

    def __del__(self):
        # MKL keeps the factorisation until told to free it: without this, every solver
        # object leaks its factors (a Newton loop on the Rotor 37 tangent reached 24 GB)
        try:
            self._s.free_memory(everything=True)
        except Exception:  # interpreter shutdown, or a failed factorisation
            pass

    def solve(self, rhs, trans: str = "N"):
        if trans != "N" and not self.symmetric:
            if self._AT is None:
                self._AT = _Pardiso(self.A.T, False)
            return self._AT.solve(rhs)
        out = self._s.solve(self.A, np.asarray(rhs, dtype=float))
        return out.reshape(np.shape(rhs))


def sparse_lu(M, *, symmetric: bool = False, what: str = "matrix", pardiso: bool = True):
    """Sparse LU of ``M`` with ``solve(rhs, trans="N")``: Pardiso when large and installed,
    else SuperLU (minimum-degree ordering on ``A + Aᵀ`` for symmetric patterns).

    Pardiso pays off for one-off factorisations with many right-hand sides (reduction,
    eigen-solvers); a per-step solve is faster with SuperLU (0.26 ms against 3.7 ms on a
    20,000-unknown bar), so steppers pass ``pardiso=False``.
    """
    n = M.shape[0]
    try:
        if pardiso and n >= PARDISO_ABOVE:
            try:
                return _Pardiso(M, symmetric)
            except ImportError:
                pass
        spec = "MMD_AT_PLUS_A" if symmetric else "COLAMD"
        return spla.splu(sp.csc_matrix(M), permc_spec=spec)
    except RuntimeError as exc:
        raise ValueError(f"the {what} is singular ({exc})") from None


def compact(M, dense_below: int = DENSE_BELOW):
    """``M`` as a dense array when it is small, as CSR otherwise."""
    if sp.issparse(M):
        return M.toarray() if max(M.shape) < dense_below else M.tocsr()
    return np.asarray(M)


class Factorised:
    """LU factorisation of a constant square matrix: dense (LAPACK) when small, else SuperLU."""

    def __init__(self, M, dense_below: int = DENSE_BELOW, what: str = "matrix"):
        n = M.shape[0]
        self.dense = n < dense_below
        try:
            if self.dense:
                A = M.toarray() if sp.issparse(M) else np.asarray(M)
                self._lu = sla.lu_factor(A, check_finite=True)
                if np.any(np.diag(self._lu[0]) == 0.0):
                    raise np.linalg.LinAlgError("zero pivot")
            else:
                self._lu = sparse_lu(M, what=what, pardiso=False)
        except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
            raise ValueError(f"the {what} is singular or not finite ({exc})") from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``M⁻¹ rhs`` for a vector or a 2D array of columns."""
        if self.dense:
            return sla.lu_solve(self._lu, rhs, check_finite=False)
        return self._lu.solve(np.ascontiguousarray(rhs))
