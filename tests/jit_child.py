"""A compiled kernel against its plain-Python run: the same code in a child process with
and without ``NUMBA_DISABLE_JIT``."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def child_json(code: str, jit: bool) -> dict:
    """Run ``code`` in a fresh interpreter (compiled kernels if ``jit``, else numba off) and
    return the JSON object its last printed line holds."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    if jit:
        env.pop("NUMBA_DISABLE_JIT", None)
    else:
        env["NUMBA_DISABLE_JIT"] = "1"
    run = subprocess.run(
        [sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True, text=True, check=True
    )
    return json.loads(run.stdout.splitlines()[-1])
