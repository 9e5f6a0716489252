"""One BLAS thread for small dense work: the shared context and the steppers' set-up."""

import os
import subprocess
import sys
import threading

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from femrub.blas import SERIAL_SETUP_DOFS, one_blas_thread
from femrub.cases.bar import bar_model
from femrub.steppers.theta import ThetaMethod


def _blas_threads() -> list[int]:
    """Threads of the process-wide BLAS pools (OpenBLAS); MKL's setting, which threadpoolctl
    reads and sets for the calling thread only, is checked apart (last test)."""
    return [
        lib["num_threads"]
        for lib in threadpool_info()
        if lib["user_api"] == "blas" and lib["internal_api"] != "mkl"
    ]


def test_one_blas_thread_nests_and_restores():
    before = _blas_threads()
    with one_blas_thread:
        assert set(_blas_threads()) == {1}
        with one_blas_thread:
            assert set(_blas_threads()) == {1}
        assert set(_blas_threads()) == {1}  # the outer context still holds
    assert _blas_threads() == before


def test_the_last_thread_out_restores_the_limits():
    before = _blas_threads()
    inside, leave = threading.Event(), threading.Event()

    def writer():
        with one_blas_thread:
            inside.set()
            leave.wait(10)

    w = threading.Thread(target=writer)
    w.start()
    inside.wait(10)
    with one_blas_thread:
        pass
    assert set(_blas_threads()) == {1}  # the other thread is still inside
    leave.set()
    w.join(10)
    assert _blas_threads() == before


def test_a_small_model_is_set_up_on_one_blas_thread(monkeypatch):
    seen = []
    setup = ThetaMethod._setup

    def spy(self):
        seen.append(_blas_threads())
        setup(self)

    monkeypatch.setattr(ThetaMethod, "_setup", spy)
    model = bar_model()
    assert model.n_dofs <= SERIAL_SETUP_DOFS
    st = ThetaMethod(model, 1e-5)
    assert seen and set(seen[0]) == {1}
    assert np.all(np.isfinite(st.step().X))


def test_mkl_loaded_after_first_use_is_limited_too():
    """A process that entered the context before loading Pardiso's MKL (a small model's
    set-up, then a large factorisation) still runs MKL on one thread inside it; in a fresh
    process, since the pytest process may have loaded MKL already."""
    pytest.importorskip("pypardiso")
    code = (
        "from threadpoolctl import threadpool_info\n"
        "from femrub.blas import one_blas_thread\n"
        "from femrub.fem.linalg import pardiso_available\n"
        "with one_blas_thread: pass\n"
        "assert pardiso_available()\n"
        "assert any(l['internal_api'] == 'mkl' for l in threadpool_info())\n"
        "with one_blas_thread:\n"
        "    seen = {l['internal_api']: l['num_threads'] for l in threadpool_info()\n"
        "            if l['user_api'] == 'blas'}\n"
        "assert set(seen.values()) == {1}, seen\n"
    )
    subprocess.run(
        [sys.executable, "-c", code], check=True, env={**os.environ, "MKL_NUM_THREADS": "2"}
    )
