"""A build compiles the contact kernels it needs in a child process when numba's cache is
cold: the paper's frictionless bar compiles its one family, not the frictional ones."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from femrub.contact.jit import compiled

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = """
from femrub.app.translate import kernel_kinds
from femrub.contact import jit
from femrub.contact.activation import compile_kernels
from femrub.scene import load_scene
kinds = kernel_kinds(load_scene("paper"))
started = jit.compile_in_background(kinds)
child = jit._CHILD.get("process")
compile_kernels(kinds)  # waits for the child, then loads what it cached
again = jit.compile_in_background(kinds)  # once per process
print(kinds, started, None if child is None else child.returncode, again)
"""


@pytest.mark.skipif(not compiled(), reason="kernels not compiled (NUMBA_DISABLE_JIT)")
def test_cold_cache_compiled_by_a_child_then_warm_only_what_the_run_needs(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(ROOT)}

    def run():
        p = subprocess.run(
            [sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=600
        )
        assert p.returncode == 0, p.stderr[-2000:]
        return p.stdout.split()

    # cold: the child compiled and cached the bar's family
    assert run() == ["('one',)", "True", "0", "False"]
    assert list(tmp_path.rglob("theta_block.one_contact_block-*.nbi"))
    assert not list(tmp_path.rglob("theta_block.friction_block-*.nbi"))  # not needed
    assert not list(tmp_path.rglob("rub_block.rub_block-*.nbi"))
    assert run() == ["('one',)", "False", "None", "False"]  # warm: no child


def test_no_child_without_compilation():
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(ROOT)}
    code = "from femrub.contact import jit; print(jit.compile_in_background())"
    p = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert p.returncode == 0 and p.stdout.split() == ["False"], p.stderr[-2000:]


def test_the_kernel_families_of_a_scene():
    from femrub.app.translate import kernel_kinds
    from femrub.contact.activation import compile_kernels
    from femrub.scene import load_scene

    assert kernel_kinds(load_scene("paper")) == ("one",)
    blade = load_scene("twisted-naca", {"contact.friction": 0.1})
    assert kernel_kinds(blade) == ("friction", "rub")  # power heat on a blade
    assert kernel_kinds(blade.with_changes({"contact.heat_law": "alpha"})) == ("friction",)
    with pytest.raises(ValueError, match="unknown kernel kinds"):
        compile_kernels(("one", "two"))
