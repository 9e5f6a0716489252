"""The documentation reads as documentation: no page over 600 lines, no project-history
vocabulary in the package, docs or benchmarks, and every number of the paper's reproduction
page resolves from ``femrub paper``'s ``summary.json``."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
GENERATED = ("_build", "auto_examples", "generated")
MAX_LINES = 600
#: project-history words (a third-party module name such as ``skfem.helpers`` is not one)
HISTORY = re.compile(r"\bsessions?\s+\d+|\bissue[-_\s]?\d+|\bhelpers?\b", re.IGNORECASE)
ALLOWED = ("skfem.helpers",)
TEXT = {".py", ".md", ".rst", ".toml", ".txt", ".json", ".csv", ".cfg", ".ini", ".yaml", ".yml"}


def _tracked(*paths: str) -> list[Path]:
    done = subprocess.run(
        ["git", "-C", str(ROOT), "ls-files", "--cached", "--others", "--exclude-standard", *paths],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        pytest.skip("not a git checkout")
    return [ROOT / p for p in done.stdout.split() if (ROOT / p).is_file()]


def _pages() -> list[Path]:
    pages = [p for p in _tracked("docs") if p.suffix in (".md", ".rst")]
    pages = [p for p in pages if not set(p.relative_to(DOCS).parts) & set(GENERATED)]
    return [*pages, ROOT / "README.md", ROOT / "CHANGELOG.md"]


def test_no_page_is_over_600_lines():
    pages = _pages()
    assert len(pages) > 10
    long = {
        p.relative_to(ROOT).as_posix(): n
        for p in pages
        if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not long, f"pages over {MAX_LINES} lines (split them by what a reader needs): {long}"


def _history_words(text: str) -> list[str]:
    for allowed in ALLOWED:
        text = text.replace(allowed, "")
    return [m.group(0) for m in HISTORY.finditer(text)]


def test_no_history_vocabulary_in_package_docs_or_benchmarks():
    files = [p for p in _tracked("femrub", "docs", "benchmarks", "README.md") if p.suffix in TEXT]
    assert any(p.name == "__init__.py" for p in files)
    found = {
        p.relative_to(ROOT).as_posix(): words
        for p in files
        if (words := _history_words(p.read_text(encoding="utf-8", errors="replace")))
    }
    assert not found, f"history belongs in git and CHANGELOG.md: {found}"


def test_the_vocabulary_check_catches_each_form():
    text = "as in session 4, see issue-13 or issue 31; a helper; from skfem.helpers import dot"
    assert _history_words(text) == ["session 4", "issue-13", "issue 31", "helper"]
    assert _history_words("a gmsh session: initialise, quiet") == []


def test_every_number_of_the_paper_page_comes_from_its_summary():
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        import paper_numbers
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    values = paper_numbers.substitutions(DOCS / "paper" / "summary.json")
    used = re.findall(r"\{\{\s*(\w+)\.(\w+)\s*\}\}", (DOCS / "paper-reproduction.md").read_text())
    assert used
    missing = sorted({f"{run}.{key}" for run, key in used if key not in values.get(run, {})})
    assert not missing, (
        f"paper-reproduction.md quotes numbers summary.json does not give: {missing}"
    )
