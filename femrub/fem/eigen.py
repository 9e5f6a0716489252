"""The eigen-solvers of femrub, in one place.

* :func:`lowest_modes`: the ``k`` lowest eigenpairs of ``K x = λ M x`` (``K``, ``M``
  symmetric, ``M`` positive): LAPACK ``eigh`` on dense matrices below
  :data:`DENSE_EIGEN_BELOW` unknowns, else shift-invert about σ = 0, by block Lanczos
  (:mod:`femrub.fem.block_eigen`) for many modes of a large problem (from
  :data:`BLOCK_EIGEN_MODES` modes and :data:`BLOCK_EIGEN_ABOVE` unknowns), otherwise by
  ARPACK ``eigsh``, reusing a given factorisation of ``K`` (``solve``) or factorising ``K`` with
  :func:`~femrub.fem.linalg.sparse_lu` (Pardiso's Cholesky on large problems). Shapes are
  normalised to a unit largest amplitude, with that entry positive
  (:func:`normalise_columns`), so modal coordinates carry the units of the physical dofs and
  the basis is deterministic.
* :func:`angular_frequencies`, :func:`natural_frequencies`: ``ω = √λ`` (rad/s) and
  ``f = ω / 2π`` (Hz) of the lowest modes; a free structure (singular ``K``) is shifted.
* :func:`largest_modulus`: the largest ``|λ|`` of ``A⁻¹ B`` (non-symmetric), which bounds
  the step of an explicit scheme (``h < 2 / |λ|_max``).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .. import progress
from ..blas import one_blas_thread
from .block_eigen import block_lowest, block_sizes
from .linalg import sparse_lu

__all__ = [
    "DENSE_EIGEN_BELOW",
    "angular_frequencies",
    "hermitian_solver",
    "largest_modulus",
    "lowest_hermitian_modes",
    "lowest_modes",
    "natural_frequencies",
    "normalise_columns",
    "orient_columns",
]

#: Problem sizes below which dense LAPACK solvers replace ARPACK.
DENSE_EIGEN_BELOW = 400
#: Shift used when the stiffness is singular (free structure): σ = −1 rad²/s².
FREE_SHIFT = -1.0
#: Problem sizes from which block shift-invert Lanczos (:mod:`femrub.fem.block_eigen`)
#: replaces ARPACK for :data:`BLOCK_EIGEN_MODES` modes or more: where the factorisation is
#: Pardiso's (from :data:`~femrub.fem.linalg.PARDISO_ABOVE`), whose solves of a block of
#: right-hand sides cost a small multiple of one, and ARPACK's vector-by-vector
#: reorthogonalisation of a basis of ``2 k + 1`` vectors costs as much as its solves
#: (docs/performance.md).
BLOCK_EIGEN_ABOVE = 20_000
#: Fewest modes for which the block solver is used (fewer: ARPACK is as fast).
BLOCK_EIGEN_MODES = 16


def _dense(M) -> np.ndarray:
    return M.toarray() if sp.issparse(M) else np.asarray(M)


def normalise_columns(V: np.ndarray) -> np.ndarray:
    """Scale each column to a largest absolute entry of +1."""
    V = np.array(V, dtype=float, copy=True)
    if V.size == 0:
        return V
    idx = np.argmax(np.abs(V), axis=0)
    peak = V[idx, np.arange(V.shape[1])]
    peak[peak == 0.0] = 1.0
    return V / peak


def orient_columns(V: np.ndarray, tie: float = 1e-8) -> np.ndarray:
    """Shapes with the first of their largest entries (ties within ``tie``) positive.

    :func:`normalise_columns` makes the largest entry positive; when two entries tie (a
    mirror-symmetric mode), round-off picks one, and it changes with the number of modes
    solved for. This sign is the same for any number of modes, so a basis truncated to its
    leading columns equals one computed at that size (the Craig–Bampton reductor's
    ``reduce(dims)``).
    """
    if V.size == 0:
        return V
    mag = np.abs(V)
    first = np.argmax(mag >= (1.0 - tie) * mag.max(axis=0), axis=0)
    return V * np.where(V[first, np.arange(V.shape[1])] < 0.0, -1.0, 1.0)


def lowest_modes(K, M, k: int, solve=None, *, tol: float = 1e-12, vectors: bool = True):
    """The ``k`` lowest eigenpairs of ``K x = λ M x``.

    Parameters
    ----------
    K, M : (n, n) sparse or dense, symmetric; ``M`` positive definite.
    k : number of modes (0 <= k <= n).
    solve : optional callable ``rhs -> K⁻¹ rhs`` (an existing factorisation), used as the
        shift-invert operator about σ = 0; without it ``K`` is factorised here, and shifted by
        :data:`FREE_SHIFT` when singular.
    vectors : also return the shapes.

    Returns
    -------
    lam : (k,) eigenvalues in increasing order (ω² in rad²/s², or μ in 1/s).
    V : (n, k) shapes normalised by :func:`normalise_columns` (when ``vectors``).
    """
    n = K.shape[0]
    if not 0 <= k <= n:
        raise ValueError(f"asked for {k} modes of a {n}-dof problem")
    if k == 0:
        return (np.zeros(0), np.zeros((n, 0))) if vectors else np.zeros(0)
    if n < DENSE_EIGEN_BELOW or k >= n - 1:
        with one_blas_thread:  # threads only slow small problems
            out = sla.eigh(
                _dense(K), _dense(M), subset_by_index=[0, k - 1], eigvals_only=not vectors
            )
        lam, V = (out, None) if not vectors else out
    else:
        b, _, p = block_sizes(k)
        block = n >= BLOCK_EIGEN_ABOVE and k >= BLOCK_EIGEN_MODES and p + b <= n // 2
        name = "block shift-invert Lanczos" if block else "ARPACK"
        with progress.phase(f"eigen-solve: {k} lowest modes of {n} unknowns ({name})"):
            lam, V = _shift_invert_lowest(K, M, k, solve, tol, vectors, block)
    lam = np.asarray(lam)
    return (lam, normalise_columns(V)) if vectors else lam


def _shift_invert_lowest(K, M, k, solve, tol, vectors, block):
    """Shift-invert about σ = 0 (or :data:`FREE_SHIFT` when ``K`` is singular) with
    ``solve`` or a factorisation made here; block Lanczos (``block``) or ARPACK, sorted."""
    n = K.shape[0]
    Kc, Mc = sp.csc_matrix(K), sp.csc_matrix(M)
    sigma = 0.0
    if solve is None:
        try:
            solve = sparse_lu(Kc, symmetric=True, what="stiffness").solve
        except ValueError:  # singular stiffness: a free structure
            sigma = FREE_SHIFT
            lu = sparse_lu(Kc - FREE_SHIFT * Mc, symmetric=True, what="shifted stiffness")
            solve = lu.solve
    if block:
        out = block_lowest(Kc, Mc, k, solve, tol=tol, vectors=vectors)
        lam, V = out if vectors else (out, None)
        return lam + sigma, V
    opinv = spla.LinearOperator((n, n), matvec=solve, dtype=float)
    kw = dict(k=k, M=Mc, which="LM", tol=tol, return_eigenvectors=vectors, v0=start_vector(n))
    out = spla.eigsh(Kc, sigma=sigma, OPinv=opinv, **kw)
    lam, V = out if vectors else (out, None)
    order = np.argsort(lam)
    return lam[order], None if V is None else V[:, order]


def angular_frequencies(K, M, k: int, solve=None, *, tol: float = 1e-12) -> np.ndarray:
    """The ``k`` lowest angular frequencies ``ω`` (rad/s) of ``K φ = ω² M φ``.

    ``tol``: relative accuracy asked of the eigenvalues ``ω²`` (ARPACK)."""
    lam = lowest_modes(K, M, min(k, K.shape[0]), solve, vectors=False, tol=tol)
    return np.sqrt(np.clip(lam, 0.0, None))


def natural_frequencies(K, M, k: int) -> np.ndarray:
    """The ``k`` lowest natural frequencies (Hz) of ``K φ = ω² M φ``."""
    return angular_frequencies(K, M, k) / (2.0 * np.pi)


def largest_modulus(A, B) -> float:
    """Largest ``|λ|`` of ``B x = λ A x`` (``A`` invertible; ARPACK above the dense size)."""
    n = A.shape[0]
    if n < DENSE_EIGEN_BELOW:
        ev = sla.eigvals(_dense(B), _dense(A))
        ev = ev[np.isfinite(ev)]
        return float(np.max(np.abs(ev))) if ev.size else 0.0
    lu = spla.splu(sp.csc_matrix(A))
    Bc = sp.csr_matrix(B)
    op = spla.LinearOperator((n, n), matvec=lambda x: lu.solve(Bc @ x), dtype=float)
    ev = spla.eigs(op, k=2, which="LM", return_eigenvectors=False, tol=1e-6, maxiter=5000)
    return float(np.max(np.abs(ev)))


def start_vector(n: int, dtype=float) -> np.ndarray:
    """ARPACK's start vector: the same pseudo-random ``(n,)`` vector on every call (ARPACK's
    own is random), so the modes of a cluster of nearly equal frequencies, and the last digits
    of every mode, are the same from one run to the next."""
    rng = np.random.default_rng(0)
    v = rng.standard_normal(n)
    return v + 1j * rng.standard_normal(n) if np.issubdtype(dtype, np.complexfloating) else v


def ritz_refined(K, M, V, solve):
    """One inverse iteration ``W = K⁻¹ M V`` and the Rayleigh–Ritz pairs of ``(K, M)`` on
    ``span W``.

    ARPACK's shift-invert converges on ``K⁻¹ M x = θ x``; its residual there, carried back
    to ``K x − λ M x``, grows with the conditioning of ``K``. After one inverse iteration
    ``K w − λ M w = M (x − λ K⁻¹ M x)``: the shift-invert residual itself, so the lowest
    modes of a stiff structure reach the residual of their sector to round-off.

    Returns
    -------
    lam : (k,) eigenvalues, increasing.
    V : (n, k) shapes, ``M``-normalised.
    """
    W = np.column_stack([solve(M @ v) for v in V.T])
    Kw, Mw = W.conj().T @ (K @ W), W.conj().T @ (M @ W)
    lam, Y = sla.eigh(0.5 * (Kw + Kw.conj().T), 0.5 * (Mw + Mw.conj().T))
    return lam, W @ Y


def _real_solve(lu, rhs):
    rhs = np.asarray(rhs, dtype=complex)
    return lu.solve(np.ascontiguousarray(rhs.real)) + 1j * lu.solve(np.ascontiguousarray(rhs.imag))


def hermitian_solver(K, what: str = "cyclic stiffness"):
    """``rhs -> K⁻¹ rhs`` for a complex Hermitian positive definite sparse ``K`` (n, n).

    ``K = A + iB`` (``A`` symmetric, ``B`` antisymmetric) is factorised once as the real
    symmetric ``[[A, −B], [B, A]]`` (:func:`~femrub.fem.linalg.sparse_lu`); the solver takes
    a complex vector or ``(n, m)`` block.
    """
    n = K.shape[0]
    Kc = sp.csc_matrix(K, dtype=complex)
    if not np.any(Kc.imag.data):  # a real K (k = 0, N/2): its own factor, half the size
        Kr = sp.csc_matrix((np.ascontiguousarray(Kc.data.real), Kc.indices, Kc.indptr), Kc.shape)
        lu_real = sparse_lu(Kr, symmetric=True, what=what)
        return lambda rhs: _real_solve(lu_real, rhs)
    real = sp.bmat([[Kc.real, -Kc.imag], [Kc.imag, Kc.real]]).tocsc()
    lu = sparse_lu(real, symmetric=True, what=what)

    def solve(rhs):
        rhs = np.asarray(rhs, dtype=complex)
        z = lu.solve(np.concatenate([rhs.real, rhs.imag]))
        return z[:n] + 1j * z[n:]

    return solve


def lowest_hermitian_modes(K, M, k: int, *, tol: float = 1e-12, solve=None):
    """The ``k`` lowest eigenpairs of ``K x = λ M x`` with ``K``, ``M`` complex Hermitian
    (``M`` positive definite), as the cyclic-symmetry problems of one nodal diameter.

    Dense LAPACK ``eigh`` below :data:`DENSE_EIGEN_BELOW` unknowns, else ARPACK in complex
    arithmetic, shift-invert about σ = 0 with ``solve`` (``rhs -> K⁻¹ rhs``; by default
    :func:`hermitian_solver` of ``K``).

    Returns
    -------
    lam : (k,) real eigenvalues in increasing order (ω² in rad²/s²).
    V : (n, k) complex shapes, ``M``-normalised.
    """
    n = K.shape[0]
    if not 0 < k <= n:
        raise ValueError(f"asked for {k} modes of a {n}-dof problem")
    if n < DENSE_EIGEN_BELOW or k >= n - 1:
        with one_blas_thread:
            return sla.eigh(_dense(K), _dense(M), subset_by_index=[0, k - 1])
    Kc, Mc = sp.csc_matrix(K, dtype=complex), sp.csc_matrix(M, dtype=complex)
    solve = hermitian_solver(Kc) if solve is None else solve
    opinv = spla.LinearOperator((n, n), matvec=solve, dtype=complex)
    with progress.phase(f"eigen-solve: {k} lowest modes of {n} complex unknowns (ARPACK)"):
        lam, V = spla.eigsh(
            Kc, k=k, M=Mc, sigma=0.0, OPinv=opinv, which="LM", tol=tol, v0=start_vector(n, complex)
        )
        return ritz_refined(Kc, Mc, V, solve)
