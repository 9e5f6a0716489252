"""A build compiles the contact kernels in a child process when numba's cache is cold."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from femrub.contact.jit import compiled

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = """
import sys
from femrub.contact import jit
from femrub.contact.activation import compile_kernels
started = jit.compile_in_background()
child = jit._CHILD.get("process")
compile_kernels()  # waits for the child, then loads what it cached
again = jit.compile_in_background()  # once per process
print(started, None if child is None else child.returncode, again)
"""


@pytest.mark.skipif(not compiled(), reason="kernels not compiled (NUMBA_DISABLE_JIT)")
def test_cold_cache_compiled_by_a_child_then_warm(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(ROOT)}

    def run():
        p = subprocess.run(
            [sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=600
        )
        assert p.returncode == 0, p.stderr[-2000:]
        return p.stdout.split()

    assert run() == ["True", "0", "False"]  # cold: the child compiled and cached them
    assert list(tmp_path.rglob("theta_block.friction_block-*.nbi"))
    assert run() == ["False", "None", "False"]  # warm: no child


def test_no_child_without_compilation():
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(ROOT)}
    code = "from femrub.contact import jit; print(jit.compile_in_background())"
    p = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert p.returncode == 0 and p.stdout.split() == ["False"], p.stderr[-2000:]
