"""The performance pages (``docs/performance.md`` and ``docs/performance/*.md`` of
``run_all.PAGES``) are what ``benchmarks/run_all.py --render-only`` writes from the committed
JSON files and hand-written notes: a page edited by hand, or a JSON file changed without
re-rendering, fails here."""

import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


@pytest.fixture(scope="module")
def run_all(load_benchmark):
    return load_benchmark("run_all")


@pytest.fixture
def rendered(run_all, tmp_path):
    shutil.copytree(DOCS / "performance", tmp_path / "performance")
    run_all.render(tmp_path / "performance", tmp_path / "performance.md")
    return tmp_path


def test_render_only_reproduces_the_committed_pages(run_all, rendered):
    for name in ["performance.md", *(f"performance/{page}" for page in run_all.PAGES)]:
        assert (rendered / name).read_text() == (DOCS / name).read_text(), (
            f"docs/{name} differs from what `python benchmarks/run_all.py --render-only` "
            "writes: put hand text in benchmarks/performance_notes.py or exponential_notes.py"
        )


def test_every_listed_page_exists_and_is_short(run_all, rendered):
    for name in [*run_all.PAGES, *run_all.OTHER_PAGES]:
        page = DOCS / "performance" / name
        assert page.exists(), f"docs/performance/{name} is listed but missing"
        assert len(page.read_text().splitlines()) <= 600, f"{name} is over 600 lines"


def test_each_study_page_says_where_its_numbers_come_from(rendered):
    for name in ("speed-and-accuracy.md", "against-siconos.md", "hard-case-stability.md"):
        assert "*Measured by `python benchmarks/" in (rendered / "performance" / name).read_text()
