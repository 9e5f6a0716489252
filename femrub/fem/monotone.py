"""Monotone conduction operator: the Galerkin conduction matrix made an M-matrix.

On tetrahedra with obtuse dihedral angles the P1 conduction matrix ``K^θθ`` has positive
off-diagonal entries, so the semi-discrete heat equation ``C^θθ θ̇ + K^θθ θ = q`` has no
discrete maximum principle: heat entering at the tip drives neighbours of the heated
vertices below the ambient temperature, with no sink anywhere (docs/reduction_3d.md). The
time scheme cannot cure it (backward Euler keeps it); a lumped ``C^θθ`` is necessary but
not sufficient.

Discrete upwinding (Kuzmin, Shashkov & Svyatskiy, J. Comput. Phys. 228 (2009) 3448; Kuzmin
& Möller 2005) adds the graph Laplacian ``D`` of the positive couplings::

    d_ij = −max(k_ij, 0)   (i ≠ j),        d_ii = −Σ_{j≠i} d_ij,
    K_mono = K^θθ + D

``K_mono`` is symmetric, its off-diagonal entries are ≤ 0 and its row sums equal those of
``K^θθ`` (a uniform temperature still carries no flux: conservative), so with a lumped
(diagonal, positive) ``C^θθ`` every θ-method step with ``Γ h`` large enough — backward Euler
for any step — maps non-negative data to non-negative temperatures. ``D`` is positive
semi-definite: the operator conducts more than Galerkin, by a first-order perturbation that
vanishes on meshes without obtuse angles (then ``K_mono = K^θθ``; always so for the 1D bar)
but costs accuracy where conduction carries heat over many elements, hence an option
(``physics.conduction``), not the default (docs/theory.md §1).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["CONDUCTIONS", "monotone", "positive_couplings", "conduction_operator"]

#: ``physics.conduction`` choices (the first is the default).
CONDUCTIONS = ("galerkin", "monotone")


def positive_couplings(K: sp.spmatrix) -> int:
    """Number of positive off-diagonal entries of ``K`` (0 for an M-matrix pattern)."""
    A = sp.coo_matrix(K)
    return int(np.count_nonzero((A.row != A.col) & (A.data > 0.0)))


def monotone(K: sp.spmatrix) -> sp.csr_matrix:
    """``K + D`` with ``D`` the discrete upwinding of the positive couplings (module docstring)."""
    A = sp.coo_matrix(K)
    pos = (A.row != A.col) & (A.data > 0.0)
    P = sp.csr_matrix((A.data[pos], (A.row[pos], A.col[pos])), shape=A.shape)
    return (sp.csr_matrix(K) - P + sp.diags(np.asarray(P.sum(axis=1)).ravel())).tocsr()


def conduction_operator(K: sp.spmatrix, method: str) -> sp.csr_matrix:
    """The conduction matrix of ``method`` in :data:`CONDUCTIONS` from the Galerkin ``K``."""
    if method == "galerkin":
        return sp.csr_matrix(K)
    if method == "monotone":
        return monotone(K)
    raise ValueError(f"unknown conduction {method!r}; use one of {', '.join(CONDUCTIONS)}")
