"""The Rotor 37 validation page (modes and prestress against CalculiX) is what
``benchmarks/campbell_rotor37.py --render-only`` writes from its committed JSON, each run
stamped with where it was measured; without the shared data the generator skips cleanly."""

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("campbell_rotor37")


@pytest.fixture(scope="module")
def data(bench):
    return json.loads(bench.DATA.read_text())


def test_page_is_what_the_json_renders(bench, data):
    assert bench.PAGE.read_text() == bench.render(data), (
        "docs/validation/rotor37-calculix.md differs from what "
        "`python benchmarks/campbell_rotor37.py --render-only` writes from its JSON"
    )


def test_every_run_is_stamped_and_compared_with_calculix(bench, data):
    page = bench.PAGE.read_text()
    assert set(data["runs"]) == {"linear", "nonlinear"}
    for method, run in data["runs"].items():
        assert run["machine"].get("commit"), f"the {method} run has no commit stamp"
        assert f"{method} run: " in page and str(run["machine"]["commit"]) in page
        rest = run["rest_frequencies_hz"]
        for f, ref in zip(rest, data["calculix"]["frequencies_hz"]):
            assert f"{f:.2f}" in page and f"{100 * (f / ref - 1):+.2f} %" in page


def test_calculix_frequencies_are_stamped_where_ccx_ran(bench, data):
    ccx = data["calculix"]
    assert len(ccx["frequencies_hz"]) >= 6 and ccx["machine"]["commit"]
    assert ccx["ccx_version"] in bench.PAGE.read_text()
    assert ccx["machine"]["date"] in bench.PAGE.read_text()


def test_rest_frequencies_stay_within_half_a_percent_of_calculix(data):
    """The first three modes of the committed diagrams (measured with older code) and the
    first eight of the model measured beside CalculiX (within 0.3 %: 0.27 % at mode 6)."""
    ref = data["calculix"]["frequencies_hz"]
    for run in data["runs"].values():
        for f, f_ref in zip(run["rest_frequencies_hz"][:3], ref):
            assert abs(f / f_ref - 1) < 0.005
    for f, f_ref in zip(data["calculix"]["femrub_frequencies_hz"][:8], ref):
        assert abs(f / f_ref - 1) < 0.003


def test_render_reads_its_numbers_from_the_json(bench, data):
    changed = json.loads(json.dumps(data))
    changed["runs"]["nonlinear"]["rest_frequencies_hz"][0] = 400.0
    changed["runs"]["nonlinear"]["tip_growth_max_m"][-1] = 0.0123
    text = bench.render(changed)
    assert "| 400.00 | +28.15 % |" in text and "12.300 / " in text


def test_page_is_in_the_validation_section():
    assert "validation/rotor37-calculix" in (DOCS / "validation.md").read_text()


def test_generator_skips_without_the_shared_data(bench, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("FEMRUB_SHARED_DATA", str(tmp_path / "absent"))
    monkeypatch.setattr(bench, "DATA", tmp_path / "rotor37.json")
    monkeypatch.setattr(bench, "PAGE", tmp_path / "rotor37.md")
    bench.main(["nonlinear"])
    assert "skipped: no Rotor 37 mesh" in capsys.readouterr().out
    assert not (tmp_path / "rotor37.json").exists() and not (tmp_path / "rotor37.md").exists()


def test_generator_refuses_an_unknown_method(bench):
    with pytest.raises(SystemExit):
        bench.main(["quadratic"])
