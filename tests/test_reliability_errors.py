"""Errors, hangs and paths: one-line errors before any expensive work, no writes outside the
working folder, strict JSON and units in every output (docs/reliability.md)."""

import json

import numpy as np
import pytest
from bar_scenes import bar_scene

import femrub.app.run as run_mod
from femrub.analysis import ThetaMethod
from femrub.app.cli import main
from femrub.cases.bar import bar_model
from femrub.output.results import Results
from femrub.scene import SceneError, loads_scene

TINY = bar_scene("tiny", 5, 0.01)


@pytest.fixture()
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


def _one_error(capsys, *words):
    err = capsys.readouterr().err
    assert err.startswith("femrub: error: ") and err.count("\n") == 1, err
    for w in words:
        assert w in err, err
    return err


@pytest.mark.parametrize("workers", ["-1", "-3"])
def test_sweep_needs_a_worker_count(tiny, tmp_path, capsys, workers):
    argv = [
        "sweep",
        str(tiny),
        "-o",
        str(tmp_path / "s"),
        "--param",
        "scheme.h=1e-4",
        "--workers",
        workers,
        "-q",
    ]
    assert main(argv) == 2
    _one_error(capsys, "worker processes", "0 to run here")
    assert not (tmp_path / "s").exists()


def test_element_count_is_bounded_before_meshing(capsys):
    argv = ["check", "twisted-naca", "-q", "--set", "geometry.kind=box", "--set", "geometry.h=2e-5"]
    assert main(argv) == 2
    _one_error(capsys, "geometry.h", "tetrahedra", "raise geometry.h")


def test_unwritable_output_folder_is_reported_before_the_build(tiny, tmp_path, capsys, monkeypatch):
    def no_build(*a, **k):
        raise AssertionError("the model was built before the folder was checked")

    monkeypatch.setattr(run_mod, "build", no_build)
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    assert main(["run", str(tiny), "-o", str(blocker / "out"), "-q"]) == 2
    _one_error(capsys, "cannot write to the output folder")


def test_step_cap_on_every_entry_point(capsys):
    assert main(["paper", "--t-end", "1e6", "--out", "/tmp/femrub-never-written"]) == 2
    _one_error(capsys, "--t-end", "steps", "at most")
    with pytest.raises(ValueError, match="at most"):
        ThetaMethod(bar_model(), 1e-6).run(1e6)


@pytest.mark.parametrize(
    "name, folder", [("../../X", "X-out"), ("/abs/path", "abs_path-out"), ("..", "scene-out")]
)
def test_scene_name_cannot_write_outside_the_working_folder(tmp_path, monkeypatch, name, folder):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    (work / "s.toml").write_text(TINY.replace('name = "tiny"', f"name = {json.dumps(name)}"))
    assert main(["run", "s.toml", "-q"]) == 0
    assert (work / folder / "summary.json").is_file()
    assert sorted(p.name for p in tmp_path.rglob("summary.json")) == ["summary.json"]


def _strict(text):
    def refuse(c):
        raise ValueError(f"{c} is not JSON")

    return json.loads(text, parse_constant=refuse)


def test_json_outputs_are_strict_and_files_carry_units(tiny, tmp_path):
    out = tmp_path / "paper"
    assert main(["paper", "--out", str(out), "--figures", "fig7", "--t-end", "0.01", "-q"]) == 0
    s = _strict((out / "summary.json").read_text())
    assert s["runs"][0]["stability_limit"] is None  # the θ-method has none (was Infinity)
    assert s["units"]["h"] == "s"
    assert "[s]" in (out / "fig7.csv").read_text().splitlines()[0]
    run = tmp_path / "run"
    assert main(["run", str(tiny), "-o", str(run), "-q"]) == 0
    s = _strict((run / "summary.json").read_text())
    assert s["units"]["t"] == "s" and s["units"]["energy_kinetic"] == "J"
    header = (run / "history.csv").read_text().splitlines()[0].split(",")
    assert header[:2] == ["t [s]", "tip_displacement [m]"]
    assert "contact_force [N]" in header and "kinetic [J]" in header
    with np.load(run / "history.npz") as d:
        meta = _strict(str(d["meta"]))
    assert meta["units"]["gap"] == "m" and meta["units"]["signal_tip_temperature"] == "K"
    assert Results.load_npz(run / "history.npz").steps == 100


def test_deeply_nested_tables_are_a_clean_error(tmp_path, capsys):
    text = "x = " + "{a = " * 2000 + "1" + "}" * 2000 + "\n"
    with pytest.raises(SceneError, match="nested too deeply"):
        loads_scene(text)
    (tmp_path / "deep.toml").write_text(text)
    assert main(["check", str(tmp_path / "deep.toml"), "-q"]) == 2
    _one_error(capsys, "nested too deeply")
    assert main(["check", "paper", "-q", "--set", "name=" + "[" * 3000 + "]" * 3000]) == 2
    _one_error(capsys, "nested too deeply")
