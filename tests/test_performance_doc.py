"""docs/performance.md §1–6 are what ``benchmarks/run_all.py --render-only`` writes from the
committed JSON files and hand-written notes (so a re-render loses nothing)."""

import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def run_all(load_benchmark):
    return load_benchmark("run_all")


def test_render_only_reproduces_the_committed_document(run_all, tmp_path):
    doc = tmp_path / "performance.md"
    shutil.copy(ROOT / "docs" / "performance.md", doc)
    shutil.copytree(ROOT / "docs" / "performance", tmp_path / "performance")
    run_all.render(tmp_path / "performance", doc)
    assert doc.read_text() == (ROOT / "docs" / "performance.md").read_text(), (
        "docs/performance.md §1–6 differ from what `python benchmarks/run_all.py --render-only` "
        "writes: put hand text in benchmarks/performance_notes.py or exponential_notes.py"
    )


def test_render_keeps_the_record_of_earlier_runs(run_all, tmp_path):
    doc = tmp_path / "performance.md"
    shutil.copytree(ROOT / "docs" / "performance", tmp_path / "performance")
    text = run_all.render(tmp_path / "performance", doc).read_text()
    assert "### Earlier runs" in text and "Issue 13, first pass" in text
    assert "## 6. Exponential Moreau stepper" in text
