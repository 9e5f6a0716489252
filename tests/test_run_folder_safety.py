"""Run folders: femrub never writes through a link, nor replaces or deletes what it did not
write; --overwrite removes the previous run's outputs first."""

from __future__ import annotations

import json

import pytest
from test_reliability_data_loss import BOX

from femrub.app.cli import main
from femrub.output.folder import FolderError, claim


@pytest.fixture
def box(tmp_path):
    path = tmp_path / "box.toml"
    path.write_text("# my commented scene\n" + BOX)
    return path


def test_running_into_the_scene_folder_never_replaces_the_scene(box, capsys, monkeypatch):
    monkeypatch.chdir(box.parent)
    before = box.read_text()
    mine = box.parent / "scene.toml"  # the user's file with the name of femrub's scene dump
    mine.write_text(before)
    assert main(["run", "box.toml", "-o", ".", "-q"]) == 2
    err = capsys.readouterr().err
    assert "not empty" in err and "was not written by femrub" in err and "--overwrite" in err
    assert main(["run", "box.toml", "-o", ".", "-q", "--overwrite"]) == 2
    assert "scene.toml was not written by femrub" in capsys.readouterr().err
    assert main(["run", "scene.toml", "-o", ".", "-q", "--overwrite"]) == 2
    assert "is the scene being run" in capsys.readouterr().err
    assert mine.read_text() == before and box.read_text() == before
    assert not (box.parent / "summary.json").exists()


def test_the_scene_being_run_is_never_replaced(box, capsys):
    out = box.parent / "out"
    assert main(["run", str(box), "-o", str(out), "-q", "--set", "scheme.t_end=1e-5"]) == 0
    dumped = out / "scene.toml"
    dumped.write_text(dumped.read_text() + "# my note\n")
    before = dumped.read_text()
    assert main(["run", str(dumped), "-o", str(out), "-q", "--overwrite"]) == 2
    assert "is the scene being run" in capsys.readouterr().err
    assert dumped.read_text() == before


def test_a_users_history_is_never_replaced(tmp_path, box, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "history.csv").write_text("my own data\n")
    assert main(["run", str(box), "-o", str(out), "-q"]) == 2
    assert main(["run", str(box), "-o", str(out), "-q", "--overwrite"]) == 2
    assert "history.csv was not written by femrub" in capsys.readouterr().err
    assert (out / "history.csv").read_text() == "my own data\n"


def test_overwrite_removes_the_previous_runs_vtk(tmp_path, box):
    out = tmp_path / "out"
    assert main(["run", str(box), "-o", str(out), "-q"]) == 0
    assert (out / "vtk" / "rub.pvd").exists()
    (out / "notes.txt").write_text("mine")  # the user's file in femrub's folder
    argv = ["run", str(box), "-o", str(out), "-q", "--overwrite"]
    assert main([*argv, "--set", "outputs.vtk_stride=0"]) == 0
    assert not (out / "vtk").exists()
    assert json.loads((out / "summary.json").read_text())["vtk"] is None
    assert (out / "notes.txt").read_text() == "mine"


@pytest.mark.parametrize("name", [".femrub.lock", ".femrub", "explain.txt", "vtk", "summary.json"])
def test_planted_links_are_refused_and_their_targets_untouched(tmp_path, name):
    out = tmp_path / "out"
    out.mkdir()
    (out / ".femrub").write_text('{"kind": "run"}\n') if name != ".femrub" else None
    target = tmp_path / "precious"
    target.mkdir() if name == "vtk" else target.write_text("precious")
    (out / name).symlink_to(target)
    with pytest.raises(FolderError, match="symbolic link"):
        with claim(out, "run", overwrite=True):
            pytest.fail("claimed")
    assert target.is_dir() if name == "vtk" else target.read_text() == "precious"


def test_links_inside_vtk_are_refused(tmp_path):
    out = tmp_path / "out"
    (out / "vtk").mkdir(parents=True)
    (out / ".femrub").write_text('{"kind": "run"}\n')
    target = tmp_path / "precious"
    target.write_text("precious")
    (out / "vtk" / "rub.pvd").symlink_to(target)
    with pytest.raises(FolderError, match="symbolic link"):
        with claim(out, "run", overwrite=True):
            pass
    assert target.read_text() == "precious"


def test_json_and_figures_replace_a_link_made_after_the_claim(tmp_path):
    """A link planted while the run goes is replaced, never written through."""
    import matplotlib.pyplot as plt

    from femrub.output.jsonfile import write_json
    from femrub.output.plots import savefig

    target = tmp_path / "precious"
    target.write_text("precious")
    for name in ("summary.json", "summary.json.tmp", "signals.png"):
        (tmp_path / name).symlink_to(target)
    write_json(tmp_path / "summary.json", {"a": 1})
    savefig(plt.figure(), tmp_path / "signals.png")
    assert target.read_text() == "precious"
    assert json.loads((tmp_path / "summary.json").read_text()) == {"a": 1}
    assert not (tmp_path / "signals.png").is_symlink()


def test_a_users_summary_json_is_not_taken_for_femrubs(tmp_path, box, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "summary.json").write_text("my notes, not JSON")
    assert main(["run", str(box), "-o", str(out), "-q", "--overwrite"]) == 2
    assert "summary.json was not written by femrub" in capsys.readouterr().err
    assert (out / "summary.json").read_text() == "my notes, not JSON"
