"""The compiled CSR × dense product of the projections (:mod:`femrub.fem.spmm`).

Against scipy, compiled (threads) and as plain Python (``NUMBA_DISABLE_JIT=1``, the same
kernel), with row blocks of the dense factor that are zero on some of its columns (a
reduction basis), and through :func:`~femrub.fem.linalg.project` against the dense product.
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from jit_child import child_json

from femrub.fem.linalg import project
from femrub.fem.spmm import _csr_dense_runs, block_columns, compiled, csr_dense

ROOT = Path(__file__).resolve().parents[1]


def _case(seed=0, n=900, k=23):
    """A random CSR ``Q`` (n × n, int32 indices) and a basis ``X`` zero on some columns
    of each of its three row blocks, as a reduction basis."""
    rng = np.random.default_rng(seed)
    Q = sp.random(n, n, density=0.02, random_state=rng, format="csr")
    Q = Q + sp.identity(n, format="csr")  # a row of every kind, a diagonal
    X = rng.standard_normal((n, k))
    bounds = np.array([0, 300, 600, n])
    X[0:300, 10:] = 0.0  # u rows: u shapes and θ shapes only
    X[0:300, 20:] = rng.standard_normal((300, k - 20))
    X[300:600, :10] = 0.0  # v rows: v shapes
    X[300:600, 20:] = 0.0
    X[600:, :20] = 0.0  # θ rows: θ shapes
    return sp.csr_matrix(Q), X, bounds


def _kernel(Q, X, bounds, out_columns, columns):
    """:func:`_csr_dense_runs` called as ``csr_dense`` calls it (every JIT setting)."""
    from femrub.fem.spmm import _runs

    lows, highs, starts, stops, offsets = [], [], [], [], []
    for k, cols in enumerate(columns):
        s, e = _runs(cols)
        lows.append(np.full(s.size, bounds[k]))
        highs.append(np.full(s.size, bounds[k + 1]))
        starts.append(s)
        stops.append(e)
        offsets.append(np.searchsorted(out_columns, s))
    out = np.zeros((Q.shape[0], out_columns.size))
    cat = lambda a: np.concatenate(a).astype(np.int64)  # noqa: E731
    _csr_dense_runs(
        Q.indptr,
        Q.indices,
        Q.data,
        X,
        cat(lows),
        cat(highs),
        cat(starts),
        cat(stops),
        cat(offsets),
        out,
    )
    return out


def test_block_columns_and_runs():
    _, X, bounds = _case()
    cols = block_columns(X != 0.0, bounds)
    assert cols[0].tolist() == list(range(10)) + list(range(20, 23))
    assert cols[1].tolist() == list(range(10, 20))
    assert cols[2].tolist() == list(range(20, 23))
    from femrub.fem.spmm import _runs

    s, e = _runs(np.array([0, 1, 2, 5, 7, 8]))
    assert s.tolist() == [0, 5, 7] and e.tolist() == [3, 6, 9]


def test_csr_dense_is_scipy():
    Q, X, bounds = _case()
    ref = Q @ X
    tol = 1e-13 * np.abs(ref).max()
    cols = block_columns(X != 0.0, bounds)
    none = np.zeros(0, dtype=int)
    cases = [
        (np.arange(X.shape[1]), cols, ref),  # every block
        (cols[1], [none, cols[1], none], Q[:, 300:600] @ X[300:600][:, cols[1]]),  # v only
    ]
    for out_columns, columns, want in cases:
        assert np.allclose(csr_dense(Q, X, columns, bounds, out_columns), want, atol=tol)
        assert np.allclose(_kernel(Q, X, bounds, out_columns, columns), want, atol=tol)
    empty = csr_dense(sp.csr_matrix((4, 900)), X, cols, bounds, np.arange(23))
    assert empty.shape == (4, 23) and not empty.any()


def test_rows_split_between_threads(monkeypatch):
    import femrub.fem.spmm as spmm

    Q, X, bounds = _case(3)
    cols = block_columns(X != 0.0, bounds)
    whole = csr_dense(Q, X, cols, bounds, np.arange(X.shape[1]))
    for threads in (2, 3, 7):
        monkeypatch.setattr(spmm, "THREADS", threads)
        monkeypatch.setattr(spmm, "NNZ_PER_THREAD", 100)
        split = csr_dense(Q, X, cols, bounds, np.arange(X.shape[1]))
        assert np.array_equal(split, whole)  # each row summed by one thread, in order


def test_project_with_blocks_is_the_dense_product():
    Q, X, _ = _case(1, n=2000, k=31)
    L = X.copy()
    L[:500] *= 2.0
    ref = L.T @ (Q @ X)
    for parts in (None, [0, 300, 600, 2000]):
        got = project(L, Q, X, chunk=700, parts=parts)
        assert np.allclose(got, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


_CHILD = """
import json, numpy as np, sys
sys.path.insert(0, {tests!r})
from test_spmm import _case, _kernel
from femrub.fem.spmm import block_columns, compiled
Q, X, bounds = _case(2)
cols = block_columns(X != 0.0, bounds)
out = _kernel(Q, X, bounds, np.arange(X.shape[1]), cols)
print(json.dumps({{"jit": compiled(), "err": float(np.abs(out - Q @ X).max()),
                  "scale": float(np.abs(Q @ X).max())}}))
"""


@pytest.mark.skipif(not compiled(), reason="kernel not compiled (NUMBA_DISABLE_JIT)")
def test_the_kernel_runs_as_python_without_jit():
    code = _CHILD.format(tests=str(ROOT / "tests"))
    out = {jit: child_json(code, jit) for jit in (False, True)}
    assert not out[False]["jit"] and out[True]["jit"]
    for r in out.values():
        assert r["err"] <= 1e-13 * r["scale"]
