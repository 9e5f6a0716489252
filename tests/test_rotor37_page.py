"""The results of ``docs/rotor37.md`` are what ``benchmarks/rotor37.py --render-only`` writes
from the committed ``docs/rotor37/results-*.json`` (a note naming the command when none is
committed); the rest of the page quotes no measured number."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("rotor37")


def _section(page: str, marker: str) -> str:
    begin, end = f"<!-- {marker}:begin -->", f"<!-- {marker}:end -->"
    return page[page.index(begin) + len(begin) : page.index(end)].strip()


def test_results_section_is_what_the_committed_json_renders(bench):
    page = bench.PAGE.read_text()
    assert _section(page, bench.MARKER) == bench.render(bench.committed()).strip(), (
        "docs/rotor37.md's results differ from `python benchmarks/rotor37.py --render-only`"
    )


def _row(n: int = 16) -> dict:
    return {
        "status": "ok",
        "revolutions": 50.0,
        "steps": 50000,
        "n_dofs": 176,
        "n_full": 194276,
        "timings": {"assembly": 10.5, "stepping": 1.9},
        "cpu_per_step_us": 34.0,
        "energy_error": 9.7e-10,
        "max_contact_force": 38717.0,
        "max_friction_force": 5807.5,
        "friction_work": 946000.0,
        "coulomb_check": {"cone": 6.7e-16, "direction": 4.4e-16},
        "reduction_error": {"estimate": 0.021, "status": "ok"},
        "time_step_error": None,
        "rms_um_first": [163.8] * n,
        "rms_um_last": [149.8] * n,
        "max_um_first": [374.4] * n,
        "max_um_last": [364.4] * n,
        "max_normal_force": [12965.8] * n,
        "max_friction_force_per_node": [1944.9] * n,
        "contact_fraction": [0.2492] * n,
    }


def test_render_stamps_each_scene_and_quotes_its_json(bench):
    machine = {"date": "2026-11-28 12:00 UTC", "commit": "abc1234", "python": "3.11", "cores": 2}
    text = bench.render({"rotor37": {"machine": machine, "results": _row()}})
    assert "2026-11-28 12:00 UTC, commit abc1234" in text
    assert "**ok**, 50.0 revolutions" in text and "2.1 % (ok)" in text
    assert "| 15 | 163.8 | 374.4 | 149.8 | 364.4 | 12965.8 | 1944.9 | 24.92 % |" in text


def test_render_without_results_names_the_command(bench):
    assert "python benchmarks/rotor37.py --docs" in bench.render({})


def test_run_skips_without_the_shared_data(bench, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("FEMRUB_SHARED_DATA", str(tmp_path / "absent"))
    assert bench.main(["--docs", "--out", str(tmp_path / "out")]) == 0
    assert "skipped: no Rotor 37 mesh" in capsys.readouterr().out
    assert not (tmp_path / "out").exists()
