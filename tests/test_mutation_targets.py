"""The mutation check's fast form: every mutation of ``benchmarks/mutation_smoke.py`` applies.

The full check (``python benchmarks/mutation_smoke.py``) plants each one-line physics bug and
runs the tests that must catch it. Here, in the default test run, each bug's target text must
stand exactly once in its file, and the planted text must differ from it and parse: a line
that moved or changed fails this test instead of turning the mutation "not applicable".
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def mutations(load_benchmark):
    return load_benchmark("mutation_smoke").MUTATIONS


def test_names_are_unique(mutations):
    names = [m.name for m in mutations]
    assert len(names) == len(set(names))


def test_every_mutation_applies_exactly_once(mutations):
    for m in mutations:
        source = (ROOT / m.path).read_text(encoding="utf-8")
        assert source.count(m.old) == 1, f"{m.name}: target found {source.count(m.old)} times"
        assert m.new != m.old, m.name
        ast.parse(source.replace(m.old, m.new))  # the planted bug is still Python


def test_every_mutation_names_existing_tests(mutations):
    for m in mutations:
        assert m.tests, m.name
        for test in m.tests:
            assert (ROOT / test).is_file(), f"{m.name}: no test file {test}"
