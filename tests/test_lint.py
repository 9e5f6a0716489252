"""Code rules enforced in the test run: ruff's checks (McCabe complexity at most 12,
argument counts, imports, style) and its layout, as configured in pyproject.toml."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PATHS = ["femrub", "tests", "benchmarks", "examples"]


def _ruff(*args):
    exe = shutil.which("ruff") or str(Path(sys.executable).with_name("ruff"))
    if not Path(exe).exists() and not shutil.which(exe):
        pytest.skip("ruff is not installed (pip install -e '.[test]')")
    return subprocess.run([exe, *args], cwd=ROOT, capture_output=True, text=True)


def test_ruff_check_passes():
    out = _ruff("check", "--no-cache", *PATHS)
    assert out.returncode == 0, out.stdout + out.stderr


def test_ruff_format_is_kept():
    out = _ruff("format", "--check", "--no-cache", *PATHS)
    assert out.returncode == 0, out.stdout + out.stderr


def test_no_function_above_complexity_12_and_no_hand_packed_lines():
    # no exemption either: a `noqa` on C901 counts as a function above 12
    out = _ruff("check", "--no-cache", "--select", "C901", "femrub")
    assert out.returncode == 0, out.stdout
    packed = [
        str(p.relative_to(ROOT))
        for folder in PATHS
        for p in (ROOT / folder).rglob("*.py")
        if any(m in p.read_text(encoding="utf-8") for m in ("# fmt: " + "skip", "noqa: " + "C901"))
    ]
    assert not packed, packed
