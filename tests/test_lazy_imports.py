"""`femrub --help` and `femrub scenes` stay fast: they import neither scikit-fem nor matplotlib."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("skfem", "matplotlib", "scipy.sparse", "gmsh", "pyvista", "dask")


def _loaded(code: str, heavy=HEAVY) -> list[str]:
    """Which of the modules ``heavy`` a fresh interpreter has loaded after ``code``."""
    probe = f"{code}; import sys; print(','.join(m for m in {heavy!r} if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", probe],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        env={"PYTHONPATH": str(ROOT), "PATH": ""},
    )
    return [m for m in out.stdout.strip().split(",") if m]


def test_cli_help_and_scenes_import_nothing_heavy():
    assert _loaded("import femrub.app.cli as c; c.build_parser()") == []
    assert _loaded("from femrub.scene import builtin_scenes; builtin_scenes()") == []


def test_public_names_still_resolve():
    import femrub

    assert femrub.ThetaMethod.__name__ == "ThetaMethod" and callable(femrub.bar_model)
    assert "ThetaMethod" in dir(femrub)
