import importlib.util
import os
import sys
from pathlib import Path

import pytest
from hypothesis import settings

# property tests draw the same examples on every run (no database, no random seed):
# a failure is reproducible and CI cannot turn red by chance; HYPOTHESIS_PROFILE=explore
# draws fresh random examples when hunting for new failures
settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(scope="session", autouse=True)
def _model_cache_folder(tmp_path_factory):
    """Command-line runs in the tests cache their models in a temporary folder, not in the
    user's cache folder (``femrub.app.cache``)."""
    old = os.environ.get("FEMRUB_CACHE_DIR")
    os.environ["FEMRUB_CACHE_DIR"] = str(tmp_path_factory.mktemp("femrub-cache"))
    yield
    if old is None:
        os.environ.pop("FEMRUB_CACHE_DIR", None)
    else:
        os.environ["FEMRUB_CACHE_DIR"] = old


@pytest.fixture(scope="session")
def model_cache(_model_cache_folder):
    """The test run's :class:`~femrub.app.cache.ModelCache` (the folder the command-line runs
    use): tests whose property is a model's behaviour, not how it is built, share the
    assembled blocks, prestress and damping of the blades they have in common."""
    from femrub.app.cache import ModelCache

    return ModelCache(os.environ["FEMRUB_CACHE_DIR"])


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The read-only reference data folder; tests using it skip when it is absent."""
    path = Path(os.environ.get("FEMRUB_SHARED_DATA", ROOT.parent / "shared" / "data"))
    if not path.is_dir():
        pytest.skip(f"reference data not found at {path} (set FEMRUB_SHARED_DATA)")
    return path


@pytest.fixture(scope="session")
def load_benchmark():
    """``name -> module``: ``benchmarks/<name>.py`` imported by path (its folder on
    ``sys.path`` while it loads, for its sibling imports)."""
    bench = ROOT / "benchmarks"

    def load(name):
        sys.path.insert(0, str(bench))
        try:
            spec = importlib.util.spec_from_file_location(name, bench / f"{name}.py")
            mod = importlib.util.module_from_spec(spec)
            sys.modules[name] = mod  # dataclasses look their module up while it loads
            spec.loader.exec_module(mod)
        finally:
            sys.path.remove(str(bench))
        return mod

    return load
