"""The fast writers of the history files give what the standard ones give."""

import csv
import io
import json
import zipfile
import zlib

import numpy as np

from femrub.output import csv_rows as C
from femrub.output import results as R


def test_csv_rows_are_the_csv_modules_bytes(monkeypatch):
    monkeypatch.setattr(C, "CSV_ROWS", 7)  # several blocks, the last one short
    rng = np.random.default_rng(1)
    tables = [
        rng.standard_normal((50, 9)) * 10.0 ** rng.integers(-30, 30, 9),
        np.array([[np.nan, np.inf, -np.inf, -0.0, 0.0, 1e16, 1e-5, 0.1 + 0.2]] * 3),
        np.arange(12).reshape(3, 4),
        np.zeros((0, 3)),
    ]
    for table in tables:
        want, got = io.StringIO(), io.StringIO()
        csv.writer(want).writerows(table.tolist())
        C.write_csv_rows(got, table)
        assert got.getvalue() == want.getvalue()


def test_npz_is_a_compressed_numpy_archive(tmp_path):
    t = np.linspace(0.0, 1.0, 101)
    res = R.Results(
        scheme="theta",
        h=0.01,
        t=t,
        signals={"tip_displacement": np.sin(t)[:, None]},
        gap=np.cos(t)[:, None],
        impulse=np.abs(np.sin(3 * t))[:, None],
        steps=100,
    )
    path = res.save_npz(tmp_path / "history.npz")
    with np.load(path) as d:
        assert {"t", "gap", "impulse", "normal_force", "meta", "signal_tip_displacement"} <= set(
            d.files
        )
        assert json.loads(str(d["meta"]))["scheme"] == "theta"
        np.testing.assert_array_equal(d["normal_force"], res.force)
    back = R.Results.load_npz(path)
    np.testing.assert_array_equal(back.t, t)
    np.testing.assert_array_equal(back.signals["tip_displacement"], res.signals["tip_displacement"])
    with zipfile.ZipFile(path) as zf:  # compressed, as numpy.savez_compressed writes
        assert {i.compress_type for i in zf.infolist()} == {zipfile.ZIP_DEFLATED}


def test_npz_stores_what_does_not_deflate_as_it_is(tmp_path):
    """Arrays whose bytes barely deflate (noise-like floats of a long run) are stored as they
    are, those that do (a mostly zero contact history) deflated; both read back bit for bit
    with their dtypes, every row kept."""
    rng = np.random.default_rng(3)
    n = 40_000
    t = np.linspace(0.0, 1.0, n + 1)
    impulse = np.zeros((n + 1, 3))
    impulse[::97, 1] = 1e-3
    res = R.Results(
        scheme="theta",
        h=1.0 / n,
        t=t,
        signals={"tip_displacement": rng.standard_normal((n + 1, 1))},
        gap=rng.standard_normal((n + 1, 3)),
        impulse=impulse,
        contact_state=np.zeros((n + 1, 3), dtype=np.int8),
        steps=n,
    )
    path = res.save_npz(tmp_path / "history.npz")
    with zipfile.ZipFile(path) as zf:
        kinds = {i.filename: i.compress_type for i in zf.infolist()}
    assert kinds["gap.npy"] == kinds["signal_tip_displacement.npy"] == zipfile.ZIP_STORED
    assert kinds["impulse.npy"] == kinds["normal_force.npy"] == zipfile.ZIP_DEFLATED
    assert kinds["contact_state.npy"] == kinds["meta.npy"] == zipfile.ZIP_DEFLATED
    with zipfile.ZipFile(path) as zf:  # deflated by run-length matches (R.NPZ_STRATEGIES)
        size = zf.getinfo("impulse.npy").compress_size
    npy = io.BytesIO()
    np.lib.format.write_array(npy, impulse, allow_pickle=False)
    rle = zlib.compressobj(R.NPZ_LEVEL, zlib.DEFLATED, -15, 9, zlib.Z_RLE)
    assert size == len(rle.compress(npy.getvalue()) + rle.flush())
    with np.load(path) as d:
        for key, want in [("gap", res.gap), ("impulse", impulse), ("t", t)]:
            assert d[key].dtype == want.dtype
            np.testing.assert_array_equal(d[key], want)
        assert d["contact_state"].dtype == np.int8 and d["contact_state"].shape == (n + 1, 3)
        np.testing.assert_array_equal(d["signal_tip_displacement"], res.signals["tip_displacement"])


def test_friction_magnitude_in_blocks_is_the_norm_of_the_whole(monkeypatch):
    """``Results.friction_magnitude`` (rows taken a block at a time) equals the norm of the
    whole array bit for bit, with a short last block; no friction rows give no columns."""
    monkeypatch.setattr(R, "ROW_BLOCK", 7)
    rng = np.random.default_rng(3)
    m, nc = 30, 4
    res = R.Results(
        scheme="theta",
        h=1e-6,
        t=np.arange(m) * 1e-6,
        signals={},
        gap=np.zeros((m, nc)),
        impulse=np.zeros((m, nc)),
        friction_force=rng.standard_normal((m, nc, 3)) * 10.0 ** rng.integers(-8, 8, (m, nc, 1)),
    )
    np.testing.assert_array_equal(
        res.friction_magnitude(), np.linalg.norm(res.friction_force, axis=-1)
    )
    res.friction_force = None
    assert res.friction_magnitude().shape == (m, 0)


def test_npz_deflates_repeats_that_are_not_runs_by_the_default_strategy(tmp_path):
    """An array whose bytes repeat without runs (a periodic history) does not deflate by run
    lengths: the default strategy deflates it, instead of storing it as it is."""
    periodic = np.tile(np.random.default_rng(5).standard_normal(64), 4000)
    path = tmp_path / "h.npz"
    R._savez(path, {"periodic": periodic})
    with zipfile.ZipFile(path) as zf:
        info = zf.getinfo("periodic.npy")
    assert info.compress_type == zipfile.ZIP_DEFLATED
    assert info.compress_size < 0.1 * periodic.nbytes
    with np.load(path) as d:
        np.testing.assert_array_equal(d["periodic"], periodic)
