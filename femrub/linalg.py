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

__all__ = ["DENSE_BELOW", "compact", "Factorised"]

DENSE_BELOW = 600


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
                self._lu = spla.splu(sp.csc_matrix(M))
        except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
            raise ValueError(f"the {what} is singular or not finite ({exc})") from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``M⁻¹ rhs`` for a vector or a 2D array of columns."""
        if self.dense:
            return sla.lu_solve(self._lu, rhs, check_finite=False)
        return self._lu.solve(np.ascontiguousarray(rhs))
