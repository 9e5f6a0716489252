"""Mass lumping: row-sum for linear elements, HRZ for quadratic ones.

Row-sum lumping of a P2 mass matrix gives zero or negative vertex masses on tetrahedra, so
quadratic elements use the HRZ scheme (Hinton, Rock, Zienkiewicz 1976): keep the diagonal of
the consistent matrix and scale it, per field component, so the total mass is preserved::

    M_lumped = diag(M) * (1ᵀ M 1) / (1ᵀ diag(M))

applied to each displacement component separately (the scaling is global rather than per
element, which is exact for uniform density and keeps every entry positive).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["row_sum", "hrz", "hrz_of", "lump"]


def row_sum(matrix: sp.spmatrix) -> sp.csr_matrix:
    """Diagonal matrix of the row sums of ``matrix``."""
    return sp.diags(np.asarray(matrix.sum(axis=1)).ravel()).tocsr()


def hrz(matrix: sp.spmatrix, n_components: int = 1) -> sp.csr_matrix:
    """HRZ lumping: scaled diagonal, preserving the total mass of every component.

    Parameters
    ----------
    matrix
        Consistent mass (or heat-capacity) matrix.
    n_components
        Number of interleaved field components (3 for a 3D displacement in scikit-fem's
        ``ElementVector`` ordering, where component ``c`` has dofs ``c::n_components``).
    """
    diag = matrix.diagonal().astype(float)
    ones = np.ones(matrix.shape[0])
    totals = []
    for c in range(n_components):
        sel = np.zeros_like(ones)
        sel[c::n_components] = 1.0
        totals.append(sel @ (matrix @ sel))
    return _hrz(diag, totals, n_components)


def hrz_of(diagonal: np.ndarray, row_sums: np.ndarray, n_components: int = 1) -> sp.csr_matrix:
    """:func:`hrz` from the consistent matrix's ``diagonal`` and ``row_sums`` alone (a mass
    without coupling between components: component ``c``'s total is the sum of its rows),
    so that the consistent matrix need not be assembled."""
    d, r = np.asarray(diagonal, dtype=float), np.asarray(row_sums, dtype=float)
    return _hrz(d, [r[c::n_components].sum() for c in range(n_components)], n_components)


def _hrz(diag: np.ndarray, totals, n_components: int) -> sp.csr_matrix:
    out = np.empty_like(diag)
    for c in range(n_components):
        out[c::n_components] = diag[c::n_components] * totals[c] / diag[c::n_components].sum()
    if np.any(out <= 0.0):
        raise ValueError("HRZ lumping produced a non-positive mass; check the density and mesh")
    return sp.diags(out).tocsr()


def lump(matrix: sp.spmatrix, method: str, n_components: int = 1) -> sp.csr_matrix:
    """Lump ``matrix`` with ``method`` in {"consistent", "row-sum", "hrz"}."""
    if method == "consistent":
        return sp.csr_matrix(matrix)
    if method == "row-sum":
        return row_sum(matrix)
    if method == "hrz":
        return hrz(matrix, n_components)
    raise ValueError(f"unknown lumping {method!r}; use 'consistent', 'row-sum' or 'hrz'")
