"""`femrub run | check | scenes | scene show`: results folder, explain, interruption, refusal."""

import csv
import json

import pytest

from femrub.analysis import ThetaMethod
from femrub.app.cli import main

TINY = """
name = "tiny"
[geometry]
kind = "bar"
n_elements = 5
[contact]
casing = { kind = "concentric", clearance = "15 um" }
heat_coefficient = 3.0
[loads]
rotation_speed = "2000 rpm"
tip_force = { law = "sin", amplitude = 7.0 }
[scheme]
h = 1e-4
t_end = 0.05
"""
#: the runs whose plots no test here looks at (test_run_writes_the_results_folder does)
NO_PLOTS = ["--set", "outputs.plots=false"]


@pytest.fixture()
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


def _rows(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def test_run_writes_the_results_folder(tiny, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(tiny), "-o", str(out), "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    for name in (
        "history.csv",
        "history.npz",
        "summary.json",
        "signals.png",
        "scene.toml",
        "explain.txt",
    ):
        assert (out / name).is_file(), name
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "ok" and s["steps"] == 500
    assert s["inputs"]["scene"]["geometry"]["n_elements"] == 5
    assert s["inputs"]["versions"]["femrub"] and s["wall_seconds"] > 0
    assert s["energy_error"] < 1e-6 and "kinetic" in s["energy"]
    assert len(_rows(out / "history.csv")) == 501
    # the scene written into the folder reruns as it is
    assert main(["check", str(out / "scene.toml"), "-q"]) == 0


def test_the_run_names_the_files_it_wrote(tiny, tmp_path, capsys):
    """Without ``history.csv`` (``outputs.csv_stride = 0``) and plots, the closing line names
    what the folder holds."""
    out = tmp_path / "out"
    sets = ["--set", "outputs.csv_stride=0", "--set", "outputs.plots=false"]
    assert main(["run", str(tiny), "-o", str(out), *sets]) == 0
    said = [line for line in capsys.readouterr().out.splitlines() if "results in" in line]
    assert said == [f"  results in {out}/: summary.json, history.npz"]
    assert not (out / "history.csv").exists() and (out / "history.npz").is_file()
    sets += ["--set", "outputs.history_npz=false"]
    assert main(["run", str(tiny), "-o", str(tmp_path / "lean"), *sets]) == 0
    said = [line for line in capsys.readouterr().out.splitlines() if "results in" in line]
    assert said == [f"  results in {tmp_path / 'lean'}/: summary.json"]
    assert sorted(p.name for p in (tmp_path / "lean").iterdir() if p.suffix != ".lock") == [
        ".femrub",
        "explain.txt",
        "scene.toml",
        "summary.json",
    ]


def test_rerun_refuses_to_overwrite_a_finished_result(tiny, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(tiny), "-o", str(out), "-q", *NO_PLOTS]) == 0
    before = (out / "summary.json").stat().st_mtime_ns
    assert main(["run", str(tiny), "-o", str(out), "-q", *NO_PLOTS]) == 2
    err = capsys.readouterr().err
    assert "already holds a finished result (status ok)" in err and "--overwrite" in err
    assert err.count("\n") == 1 and (out / "summary.json").stat().st_mtime_ns == before
    assert main(["run", str(tiny), "-o", str(out), "-q", "--overwrite", *NO_PLOTS]) == 0


