"""Block shift-invert Lanczos (femrub.fem.block_eigen) against dense LAPACK and ARPACK."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from femrub.fem import eigen
from femrub.fem.block_eigen import block_lowest, block_sizes


def _grid(m: int):
    """A 2D anisotropic Laplacian (distinct eigenvalues, some close) and a lumped mass."""
    D = sp.diags([-np.ones(m - 1), 2.0 * np.ones(m), -np.ones(m - 1)], [-1, 0, 1])
    Id = sp.identity(m)
    K = (sp.kron(D, Id) + 1.37 * sp.kron(Id, D)).tocsc()
    M = sp.diags(np.random.default_rng(3).uniform(0.5, 1.5, m * m)).tocsc()
    return K, M


@pytest.mark.parametrize("k", [1, 5, 30])
def test_block_lowest_matches_dense(k):
    K, M = _grid(40)  # 1600 unknowns
    lam_ref = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True, subset_by_index=[0, k - 1])
    calls = []
    lu = spla.splu(K)

    def solve(rhs):
        calls.append(rhs.shape)
        return lu.solve(rhs)

    lam, V = block_lowest(K, M, k, solve)
    np.testing.assert_allclose(lam, lam_ref, rtol=1e-10)
    np.testing.assert_allclose(V.T @ (M @ V), np.eye(k), atol=1e-10)
    res = np.linalg.norm(K @ V - (M @ V) * lam, axis=0) / np.linalg.norm(K @ V, axis=0)
    assert res.max() < 1e-8
    b = block_sizes(k)[0]
    assert all(s[1] <= b for s in calls) and max(s[1] for s in calls) > 1  # blocks solved
    only = block_lowest(K, M, k, lu.solve, vectors=False)
    np.testing.assert_allclose(only, lam, rtol=1e-12)


def test_block_lowest_rejects_a_basis_larger_than_half_the_problem():
    K, M = _grid(8)  # 64 unknowns
    with pytest.raises(ValueError, match="dense"):
        block_lowest(K, M, 20, spla.splu(K).solve)


def test_lowest_modes_block_path_equals_arpack_path(monkeypatch):
    K, M = _grid(34)  # 1156 unknowns
    lam_a, V_a = eigen.lowest_modes(K, M, 20)  # ARPACK (below BLOCK_EIGEN_ABOVE)
    monkeypatch.setattr(eigen, "BLOCK_EIGEN_ABOVE", 500)
    monkeypatch.setattr(eigen, "BLOCK_EIGEN_MODES", 3)
    lam_b, V_b = eigen.lowest_modes(K, M, 20)
    np.testing.assert_allclose(lam_b, lam_a, rtol=1e-11)
    np.testing.assert_allclose(V_b, V_a, atol=1e-8)  # same normalisation: same shapes
    # a free structure (singular K) is shifted as on the ARPACK path
    free = (
        1e4
        * sp.diags(
            [-np.ones(599), np.r_[1.0, 2.0 * np.ones(598), 1.0], -np.ones(599)], [-1, 0, 1]
        ).tocsc()
    )
    lam = eigen.lowest_modes(free, sp.identity(600), 3, vectors=False)
    exact = 1e4 * (2.0 - 2.0 * np.cos(np.arange(3) * np.pi / 600))
    np.testing.assert_allclose(lam, exact, atol=1e-9)
