"""Clamped-boundary modes of the interior (paper Sec. 2, "dynamic shapes").

The mechanical modes solve ``K_ii φ = ω² M_ii φ`` and the thermal modes
``K^θθ_ii χ = μ C^θθ_ii χ`` with the boundary dofs held at zero, uncoupled (paper, after
Eq. 11). Only the ``k`` modes of lowest eigenvalue are computed: ARPACK (``eigsh``) in
shift-invert mode about σ = 0, reusing the LU factorisation of the stiffness already made
for the static shapes; small problems use LAPACK (``eigh``) on dense matrices.

Shapes are normalised to a unit largest amplitude, with that entry positive, so the modal
coordinates carry the units of the physical dofs (m, m/s, K) and the reduced matrices stay
well scaled; the sign makes the basis deterministic.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from threadpoolctl import threadpool_limits

__all__ = ["DENSE_MODES_BELOW", "clamped_modes", "normalise_columns"]

#: Interior sizes below which the dense LAPACK eigensolver is used.
DENSE_MODES_BELOW = 400


def normalise_columns(V: np.ndarray) -> np.ndarray:
    """Scale each column to a largest absolute entry of +1."""
    V = np.array(V, dtype=float, copy=True)
    if V.size == 0:
        return V
    idx = np.argmax(np.abs(V), axis=0)
    peak = V[idx, np.arange(V.shape[1])]
    peak[peak == 0.0] = 1.0
    return V / peak


def clamped_modes(K, M, k: int, solve=None, *, tol: float = 1e-12):
    """The ``k`` lowest eigenpairs of ``K x = λ M x`` (K, M symmetric, M positive).

    Parameters
    ----------
    K, M : sparse (n, n) stiffness-like and mass-like matrices of the interior.
    k : number of modes (0 <= k <= n).
    solve : optional callable ``rhs -> K⁻¹ rhs`` (an existing factorisation), used as the
        shift-invert operator of ``eigsh`` with σ = 0.

    Returns
    -------
    lam : (k,) eigenvalues in increasing order (ω² in rad²/s², or μ in 1/s).
    V : (n, k) shapes, normalised by :func:`normalise_columns`.
    """
    n = K.shape[0]
    if not 0 <= k <= n:
        raise ValueError(f"asked for {k} modes of a {n}-dof interior problem")
    if k == 0:
        return np.zeros(0), np.zeros((n, 0))
    if n < DENSE_MODES_BELOW or k >= n - 1:
        Kd = K.toarray() if sp.issparse(K) else np.asarray(K)
        Md = M.toarray() if sp.issparse(M) else np.asarray(M)
        with threadpool_limits(limits=1, user_api="blas"):  # threads only slow small problems
            lam, V = sla.eigh(Kd, Md, subset_by_index=[0, k - 1])
    else:
        opinv = None
        if solve is not None:
            opinv = spla.LinearOperator((n, n), matvec=solve, dtype=float)
        lam, V = spla.eigsh(
            sp.csc_matrix(K), k=k, M=sp.csc_matrix(M), sigma=0.0, which="LM", OPinv=opinv, tol=tol
        )
        order = np.argsort(lam)
        lam, V = lam[order], V[:, order]
    return np.asarray(lam), normalise_columns(V)
