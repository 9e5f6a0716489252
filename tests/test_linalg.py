"""Sparse factorisations (Pardiso and SuperLU paths), structured projections, CSV decimation."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import scipy.sparse as sp

from femrub import progress
from femrub.fem import linalg
from femrub.fem.eigen import lowest_modes
from femrub.output.csv_rows import decimate_columns


def _laplacian(n: int, shift: float = 0.0) -> sp.csr_matrix:
    return sp.diags([-np.ones(n - 1), 2.0 * np.ones(n) - shift, -np.ones(n - 1)], [-1, 0, 1])


@pytest.fixture(params=[False, True], ids=["superlu", "pardiso"])
def pardiso(request, monkeypatch):
    if request.param:
        if not linalg.pardiso_available():
            pytest.skip("pypardiso / MKL not installed")
        monkeypatch.setattr(linalg, "PARDISO_ABOVE", 10)
    return request.param


def test_sparse_lu_spd_indefinite_general_and_singular(pardiso):
    rng = np.random.default_rng(0)
    n = 200
    b = rng.standard_normal((n, 3))
    for M, sym in (
        (_laplacian(n), True),
        (_laplacian(n, 2.9), True),
        (_laplacian(n) + sp.diags(np.ones(n - 1), 1), False),
    ):
        x = linalg.sparse_lu(M, symmetric=sym).solve(b)
        np.testing.assert_allclose(M @ x, b, atol=1e-9 * np.abs(b).max())
        x1 = linalg.sparse_lu(M, symmetric=sym).solve(b[:, 0])
        assert x1.shape == (n,)
    for M, definite in ((_laplacian(n, 2.9), False), (_laplacian(n), False)):
        lu = linalg.sparse_lu(M, symmetric=True, definite=definite)  # LDLᵀ at once
        np.testing.assert_allclose(M @ lu.solve(b), b, atol=1e-9 * np.abs(b).max())
        if pardiso:
            assert lu.method == "LDLt (MKL Pardiso)"
    if pardiso:  # Cholesky when definite (the default), LDLᵀ after a failed Cholesky
        assert linalg.sparse_lu(_laplacian(n), symmetric=True).method.startswith("Cholesky")
        assert linalg.sparse_lu(_laplacian(n, 2.9), symmetric=True).method.startswith("LDLt")
    free = _laplacian(n).tolil()
    free[0, 0] = free[-1, -1] = 1.0  # a free chain: singular
    with pytest.raises(ValueError, match="singular"):
        linalg.sparse_lu(free.tocsr(), symmetric=True, what="free chain")


def test_pardiso_reports_progress(pardiso):
    notes = []
    with progress.reporting(notes.append):
        lu = linalg.sparse_lu(_laplacian(100), symmetric=True, what="chain")
        lu.solve(np.ones((100, 4)))
    if pardiso:
        assert any("factorising the chain (100 unknowns) done" in n for n in notes)
        assert any("Cholesky" in n for n in notes)
        assert any("solved 4 right-hand sides" in n for n in notes)
    with progress.reporting(None):
        progress.note("silent")  # no log: dropped


def test_lowest_modes_large_path_matches_dense(pardiso):
    n = 450  # above the dense eigen-solver's size
    K, M = _laplacian(n), sp.identity(n)
    lam = lowest_modes(K, M, 4, vectors=False)
    exact = 2.0 - 2.0 * np.cos(np.arange(1, 5) * np.pi / (n + 1))
    np.testing.assert_allclose(lam, exact, rtol=1e-9)


def test_project_equals_dense_product_on_block_structures():
    rng = np.random.default_rng(1)
    n, r = 3000, 40
    Q = sp.random(n, n, density=2e-3, random_state=2, format="csr") + sp.identity(n)
    Q = sp.csr_matrix(Q)
    Q = sp.diags(np.r_[np.ones(1000), np.zeros(500), np.ones(n - 1500)]) @ Q  # empty rows
    L, R = rng.standard_normal((n, r)), rng.standard_normal((n, r))
    L[:1200, :10] = 0.0
    R[1500:2600, 25:] = 0.0
    ref = L.T @ (Q @ R)
    for chunk in (8192, 700, 1):
        got = linalg.project(L, Q, R, chunk=chunk) if chunk > 1 else linalg.project(L, Q, R)
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_array_equal(linalg.project(L, sp.csr_matrix((n, n)), R), 0.0)
    np.testing.assert_allclose(linalg.project(L, Q.toarray(), R), ref, rtol=1e-10)


def test_decimated_columns_keep_the_total_impulse():
    t = np.arange(11) * 0.1
    imp = np.zeros(11)
    imp[[3, 4, 9]] = [1.0, 2.0, 0.5]
    cols = {"t": t, "x": t**2, "contact_impulse": imp, "contact_force": imp / 0.1}
    out = decimate_columns(cols, 4)
    np.testing.assert_allclose(out["t"], [0.0, 0.4, 0.8, 1.0])
    np.testing.assert_allclose(out["x"], out["t"] ** 2)
    np.testing.assert_allclose(out["contact_impulse"], [0.0, 3.0, 0.0, 0.5])
    np.testing.assert_allclose(out["contact_force"], [0.0, 7.5, 0.0, 2.5])
    assert out["contact_impulse"].sum() == pytest.approx(imp.sum())


def test_pardiso_factor_is_released():
    """``free`` releases MKL's memory (also when collected) and may be called twice."""
    if not linalg.pardiso_available():
        pytest.skip("pypardiso / MKL not installed")
    f = linalg._Pardiso(_laplacian(50), symmetric=True)
    assert np.isfinite(f.solve(np.ones(50))).all()
    f.free()
    f.free()
    assert f._s is None


