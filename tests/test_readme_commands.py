"""The README's promises: the two 3D commands mesh the built-in blade and write a snapshot."""

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _commands(section: str) -> list[list[str]]:
    """``femrub`` commands of the first bash block after the README heading ``section``."""
    text = (ROOT / "README.md").read_text()
    block = re.search(rf"## {re.escape(section)}.*?```bash\n(.*?)```", text, re.S).group(1)
    return [shlex.split(line)[1:] for line in block.splitlines() if "femrub" in line]


@pytest.fixture(scope="module")
def readme_3d(tmp_path_factory):
    cwd = tmp_path_factory.mktemp("readme")
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}  # no screen
    env["PYTHONPATH"] = str(ROOT)
    outs = []
    for args in _commands("A 3D rub in two commands"):
        p = subprocess.run(
            [sys.executable, "-m", "femrub", *args],
            cwd=cwd,
            env=env,
            capture_output=True,
            text=True,
            timeout=900,
        )
        assert p.returncode == 0, p.stderr[-2000:]
        outs.append(p)
    return cwd, outs


def test_readme_mesh_is_the_builtin_blade(readme_3d):
    from femrub.app.blade import load_blade
    from femrub.scene import load_scene

    cwd, _ = readme_3d
    builtin = load_blade(load_scene("twisted-naca"))
    meshed = load_blade(
        load_scene(
            "twisted-naca", {"geometry.kind": "mesh", "geometry.path": str(cwd / "blade.msh")}
        )
    )
    assert meshed.mesh.p.shape == builtin.mesh.p.shape
    assert np.allclose(np.sort(meshed.mesh.p, axis=1), np.sort(builtin.mesh.p, axis=1), atol=1e-12)
    assert np.allclose(meshed.contact_points, builtin.contact_points, atol=1e-12)


def test_readme_run_writes_snapshot_and_bounded_output(readme_3d):
    cwd, outs = readme_3d
    out = cwd / "blade-out"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok"
    png = out / "snapshot.png"
    assert "snapshot_error" not in summary, summary.get("snapshot_error")
    assert png.read_bytes()[:4] == b"\x89PNG" and png.stat().st_size > 5_000
    assert (out / "vtk" / "rub.pvd").is_file() and (out / "explain.txt").is_file()
    total = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
    assert total < 20e6  # measured 6.3 MB
    assert "X server" not in outs[1].stderr  # VTK's display warnings are silenced
    # one definition per quantity: the console's peaks are the summary's per-point maxima
    assert f"{summary['max_contact_force']:.4g} N" in outs[1].stdout
    assert f"{summary['max_contact_temperature']:.4g} K" in outs[1].stdout
