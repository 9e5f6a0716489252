"""Numbers the README quotes from the benchmarks match the files they come from."""

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _benchmark(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    import sys

    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return module


def test_femrub_paper_cold_and_warm_times_are_the_benchmarks():
    """The README's first-run and later-run times of `femrub paper` are the paragraph
    benchmarks/cold_start.py renders from its JSON, both measured in one run."""
    cold_start = _benchmark("cold_start")
    doc = json.loads(cold_start.JSON.read_text())
    begin, end = "<!-- cold_start:begin -->", "<!-- cold_start:end -->"
    assert begin in README and end in README, "README lost the cold_start markers"
    quoted = README[README.index(begin) + len(begin) : README.index(end)].strip()
    assert quoted == cold_start.table(doc), "README differs from docs/performance/cold_start.json"
    assert doc["cold"]["wall_s"] > 0 and len(doc["warm"]) >= 1