@pytest.mark.parametrize("preset", [None, "COMPATIBLE"])
def test_mkl_is_loaded_in_its_reproducible_mode(preset):
    """femrub loads MKL with conditional numerical reproducibility (MKL_CBWR=AUTO: a
    threaded factorisation gives the same bits from run to run); a user's MKL_CBWR stands.
    In a fresh interpreter, asking MKL itself which branch it runs."""
    import os
    import subprocess
    import sys

    if not linalg.pardiso_available():
        pytest.skip("pypardiso / MKL not installed")
    code = (
        "import ctypes, os\n"
        "from femrub.fem import linalg\n"
        "assert linalg.pardiso_available()\n"
        "import pypardiso\n"
        "get = pypardiso.PyPardisoSolver().libmkl.MKL_CBWR_Get\n"
        "get.restype = ctypes.c_int\n"
        "print(os.environ['MKL_CBWR'], get(ctypes.c_int(1)))\n"  # 1: MKL_CBWR_BRANCH
    )
    env = {k: v for k, v in os.environ.items() if k != "MKL_CBWR"}
    if preset:
        env["MKL_CBWR"] = preset
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    ).stdout.split()
    # MKL's branch codes: 1 off (MKL's default), 2 AUTO, 3 COMPATIBLE
    assert out == (["COMPATIBLE", "3"] if preset else ["AUTO", "2"])


def test_the_mkl_runtime_is_found_without_searching_the_environment():
    """pip's ``mkl`` wheel puts the runtime in ``sys.prefix/lib``: a fresh process loads it
    from there (kept in ``PYPARDISO_MKL_RT``) without pypardiso's recursive search of the
    environment's folders (seconds per process on a cold disk)."""
    import glob
    import os
    import subprocess
    import sys

    if not glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")):
        pytest.skip("no MKL runtime in sys.prefix/lib")
    code = (
        "import glob, os\n"
        "seen = []\n"
        "plain = glob.glob\n"
        "glob.glob = lambda p, **k: seen.append(k.get('recursive', False)) or plain(p, **k)\n"
        "from femrub.fem import linalg\n"
        "print(linalg.pardiso_available(), any(seen), os.environ['PYPARDISO_MKL_RT'])\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "PYPARDISO_MKL_RT"}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    ).stdout.split()
    assert out[:2] == ["True", "False"]
    assert os.path.dirname(out[2]) == os.path.join(sys.prefix, "lib")


def test_threads_may_share_a_factorisation(pardiso):
    """Solves of one factorisation from several threads at once give the serial solves
    (Pardiso's solve phase writes in the factorisation's memory: they take turns)."""
    side = 120  # a 2D Laplacian: its factor fills in, so that the solves overlap
    one = _laplacian(side)
    A = sp.kron(one, sp.identity(side)) + sp.kron(sp.identity(side), one)
    lu = linalg.sparse_lu(A.tocsr(), symmetric=True)
    B = np.random.default_rng(3).standard_normal((side**2, 32))
    serial = np.column_stack([lu.solve(B[:, j]) for j in range(B.shape[1])])
    with ThreadPoolExecutor(4) as pool:
        for _ in range(6):  # a race shows in one round of two or so
            shared = pool.map(lambda j: lu.solve(B[:, j]), range(B.shape[1]))
            np.testing.assert_array_equal(np.column_stack(list(shared)), serial)
