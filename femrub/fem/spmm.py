"""Sparse (CSR) × dense products on every core, compiled with numba.

scipy's CSR × dense product runs on one thread; the projections of a reduction
(:func:`~femrub.fem.linalg.project`) spend most of their time in it. :func:`csr_dense`
computes ``Q[:, in block b] @ X[in block b][:, columns of b]`` summed over row blocks ``b``
of ``X``: each block of ``X`` (the ``u``, ``v``, ``θ`` rows of a reduction basis)
multiplies only the columns it is not zero on, so a stiffness acting on ``u`` does not
multiply the velocity shapes' zeros. The rows of ``Q`` are split between threads, each
running the compiled kernel without the GIL (plain threads, not numba's OpenMP layer, whose
idle workers spin and slow the BLAS calls around the kernel on a busy machine).

With ``NUMBA_DISABLE_JIT=1`` (or without numba) the kernel runs as plain Python (the same
code, tested both ways); :func:`csr_dense` then uses scipy instead, whose result is the same
to round-off (only the order of the sums differs).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import scipy.sparse as sp

try:  # numba is a dependency; the fallback keeps a broken install importable
    import numba
except ImportError:  # pragma: no cover
    numba = None

__all__ = ["block_columns", "compiled", "csr_dense"]


def compiled() -> bool:
    """Whether the kernel runs as machine code (numba present and JIT enabled)."""
    if numba is None:  # pragma: no cover
        return False
    from numba.core import config

    return not config.DISABLE_JIT


def _compile(fn):
    """``fn`` compiled without the GIL (cached on disk), or ``fn`` itself without numba."""
    if numba is None:  # pragma: no cover
        return fn
    return numba.njit(cache=True, nogil=True)(fn)


#: Threads the rows are split between (the cores this process may use, at most 8).
THREADS = max(
    1,
    min(
        8,
        len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1),
    ),
)
#: Nonzeros of ``Q`` per thread below which fewer threads are used (small products).
NNZ_PER_THREAD = 100_000
_POOL: dict = {}


@_compile
def _csr_dense_runs(indptr, indices, data, X, lows, highs, starts, stops, offsets, out):
    """``out[i, offsets[r] + j − starts[r]] = Σ_c Q[i, c] X[c, j]`` over the columns ``c``
    of run ``r``'s row block (``lows[r] <= c < highs[r]``), for ``j`` in
    ``starts[r] … stops[r]``: a row of ``out`` summed in a local array, a contiguous run of
    ``X``'s row per term."""
    width = out.shape[1]
    for i in range(indptr.size - 1):
        acc = np.zeros(width)
        for r in range(starts.size):
            lo, hi, s, o = lows[r], highs[r], starts[r], offsets[r]
            n = stops[r] - s
            for p in range(indptr[i], indptr[i + 1]):
                c = indices[p]
                if c >= lo and c < hi:
                    v = data[p]
                    x = X[c, s : s + n]  # views: 1D loops the compiler vectorises
                    a = acc[o : o + n]
                    for j in range(n):
                        a[j] += v * x[j]
        out[i, :] = acc


def _runs(columns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and stops of the contiguous runs of sorted ``columns``."""
    if columns.size == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    cut = np.flatnonzero(np.diff(columns) != 1) + 1
    return columns[np.r_[0, cut]].astype(np.int64), columns[np.r_[cut - 1, -1]].astype(np.int64) + 1


def block_columns(nonzero: np.ndarray, bounds) -> list[np.ndarray]:
    """The columns of each row block ``bounds[b]:bounds[b + 1]`` of the boolean pattern
    ``nonzero`` (rows × columns) that are not zero in that block."""
    b = np.asarray(bounds, dtype=np.int64)
    return [np.flatnonzero(np.any(nonzero[b[k] : b[k + 1]], axis=0)) for k in range(b.size - 1)]


def csr_dense(Q, X: np.ndarray, columns: list[np.ndarray], bounds, out_columns: np.ndarray):
    """``Σ_b Q[:, block b] @ X[block b][:, columns[b]]`` into the ``out_columns`` layout.

    Parameters
    ----------
    Q : (m, n) CSR matrix (sorted indices not needed).
    X : (n, k) dense array.
    columns : per row block ``b`` of ``X`` (``bounds[b]:bounds[b + 1]``), the sorted columns
        of ``X`` it multiplies (the others are zero there).
    bounds : (n_blocks + 1,) row bounds of the blocks, ``bounds[0] = 0``, last ``n``.
    out_columns : sorted union of ``columns``: the columns of ``X`` the result holds.

    Returns
    -------
    (m, out_columns.size) array: ``(Q @ X)[:, out_columns]``.
    """
    Q = sp.csr_matrix(Q)
    out = np.zeros((Q.shape[0], out_columns.size))
    if Q.nnz == 0 or out_columns.size == 0:
        return out
    if not compiled():  # plain Python would be slow: scipy, block by block
        b = np.asarray(bounds, dtype=np.int64)
        for k, cols in enumerate(columns):
            if cols.size:
                part = Q[:, b[k] : b[k + 1]] @ X[b[k] : b[k + 1]][:, cols]
                out[:, np.searchsorted(out_columns, cols)] += part
        return out
    b = np.asarray(bounds, dtype=np.int64)
    lows, highs, starts, stops, offsets = [], [], [], [], []
    for k, cols in enumerate(columns):
        s, e = _runs(cols)
        lows.append(np.full(s.size, b[k]))
        highs.append(np.full(s.size, b[k + 1]))
        starts.append(s)
        stops.append(e)
        offsets.append(np.searchsorted(out_columns, s))
    cat = lambda a: np.concatenate(a).astype(np.int64)  # noqa: E731
    runs = (cat(lows), cat(highs), cat(starts), cat(stops), cat(offsets))
    data = np.asarray(Q.data, dtype=float)
    m = Q.shape[0]
    parts = min(THREADS, max(1, Q.nnz // NNZ_PER_THREAD))
    cuts = np.searchsorted(Q.indptr, np.linspace(0, Q.nnz, parts + 1)[1:-1])  # equal nnz
    bounds_rows = np.r_[0, np.clip(cuts, 0, m), m]

    def rows(k):
        r0, r1 = bounds_rows[k], bounds_rows[k + 1]
        _csr_dense_runs(Q.indptr[r0 : r1 + 1], Q.indices, data, X, *runs, out[r0:r1])

    if parts == 1:
        rows(0)
    else:
        pool = _POOL.get(parts) or _POOL.setdefault(parts, ThreadPoolExecutor(parts))
        list(pool.map(rows, range(parts)))
    return out
