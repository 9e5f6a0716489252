"""The public API: ``import femrub as fr`` gives the user-level objects, each importable,
documented and listed in the API reference (``docs/reference/api.rst``), and importing the
package stays light (every name is imported on first use)."""

import inspect
import re
from pathlib import Path

import pytest

import femrub

ROOT = Path(__file__).resolve().parents[1]
API_PAGE = ROOT / "docs" / "reference" / "api.rst"
HEAVY = ("numpy", "scipy", "skfem", "numba", "matplotlib", "gmsh", "pyvista", "dask")
#: one user-level entry per stage of the pipeline (scene to results)
STAGES = (
    "load_scene",
    "Scene",
    "SceneError",
    "Simulation",
    "build",
    "run_scene",
    "BladeMesh",
    "read_mesh",
    "casing_profile",
    "bar_model",
    "solid_model",
    "build_rub",
    "RubConfig",
    "FirstOrderModel",
    "ThermoelasticCraigBampton",
    "ThetaMethod",
    "ExponentialMoreau",
    "RunOptions",
    "Results",
    "load_results",
)


def _documented_names(page: Path) -> set[str]:
    """Names of the autosummary entries written under ``.. currentmodule:: femrub``."""
    names, module, in_summary = set(), None, False
    for line in page.read_text().splitlines():
        if m := re.match(r"\.\. currentmodule:: (\S+)", line):
            module = m.group(1)
        elif line.startswith(".. autosummary::"):
            in_summary = True
        elif in_summary and re.match(r"   [A-Za-z_][\w.]*$", line) and module == "femrub":
            names.add(line.strip())
        elif line and not line.startswith(" "):
            in_summary = False
    return names


def test_every_user_stage_is_exported():
    assert set(STAGES) <= set(femrub.__all__)


@pytest.mark.parametrize("name", femrub.__all__)
def test_exported_name_is_importable_and_documented(name):
    namespace = {}
    exec(f"from femrub import {name}", namespace)
    obj = namespace[name]
    assert obj is getattr(femrub, name)
    doc = inspect.getdoc(obj if inspect.isclass(obj) or callable(obj) else type(obj))
    assert doc and len(doc.strip()) > 20, f"femrub.{name} has no docstring"


def test_api_reference_lists_every_exported_name_and_no_other():
    listed = {name for name in _documented_names(API_PAGE) if "." not in name}
    missing = sorted(set(femrub.__all__) - listed)
    stale = sorted(listed - set(femrub.__all__))
    assert not missing, f"femrub names missing from docs/reference/api.rst: {missing}"
    assert not stale, f"docs/reference/api.rst lists names femrub does not export: {stale}"


def test_the_reference_parser_sees_entries_and_modules():
    """The parser reads only the entries of ``femrub``'s own autosummary blocks."""
    names = _documented_names(API_PAGE)
    assert {"ThetaMethod", "Results", "geometry.read_gmsh"} <= names
    assert "autosummary::" not in " ".join(names)


def test_readme_snippet_names_resolve():
    readme = (ROOT / "README.md").read_text()
    used = set(re.findall(r"\bfr\.([A-Za-z_]\w*)", readme))
    assert {"bar_model", "ThetaMethod"} <= used
    assert not sorted(used - set(dir(femrub))), "README uses names femrub does not give"


def test_import_femrub_loads_nothing_heavy():
    from test_lazy_imports import _loaded

    loaded = _loaded("import femrub", HEAVY)
    assert loaded == [], f"import femrub loads {','.join(loaded)}"


def test_load_results_reads_a_folder_or_a_file_and_names_a_missing_one(tmp_path):
    model = femrub.bar_model(n_elements=4)
    res = femrub.ThetaMethod(model, 1e-5).run(2e-4)
    res.save_npz(tmp_path / "history.npz")
    for path in (tmp_path, tmp_path / "history.npz"):
        back = femrub.load_results(path)
        assert back.steps == res.steps and back.status == res.status
        assert (back.t == res.t).all()
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(FileNotFoundError, match="has no history.npz"):
        femrub.load_results(empty)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        femrub.load_results(tmp_path / "nowhere.npz")
