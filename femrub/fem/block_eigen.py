"""Lowest eigenpairs by block shift-invert Lanczos with thick restarts.

:func:`block_lowest` finds the ``k`` lowest eigenpairs of ``K x = λ M x`` (``K``, ``M``
symmetric positive definite) from the largest ones of ``T = K⁻¹ M``, self-adjoint in the
``M`` inner product, as ARPACK's shift-invert mode about σ = 0 does, but it applies ``T``
to a block of ``b`` vectors at a time: a sparse direct solver (Pardiso) solves ``b``
right-hand sides for a small multiple of the cost of one, where ARPACK makes one solve per
Lanczos step and reorthogonalises vector by vector.

A cycle extends an ``M``-orthonormal basis ``V`` by blocks: ``W = T Z`` for the last block
``Z``, orthogonalised twice against ``V`` (block classical Gram–Schmidt in the ``M``
product; the coefficients are the columns ``Vᵀ M T Z`` of ``H = Vᵀ M T V``) and
``M``-orthonormalised, ``W = Z' S``. The Rayleigh–Ritz step on ``H`` gives Ritz pairs
``(θ, x = V y)`` with residual ``T x − θ x = Z' S y_Z`` (``y_Z``: the rows of ``y`` on the
last block), so ``‖T x − θ x‖_M = ‖S y_Z‖``; a pair has converged when that is at most
``tol θ`` (ARPACK's test on the eigenvalues of its operator, with ``tol`` its ``tol``). The
next cycle restarts from the ``keep`` leading Ritz vectors (``H = diag(θ)`` on them) and
``Z'``, coupled to them by ``S y_Z``: nothing is solved twice. Memory: one ``(n, p + b)``
basis (``p`` the largest basis, :func:`block_sizes`), rotated in place by row blocks on a
restart.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

__all__ = ["block_lowest", "block_sizes"]

#: Most restart cycles before :func:`block_lowest` gives up.
MAX_CYCLES = 100
#: Rows of the basis combined at a time on a restart (bounds the temporaries).
ROWS = 8192
#: Block size: Pardiso solves 16 right-hand sides of a Rotor 37 blade's stiffness for
#: about 4 times the cost of one.
BLOCK = 16


def block_sizes(k: int) -> tuple[int, int, int]:
    """``(b, keep, p)``: block size, Ritz vectors kept on a restart and largest basis for
    ``k`` eigenpairs."""
    keep = k + max(4, k // 4)
    return BLOCK, keep, keep + max(4, min(10, keep // 10)) * BLOCK


def _m_orthonormal(W, M):
    """``(Z, S)`` with ``W = Z S`` on its numerically independent directions, ``Zᵀ M Z = I``
    (an eigen-decomposition of the Gram matrix)."""
    G = W.T @ (M @ W)
    s, U = np.linalg.eigh(0.5 * (G + G.T))
    s, U = s[::-1], U[:, ::-1]
    n = int(np.count_nonzero(s > 1e-12 * s[0])) if s.size and s[0] > 0 else 0
    root = np.sqrt(s[:n])
    return W @ (U[:, :n] / root), root[:, None] * U[:, :n].T


def _extend(W, V, M):
    """``(Z, C, S)``: ``W = V C + Z S`` with ``Z`` ``M``-orthonormal and ``M``-orthogonal
    to the ``M``-orthonormal ``V`` (two Gram–Schmidt passes)."""
    C = np.zeros((V.shape[1], W.shape[1]))
    S = np.eye(W.shape[1])
    for _pass in range(2):
        D = V.T @ (M @ W)
        W = W - V @ D
        C += D @ S
        W, S2 = _m_orthonormal(W, M)
        S = S2 @ S
    return W, C, S


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
    if p + b > n // 2:
        raise ValueError(f"{k} modes of {n} unknowns: use a dense eigen-solver")
    V, H = np.empty((n, p + b)), np.zeros((p + b, p + b))
    Z, _ = _m_orthonormal(np.random.default_rng(seed).standard_normal((n, b)), M)
    m = 0  # columns of V in use, Z is V[:, m : m + w]
    for _ in range(MAX_CYCLES):
        while True:  # add Z, then W = T Z split into V C + Z' S
            w = Z.shape[1]
            V[:, m : m + w] = Z
            TZ = np.asarray(solve(M @ Z), dtype=float).reshape(Z.shape)
            Z, C, S = _extend(TZ, V[:, : m + w], M)
            del TZ
            H[: m + w, m : m + w] = C
            H[m : m + w, : m + w] = C.T
            m += w
            if m + b > p or Z.shape[1] == 0:
                break
        theta, Y = sla.eigh(0.5 * (H[:m, :m] + H[:m, :m].T))
        j = min(keep, m)
        theta, Y = theta[::-1][:j], Y[:, ::-1][:, :j]
        coupling = S @ Y[m - w : m]  # T x_i − θ_i x_i = Z coupling[:, i]
        res = np.linalg.norm(coupling, axis=0)
        _rotate(V, Y)
        m = j
        if np.all(res[:k] <= tol * np.abs(theta[:k])) or Z.shape[1] == 0:
            lam = 1.0 / theta[:k]  # θ decreasing: λ increasing
            return (lam, V[:, :k].copy()) if vectors else lam
        H[:] = 0.0  # restart: diag(θ) on the Ritz vectors, coupled to Z
        H[np.arange(m), np.arange(m)] = theta
        w = Z.shape[1]
        H[m : m + w, :m] = coupling[:w]
        H[:m, m : m + w] = coupling[:w].T
    raise RuntimeError(f"block Lanczos: {k} eigenpairs not converged in {MAX_CYCLES} cycles")
