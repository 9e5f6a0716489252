"""Faults of the machine end with the right story: a full disk, a read error, SIGHUP, a
signal while a finished result is written."""

from __future__ import annotations

import errno
import json
import os
import signal

import numpy as np
import pytest
from test_reliability_data_loss import BOX

from femrub.app.cli import main
from femrub.output import history_file, run_folder
from femrub.output.folder import FINISHED

NO_SPACE = OSError(errno.ENOSPC, "No space left on device")


@pytest.fixture
def box(tmp_path):
    path = tmp_path / "box.toml"
    path.write_text(BOX.replace("vtk_stride = 10", "vtk_stride = 0"))
    return path


def _leftovers(out):
    return [p.name for p in out.rglob("*") if ".tmp" in p.name]


def _csv_rows(path):
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def test_a_full_disk_while_streaming_the_history(box, tmp_path, capsys, monkeypatch):
    real, calls = history_file.write_csv_rows, []

    def write(fh, block):
        calls.append(len(block))
        if len(calls) > 1:
            fh.write("0.5,1")  # part of a row reached the disk
            raise NO_SPACE
        real(fh, block)

    monkeypatch.setattr(history_file, "write_csv_rows", write)
    monkeypatch.setattr("femrub.output.recorder.CHUNK_STEPS", 10)
    out = tmp_path / "out"
    assert main(["run", str(box), "-o", str(out), "-q", "--set", "reduction.method=none"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "history.csv" in err and "No space left" in err and "free space" in err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and "history.csv" in s["message"]
    assert s["steps"] >= calls[0]
    assert _csv_rows(out / "history.csv").shape[0] >= calls[0]  # the first block is kept
    assert not _leftovers(out)


def test_a_full_disk_while_writing_the_final_files(box, tmp_path, capsys, monkeypatch):
    from femrub.output import results

    def savez(path, arrays):
        path.write_bytes(b"PK partial")
        raise NO_SPACE

    monkeypatch.setattr(results, "_savez", savez)
    out = tmp_path / "out"
    assert main(["run", str(box), "-o", str(out), "-q"]) == 1
    err = capsys.readouterr().err
    assert "history.npz" in err and "No space left on device" in err
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and "history.npz" in s["message"]
    rows = _csv_rows(out / "history.csv")
    assert rows.shape[0] == s["steps"] + 1  # every finished row kept
    assert not _leftovers(out) and not (out / "history.npz").exists()


def test_a_read_error_names_the_file(box, tmp_path, capsys, monkeypatch):
    import femrub.app.run as run_mod

    def build(*a, **k):
        raise OSError(errno.EIO, "Input/output error", "/data/blade.msh")

    monkeypatch.setattr(run_mod, "build", build)
    out = tmp_path / "out"
    assert main(["run", str(box), "-o", str(out), "-q"]) == 1
    err = capsys.readouterr().err.strip()
    assert "/data/blade.msh" in err and "Input/output error" in err and "check the disk" in err
    assert json.loads((out / "summary.json").read_text())["status"] == "failed"


def test_sighup_interrupts_with_status_129(box, tmp_path, capsys, monkeypatch):
    real, calls = history_file.HistoryCSV._append, []

    def append(self, arrays):
        calls.append(1)
        real(self, arrays)
        if len(calls) == 1:
            os.kill(os.getpid(), signal.SIGHUP)

    monkeypatch.setattr(history_file.HistoryCSV, "_append", append)
    monkeypatch.setattr("femrub.output.recorder.CHUNK_STEPS", 10)  # rows stream while stepping
    out = tmp_path / "out"
    assert main(["run", str(box), "-o", str(out), "-q", "--set", "reduction.method=none"]) == 129
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "interrupted"
    assert _csv_rows(out / "history.csv").shape[0] >= 1 and not _leftovers(out)


def test_ctrl_c_while_a_finished_result_is_written_keeps_it(box, tmp_path, capsys, monkeypatch):
    real = run_folder.savefig

    def savefig(fig, path):
        os.kill(os.getpid(), signal.SIGINT)
        return real(fig, path)

    monkeypatch.setattr(run_folder, "savefig", savefig)
    out = tmp_path / "out"
    assert main(["run", str(box), "-o", str(out), "-q", "--set", "outputs.plots=true"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] in FINISHED and (out / "signals.png").exists()
    assert f"they are complete (status {s['status']})" in capsys.readouterr().err
