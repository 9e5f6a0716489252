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
compile_kernels()  # waits for the child, then loads what it cached (all kinds)
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


ONE_KIND = """
from femrub.app.translate import kernel_kinds
from femrub.contact import jit
from femrub.contact.activation import compile_kernels
from femrub.scene import load_scene
kinds = kernel_kinds(load_scene("paper"))
print(kinds, jit.compile_in_background(kinds))
compile_kernels(kinds)
"""


@pytest.mark.skipif(not compiled(), reason="kernels not compiled (NUMBA_DISABLE_JIT)")
def test_a_frictionless_run_compiles_only_its_kernels(tmp_path):
    """The paper's bar needs one frictionless contact: its cold start compiles that family
    alone, not the frictional and rub kernels."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(ROOT)}
    p = subprocess.run(
        [sys.executable, "-c", ONE_KIND], env=env, capture_output=True, text=True, timeout=600
    )
    assert p.returncode == 0, p.stderr[-2000:]
    assert p.stdout.split() == ["('one',)", "True"]
    assert list(tmp_path.rglob("theta_block.one_contact_block-*.nbi"))
    assert not list(tmp_path.rglob("theta_block.friction_block-*.nbi"))
    assert not list(tmp_path.rglob("rub_block.rub_block-*.nbi"))


def test_the_kernel_families_of_a_scene():
    from femrub.app.translate import kernel_kinds
    from femrub.scene import load_scene

    assert kernel_kinds(load_scene("paper")) == ("one",)
    blade = load_scene("twisted-naca", {"contact.friction": 0.1})
    assert kernel_kinds(blade) == ("friction", "rub")  # power heat on a blade
    assert kernel_kinds(blade.with_changes({"contact.heat_law": "alpha"})) == ("friction",)
    with pytest.raises(ValueError, match="unknown kernel kinds"):
        from femrub.contact.activation import compile_kernels

        compile_kernels(("one", "two"))
