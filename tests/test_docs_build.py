"""The documentation site builds with warnings as errors (``docs/conf.py``), quick gallery.

One build (about a minute): the API reference from the docstrings, every scene key from the
schema, every command from the parser, and the gallery's examples executed with their figures.
The docs are copied to a temporary folder so that the build writes nothing into the project.
"""

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("sphinx", "pydata_sphinx_theme", "numpydoc", "myst_parser", "sphinx_gallery")
MISSING = [name for name in PACKAGES if importlib.util.find_spec(name) is None]

pytestmark = pytest.mark.skipif(
    bool(MISSING),
    reason=f"docs packages not installed ({', '.join(MISSING)}): pip install -e '.[docs]'",
)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The built HTML site (a failed build fails every test with sphinx's output)."""
    tmp = tmp_path_factory.mktemp("docs-build")
    generated = ("_build", "auto_examples", "generated", "sg_execution_times.rst")
    shutil.copytree(ROOT / "docs", tmp / "docs", ignore=shutil.ignore_patterns(*generated))
    shutil.copy(ROOT / "CHANGELOG.md", tmp / "CHANGELOG.md")
    env = {
        **os.environ,
        "FEMRUB_DOCS_QUICK": "1",
        "MPLBACKEND": "Agg",
        "TMPDIR": str(tmp),  # the examples' working folders, removed with the test's own
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    out = tmp / "html"
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html"]
    done = subprocess.run(
        [*cmd, str(tmp / "docs"), str(out)], env=env, capture_output=True, text=True, timeout=900
    )
    assert done.returncode == 0, f"sphinx -W failed:\n{done.stdout[-4000:]}\n{done.stderr[-8000:]}"
    return out


def _text(page: Path) -> str:
    return re.sub(r"<[^>]+>", " ", page.read_text(encoding="utf-8"))


def test_api_reference_documents_the_user_objects(site):
    import femrub

    generated = site / "reference" / "generated"
    missing = [n for n in femrub.__all__ if not (generated / f"femrub.{n}.html").exists()]
    assert not missing, f"no API page for femrub.{missing}"
    assert "stability_limit" in _text(generated / "femrub.ThetaMethod.html")
    assert "Eq." in _text(generated / "femrub.FirstOrderModel.html")
    assert "load_results" in _text(site / "reference" / "api.html")


def test_validation_has_the_rotor37_calculix_page(site):
    text = _text(site / "validation" / "rotor37-calculix.html")
    assert "CalculiX C3D15" in text and "commit" in text
    text = _text(site / "validation" / "rotor37-tip-flexibility.html")
    assert "C3D10" in text and "residual flexibility" in text


def test_scene_key_reference_lists_every_key(site):
    from femrub.scene import schema_rows

    text = _text(site / "reference" / "scene-keys.html")
    missing = sorted({key for key, _, _ in schema_rows() if key not in text})
    assert not missing, f"scene keys missing from the reference: {missing}"


def test_cli_reference_lists_every_command(site):
    text = _text(site / "reference" / "cli.html")
    for command in ("femrub run", "femrub sweep", "femrub campbell", "femrub paper", "--set"):
        assert command in text


def test_gallery_examples_ran_and_show_their_figures(site):
    examples = sorted((ROOT / "docs" / "gallery").glob("plot_*.py"))
    assert examples
    for example in examples:
        page = site / "auto_examples" / f"{example.stem}.html"
        assert page.exists(), f"{example.name} was not rendered"
        assert re.search(rf"sphx_glr_{example.stem}_\d+\.png", page.read_text()), (
            f"{example.name} shows no figure"
        )
