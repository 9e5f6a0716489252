"""Large arrays mapped on their own give their memory back when freed (femrub.heap)."""

import os
import subprocess
import sys

import pytest

from femrub import heap

SCRIPT = """
import sys
import numpy as np
from femrub import heap

def resident_mb():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS"):
            return int(line.split()[1]) / 1024

took = heap.map_large_arrays() if sys.argv[1] == "mapped" else False
big = np.ones(16 << 17)  # 16 MB mapped then freed: glibc raises its threshold to it
del big
blocks, pins = [], []
for _ in range(40):  # 4 MB arrays with small ones between them
    blocks.append(np.ones(4 << 17))
    pins.append(np.ones(1000))
before = resident_mb()
del blocks
print(took, before - resident_mb())
"""


def _returned(mode: str) -> tuple[bool, float]:
    env = {k: v for k, v in os.environ.items() if k != heap.ENV}
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT, mode], capture_output=True, text=True, env=env, check=True
    ).stdout.split()
    return out[0] == "True", float(out[1])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc")
def test_freed_large_arrays_go_back_to_the_system():
    took, mapped = _returned("mapped")
    if not took:
        pytest.skip("the C library is not glibc")
    _, heaped = _returned("heap")
    # 160 MB freed: all of it returned when mapped; kept in the heap by glibc's own threshold
    assert mapped > 150.0 and heaped < 50.0


def test_the_environment_setting_stands(monkeypatch):
    monkeypatch.setenv(heap.ENV, "65536")
    assert heap.map_large_arrays() is False
