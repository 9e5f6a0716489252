"""Lowest eigenpairs by block shift-invert Lanczos with thick restarts.

:func:`block_lowest` finds the ``k`` lowest eigenpairs of ``K x = λ M x`` (``K``, ``M``
symmetric positive definite) from the largest ones of ``T = K⁻¹ M``, self-adjoint in the
``M`` inner product, as ARPACK's shift-invert mode about σ = 0 does, but it applies ``T``
to a block of ``b`` vectors at a time: a sparse direct solver (Pardiso) solves ``b``
right-hand sides for a small multiple of the cost of one, where ARPACK makes one solve per
Lanczos step (and reorthogonalises vector by vector).

One cycle extends an ``M``-orthonormal basis ``V`` by blocks ``Z_{j+1} = T Z_j``
(orthogonalised twice against ``V``, block classical Gram–Schmidt in the ``M`` product),
keeping ``T V`` beside it and ``H = Vᵀ M T V`` up to date, then makes the Rayleigh–Ritz step
on ``H``. A Ritz pair ``(θ, x)`` has converged when its residual ``‖T x − θ x‖_M <= tol θ``
(ARPACK's test on the eigenvalues of its operator, with ``tol`` its ``tol``). The next
cycle restarts from the ``keep`` leading Ritz vectors (``H`` is then ``diag(θ)``) and the
block of their residuals, which spans one block (the continuation of the Krylov space):
nothing is solved twice. Memory: two ``(n, p)`` arrays (``V``, ``T V``), ``p`` the largest
basis; the restart overwrites them row block by row block.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

__all__ = ["block_lowest", "block_sizes"]

#: Most restart cycles before :func:`block_lowest` gives up.
MAX_CYCLES = 100
#: Rows of ``V`` combined at a time on a restart (bounds the temporaries).
ROWS = 8192


def block_sizes(k: int) -> tuple[int, int, int]:
    """``(b, keep, p)``: block size, Ritz vectors kept on a restart and largest basis for
    ``k`` eigenpairs."""
    b = int(min(max(8, k // 3), 32))
    keep = k + max(4, k // 4)
    return b, keep, keep + 4 * b


def _m_orthonormal(Z, M, most: int) -> np.ndarray:
    """At most ``most`` ``M``-orthonormal columns spanning the leading directions of ``Z``
    (an eigen-decomposition of its Gram matrix; numerically dependent directions dropped)."""
    G = Z.T @ (M @ Z)
    s, U = np.linalg.eigh(0.5 * (G + G.T))
    s, U = s[::-1], U[:, ::-1]
    good = int(np.count_nonzero(s > 1e-12 * s[0])) if s.size and s[0] > 0 else 0
    n = min(most, good)
    return Z @ (U[:, :n] / np.sqrt(s[:n]))


def _orthogonalise(Z, V, M, most: int) -> np.ndarray:
    """``Z`` made ``M``-orthogonal to the ``M``-orthonormal ``V`` (twice) and
    ``M``-orthonormal itself (at most ``most`` columns)."""
    for _pass in range(2):
        if V.shape[1]:
            Z = Z - V @ (V.T @ (M @ Z))
        Z = _m_orthonormal(Z, M, most)
    return Z


def _rotate(A, Y) -> None:
    """``A[:, :Y.shape[1]] = A[:, :Y.shape[0]] @ Y`` in place, by row blocks."""
    r, c = Y.shape
    for s in range(0, A.shape[0], ROWS):
        A[s : s + ROWS, :c] = A[s : s + ROWS, :r] @ Y


def block_lowest(K, M, k: int, solve, *, tol: float = 1e-12, seed: int = 0, vectors=True):
    """The ``k`` lowest eigenpairs of ``K x = λ M x`` (module docstring).

    Parameters
    ----------
    K, M : (n, n) sparse, symmetric positive definite (``K`` is only used through ``solve``).
    k : number of eigenpairs; the largest basis (:func:`block_sizes`) must fit in ``n / 2``.
    solve : callable ``(n, b) array -> K⁻¹ array`` (a factorisation of ``K``).
    tol : relative residual of the Ritz pairs of ``T = K⁻¹ M`` (ARPACK's ``tol``).
    seed : seed of the random start block (the result does not depend on it beyond ``tol``).
    vectors : also return the shapes.

    Returns
    -------
    lam : (k,) eigenvalues in increasing order; V : (n, k) ``M``-orthonormal shapes
    (when ``vectors``).
    """
    n = K.shape[0]
    b, keep, p = block_sizes(k)
    if p > n // 2:
        raise ValueError(f"{k} modes of {n} unknowns: use a dense eigen-solver")
    V, TV, H = np.empty((n, p)), np.empty((n, p)), np.zeros((p, p))
    Z = _orthogonalise(np.random.default_rng(seed).standard_normal((n, b)), V[:, :0], M, b)
    m = 0  # columns of V in use
    for _ in range(MAX_CYCLES):
        while True:  # extend V by blocks Z, T Z, T² Z, ... up to p columns
            w = Z.shape[1]
            V[:, m : m + w] = Z
            TV[:, m : m + w] = np.asarray(solve(M @ Z), dtype=float).reshape(Z.shape)
            H[: m + w, m : m + w] = V[:, : m + w].T @ (M @ TV[:, m : m + w])
            H[m : m + w, :m] = H[:m, m : m + w].T
            m += w
            if m + b > p or w == 0:
                break
            Z = _orthogonalise(TV[:, m - w : m], V[:, :m], M, b)
        theta, Y = sla.eigh(0.5 * (H[:m, :m] + H[:m, :m].T))
        j = min(keep, m)
        theta, Y = theta[::-1][:j], Y[:, ::-1][:, :j]
        _rotate(V, Y)
        _rotate(TV, Y)
        m = j
        R = TV[:, :m] - V[:, :m] * theta  # residuals of the Ritz pairs
        res = np.sqrt(np.maximum(np.einsum("ij,ij->j", R, M @ R), 0.0))
        if np.all(res[:k] <= tol * np.abs(theta[:k])) or m + b > n:
            lam = 1.0 / theta[:k]  # θ decreasing: λ increasing
            return (lam, V[:, :k].copy()) if vectors else lam
        # restart: H = diag(θ) on the Ritz vectors, extended along their residuals' block
        H[:] = 0.0
        H[np.arange(m), np.arange(m)] = theta
        Z = _orthogonalise(R, V[:, :m], M, b)
        del R
    raise RuntimeError(f"block Lanczos: {k} eigenpairs not converged in {MAX_CYCLES} cycles")