def test_interrupted_run_keeps_partial_results(tiny, tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    real_step, calls = ThetaMethod._step, [0]

    def step(self):
        calls[0] += 1
        if calls[0] == 200:
            raise KeyboardInterrupt
        return real_step(self)

    monkeypatch.setattr(ThetaMethod, "_step", step)
    monkeypatch.setattr(
        ThetaMethod, "block_steps", False
    )  # step by step (blocks: test_theta_blocks)
    assert main(["run", str(tiny), "-o", str(out), "-q", *NO_PLOTS]) == 130
    err = capsys.readouterr().err
    assert "interrupted at t = " in err and str(out) in err and "partial results kept" in err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "interrupted" and 0 < s["steps"] < 500
    rows = _rows(out / "history.csv")
    assert 1 < len(rows) < 501 and float(rows[-1]["t [s]"]) < 0.05
    # an interrupted result is not a finished one: the same command starts again
    monkeypatch.setattr(ThetaMethod, "_step", real_step)
    assert main(["run", str(tiny), "-o", str(out), "-q", *NO_PLOTS]) == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    assert main(["run", str(tiny), "-o", str(out), "-q", *NO_PLOTS]) == 2
    assert "--overwrite" in capsys.readouterr().err


def test_failed_run_keeps_partial_results(tiny, tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    real_step, calls = ThetaMethod._step, [0]

    def step(self):
        calls[0] += 1
        if calls[0] == 100:
            raise RuntimeError("solver exploded")
        return real_step(self)

    monkeypatch.setattr(ThetaMethod, "_step", step)
    monkeypatch.setattr(
        ThetaMethod, "block_steps", False
    )  # step by step (blocks: test_theta_blocks)
    assert main(["run", str(tiny), "-o", str(out), "-q", *NO_PLOTS]) == 1
    err = capsys.readouterr().err
    assert "run failed" in err and "solver exploded" in err and str(out) in err
    assert json.loads((out / "summary.json").read_text())["status"] == "failed"
    assert (out / "history.csv").is_file()


def test_stop_limit_ends_the_run(tiny, tmp_path):
    out = tmp_path / "out"
    assert (
        main(
            ["run", str(tiny), "-o", str(out), "-q", *NO_PLOTS, "--set", "limits.contact_force=1.0"]
        )
        == 0
    )
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "diverged-physically" and "contact_force exceeded 1" in s["message"]
    assert s["t_reached"] < 0.05


def test_explain_shows_dropped_physics_and_contacts(tiny, capsys):
    # no heat source: the temperature dofs go; the casing out of reach: the contact goes
    args = ["check", str(tiny), "--explain", "--set", "contact.heat_coefficient=0"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "40 state dofs" not in text and "20 state dofs (u 5 + v 5)" not in text
    assert "10 state dofs (u 5 + v 5), 1 contact(s)" in text
    assert "dropped: no heat source (contact.heat_coefficient = 0)" in text
    assert main(["check", str(tiny), "--explain", "--set", "contact.casing.clearance=1e-3"]) == 0
    text = capsys.readouterr().out
    assert "0 of 1 kept" in text and "dropped 1: never within reach" in text
    assert "no contact the casing can reach" in text and "0 contact(s)" in text


def test_explain_paper_scene(capsys):
    assert main(["check", "paper", "--explain"]) == 0
    text = capsys.readouterr().out
    assert "60 state dofs (u 20 + v 20 + θ 20), 1 contact(s)" in text
    assert "kept: frictional heat at the contacts (coupling 'paper')" in text
    assert "1 of 1 kept" in text and "none (reduction.method = 'none')" in text
    assert "40000 steps" in text and text.rstrip().endswith("s")


def test_explain_naca_scene_drops_contacts(capsys):
    args = ["check", "twisted-naca", "--explain", "--set", "reduction.method=none"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "2 of 8 kept" in text and "dropped 6: never within reach" in text
    assert "casing intrusion 30 µm" in text and "FE dofs" in text


def test_scenes_and_scene_show(capsys):
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    assert "paper" in out and "twisted-naca" in out and "rotor37" in out
    assert main(["scene", "show", "paper"]) == 0
    assert 'name = "paper"' in capsys.readouterr().out
    assert main(["scene", "show", "nope"]) == 2
    assert "built-ins: " in capsys.readouterr().err


def test_schema_only_check(capsys):
    assert main(["check", "rotor37", "--schema-only", "--set", "geometry.path=/x/none.inp"]) == 2
    assert "geometry.path = '/x/none.inp': file /x/none.inp not found" in capsys.readouterr().err
