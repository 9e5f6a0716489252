"""Data loss and overwrites: results folders are owned, locked, streamed and never replaced
silently (docs/reliability.md)."""

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import meshio
import numpy as np
import pytest
from bar_scenes import bar_scene

import femrub.app.sweep as sweep_mod
from femrub.analysis import ThetaMethod
from femrub.app.cli import main
from femrub.output.folder import claim
from femrub.output.results import Results

ROOT = Path(__file__).resolve().parents[1]

TINY = bar_scene("tiny", 5, 0.02)

BOX = """
name = "box"
[geometry]
kind = "box"
span = 0.1
chord = 0.03
thickness = 0.003
h = 0.01
n_contact = 3
[contact]
casing = { kind = "concentric", clearance = "20 um" }
friction = 0.02
[loads]
rotation_speed = 1500.0
tip_force = { law = "sin", amplitude = 30.0, frequency = "1500 rad/s" }
[reduction]
method = "craig-bampton"
n_uv = 8
n_theta = 4
[scheme]
h = 2e-6
t_end = 1e-4
[outputs]
vtk_stride = 10
plots = false
"""


@pytest.fixture()
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


def _rows(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def test_unreadable_summary_is_not_taken_for_no_result(tiny, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(tiny), "-o", str(out), "-q"]) == 0
    (out / "summary.json").write_text('{"status": "ok", "steps": 2')  # truncated by a full disk
    history = (out / "history.csv").read_bytes()
    assert main(["run", str(tiny), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert "unreadable" in err and "--overwrite" in err and err.count("\n") == 1
    assert (out / "history.csv").read_bytes() == history
    assert main(["run", str(tiny), "-o", str(out), "-q", "--overwrite"]) == 0


def test_commands_do_not_write_into_each_others_folders(tiny, tmp_path, capsys):
    run_out, paper_out = tmp_path / "run", tmp_path / "paper"
    assert main(["run", str(tiny), "-o", str(run_out), "-q"]) == 0
    summary = (run_out / "summary.json").read_bytes()
    # a paper reproduction or a sweep never replaces a run's results, even with --overwrite
    assert main(["paper", "--out", str(run_out), "--figures", "fig7", "-q", "--overwrite"]) == 2
    assert "femrub run" in capsys.readouterr().err
    argv = ["sweep", str(tiny), "-o", str(run_out), "--param", "scheme.h=1e-4", "-q"]
    assert main(argv) == 2
    assert "femrub run" in capsys.readouterr().err
    assert (run_out / "summary.json").read_bytes() == summary
    # a run never replaces a paper reproduction
    paper_out.mkdir()
    (paper_out / "summary.json").write_text(json.dumps({"status": "ok", "runs": []}))
    assert main(["run", str(tiny), "-o", str(paper_out), "-q", "--overwrite"]) == 2
    assert "femrub paper" in capsys.readouterr().err
    assert json.loads((paper_out / "summary.json").read_text())["runs"] == []


def test_a_folder_in_use_is_refused(tiny, tmp_path, capsys):
    out = tmp_path / "out"
    with claim(out, "run"):  # another femrub process writing there
        assert main(["run", str(tiny), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert "in use by another femrub process" in err and err.count("\n") == 1
    assert not (out / "summary.json").exists()
    assert main(["run", str(tiny), "-o", str(out), "-q"]) == 0  # released


def test_history_is_streamed_in_checked_blocks(tiny, tmp_path, monkeypatch):
    """The CSV holds every block checked before a crash of the process itself."""
    out = tmp_path / "out"
    real_step, calls, seen = ThetaMethod._step, [0], []

    def step(self):
        calls[0] += 1
        if calls[0] == 150:  # the history file as it is on disk at this moment
            seen.append(len(_rows(out / "history.csv")))
        return real_step(self)

    monkeypatch.setattr("femrub.output.recorder.CHUNK_STEPS", 64)
    monkeypatch.setattr(ThetaMethod, "_step", step)
    monkeypatch.setattr(ThetaMethod, "block_steps", False)  # step by step, to look inside
    assert main(["run", str(tiny), "-o", str(out), "-q"]) == 0
    assert seen == [129]  # rows 0..128: two checked blocks of 64 steps, flushed
    rows = _rows(out / "history.csv")
    assert len(rows) == 201 and float(rows[-1]["t [s]"]) == pytest.approx(0.02)


def _spawn(scene, out):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "femrub", "run", str(scene), "-o", str(out), "-q"]
    return subprocess.Popen(cmd, env=env, stderr=subprocess.PIPE, text=True)


def _wait_rows(path, n, proc, timeout=120):
    t0 = time.time()
    while time.time() - t0 < timeout:
        if path.exists() and path.read_text().count("\n") > n:
            return
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.05)
    raise AssertionError("no history streamed")


@pytest.mark.parametrize("signals", [1, 2])
def test_sigterm_and_double_signal_keep_every_finished_step(tmp_path, signals):
    scene = tmp_path / "long.toml"
    scene.write_text(TINY.replace("t_end = 0.02", "t_end = 50.0"))
    out = tmp_path / "out"
    proc = _spawn(scene, out)
    _wait_rows(out / "history.csv", 1000, proc)
    proc.send_signal(signal.SIGTERM)
    if signals == 2:
        time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "interrupted" and s["steps"] > 1000
    res = Results.load_npz(out / "history.npz")
    assert res.steps == s["steps"] and res.t.size == s["steps"] + 1
    rows = _rows(out / "history.csv")
    assert len(rows) == s["steps"] + 1
    t = np.array([float(r["t [s]"]) for r in rows])
    assert np.allclose(np.diff(t), 1e-4)


def test_paper_honours_ctrl_c(tmp_path, capsys, monkeypatch):
    real_step, calls = ThetaMethod._step, [0]

    def step(self):
        calls[0] += 1
        if calls[0] == 250:  # during the second run of Fig. 2
            raise KeyboardInterrupt
        return real_step(self)

    monkeypatch.setattr(ThetaMethod, "_step", step)
    monkeypatch.setattr(
        ThetaMethod, "block_steps", False
    )  # step by step (blocks: test_theta_blocks)
    out = tmp_path / "paper"
    assert main(["paper", "--out", str(out), "--figures", "fig2,fig3", "--t-end", "0.02"]) == 130
    assert "interrupted" in capsys.readouterr().err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "interrupted" and len(s["runs"]) == 1
    assert not (out / "fig3.png").exists()
    # an interrupted reproduction is not a finished one: rerunning starts again
    monkeypatch.setattr(ThetaMethod, "_step", real_step)
    assert main(["paper", "--out", str(out), "--figures", "fig2", "--t-end", "0.02", "-q"]) == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    assert main(["paper", "--out", str(out), "--figures", "fig2", "--t-end", "0.02", "-q"]) == 2
    assert "--overwrite" in capsys.readouterr().err


def _serial(scene, todo, scheduler, workers, progress, cache=None):
    for r in todo:
        r.update(
            sweep_mod.run_point(
                scene.data, scene.source, str(scene.base_dir), r["params"], r["folder"]
            )
        )


def test_resumed_sweep_keys_points_by_the_resolved_scene(tiny, tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_mod, "_compute", _serial)
    out = tmp_path / "sweep"
    argv = ["sweep", str(tiny), "-o", str(out), "--param", "heat_coefficient=1,3", "-q"]
    assert main(argv) == 0
    first = sorted(p.name for p in (out / "runs").iterdir())
    assert main(argv) == 0  # same scene: both points skipped
    rows = _rows(out / "interaction.csv")
    assert [r["skipped"] for r in rows] == ["True", "True"]
    # the scene changed: the points run again into new folders, the old results stay
    assert main([*argv, "--set", "scheme.t_end=0.01"]) == 0
    rows = _rows(out / "interaction.csv")
    assert [r["skipped"] for r in rows] == ["False", "False"]
    assert all(float(r["t_reached_s"]) == pytest.approx(0.01) for r in rows)
    now = sorted(p.name for p in (out / "runs").iterdir())
    assert set(first) < set(now) and len(now) == 4
    for name in first:
        s = json.loads((out / "runs" / name / "summary.json").read_text())
        assert s["t_reached"] == pytest.approx(0.02)


def test_vtk_frames_are_complete_and_stale_frames_removed(tmp_path):
    scene = tmp_path / "box.toml"
    scene.write_text(BOX)
    out = tmp_path / "out"
    (out / "vtk").mkdir(parents=True)
    (out / ".femrub").write_text('{"kind": "run"}\n')  # an earlier run of femrub's
    (out / "vtk" / "rub_000099.vtu").write_text("stale frame of an earlier run")
    (out / "vtk" / "rub_000007.vtu.tmp").write_text("half-written")
    assert main(["run", str(scene), "-o", str(out), "-q"]) == 0
    files = sorted(p.name for p in (out / "vtk").iterdir())
    assert "rub_000099.vtu" not in files and not any(f.endswith(".tmp") for f in files)
    pvd = (out / "vtk" / "rub.pvd").read_text()
    assert "femrub units:" in pvd and "temperature [K above ambient]" in pvd
    vtus = [f for f in files if f.endswith(".vtu")]
    assert len(vtus) == 6 and all(f in pvd for f in vtus)
    for f in vtus:
        m = meshio.read(out / "vtk" / f)
        assert set(m.point_data) >= {"displacement", "temperature", "contact_force"}
        assert b"femrub units:" in (out / "vtk" / f).read_bytes()[:400]
