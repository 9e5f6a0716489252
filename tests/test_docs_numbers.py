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


def test_factorisation_table_is_the_benchmarks_and_sets_the_threshold(load_benchmark):
    """docs/performance/blade-scale.md's SuperLU-against-Pardiso table is the one
    benchmarks/factorisation_size.py renders from its JSON, and ``PARDISO_ABOVE`` sits where
    that table says Pardiso is the faster."""
    from femrub.fem.linalg import PARDISO_ABOVE

    study = load_benchmark("factorisation_size")
    doc = study.C.read_json(study.JSON)
    page = study.PAGE.read_text()
    begin, end = "<!-- factorisation_size:begin -->", "<!-- factorisation_size:end -->"
    quoted = page[page.index(begin) + len(begin) : page.index(end)].strip()
    assert quoted == study.table(doc), "blade-scale.md differs from factorisation_size.json"
    above = [r["ratio"] for r in doc["rows"] if r["unknowns"] >= PARDISO_ABOVE]
    below = [r["ratio"] for r in doc["rows"] if r["unknowns"] < PARDISO_ABOVE]
    assert above and min(above) > 1.0, above
    assert below and max(below) < 1.0, below
