"""Numbers the README quotes from the benchmarks match the files they come from."""

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_femrub_paper_cold_and_warm_times_are_the_benchmarks(load_benchmark):
    """The README's first-run and later-run times of `femrub paper` are the paragraph
    benchmarks/cold_start.py renders from its JSON, both measured in one run."""
    cold_start = load_benchmark("cold_start")
    doc = json.loads(cold_start.JSON.read_text())
    begin, end = "<!-- cold_start:begin -->", "<!-- cold_start:end -->"
    assert begin in README and end in README, "README lost the cold_start markers"
    quoted = README[README.index(begin) + len(begin) : README.index(end)].strip()
    assert quoted == cold_start.table(doc), "README differs from docs/performance/cold_start.json"
    assert doc["cold"]["wall_s"] > 0 and len(doc["warm"]) >= 1
