"""Pages whose tables a benchmark renders between markers hold exactly what their stored
JSON (or, for the Rotor 37 set-up, the built-in scenes) renders today: a table edited by
hand, or left behind by a change of the renderer or the scenes, fails here."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PERFORMANCE = ROOT / "docs" / "performance"


def _marked(page: Path, name: str) -> str:
    text = page.read_text()
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    assert begin in text and end in text, f"{page.name} lost the {name} markers"
    return text[text.index(begin) + len(begin) : text.index(end)].strip()


def _check(page: Path, sections: dict[str, str], command: str) -> None:
    assert sections, f"nothing stored for {page.name}"
    for name, text in sections.items():
        assert _marked(page, name) == text.strip(), (
            f"{page.relative_to(ROOT)} section {name} differs from `{command}`"
        )


@pytest.mark.parametrize("study", ["abradable_convergence", "abradable_order"])
def test_abradable_page_is_its_json(load_benchmark, study):
    bench = load_benchmark(study)
    data = bench.read_json(bench.JSON)
    _check(bench.DOC, bench.render(data), f"python benchmarks/{study}.py --render-only")


def test_reduction_3d_page_is_its_json(load_benchmark):
    bench = load_benchmark("reduction_convergence_3d")
    sections = bench.stamped_sections(bench.read_json(bench.STORE), "reduction_3d")
    _check(bench.PAGE, sections, "python benchmarks/reduction_convergence_3d.py --render-only")


def test_rotor37_direction_is_its_json(load_benchmark):
    bench = load_benchmark("rotor37_direction")
    _check(bench.PAGE, bench.render(bench.read_json(bench.JSON)), bench.COMMAND + " --render-only")


def test_rotor37_setup_is_the_scenes(load_benchmark):
    bench = load_benchmark("rotor37_setup")
    _check(bench.PAGE, {bench.MARKER: bench.table()}, "python benchmarks/rotor37_setup.py")


def test_every_stored_section_is_stamped(load_benchmark):
    """Each stored study says when, at which commit and on what machine it was measured."""
    common = load_benchmark("_common")
    for name in ("abradable_convergence", "abradable_order", "reduction_3d"):
        path = PERFORMANCE / f"{name}.json"
        data = common.read_json(path) if path.exists() else {}
        assert data, f"{path.relative_to(ROOT)} is missing"
        for key, entry in data.items():
            m = entry["machine"]
            assert m["date"] and m["commit"] and m["cores"], f"{name}:{key} has no stamp"


@pytest.mark.parametrize(
    ("study", "marker"),
    [
        ("campbell_speed", "campbell_speed"),
        ("thermal_cost", "thermal_cost"),
        ("thermal_step", "thermal_step"),
    ],
)
def test_rotor37_study_pages_are_their_json(load_benchmark, study, marker):
    bench = load_benchmark(study)
    sections = {marker: bench.render(bench.C.read_json(bench.JSON))}
    _check(bench.PAGE, sections, f"python benchmarks/{study}.py --render-only")
