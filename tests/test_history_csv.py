"""``history.csv`` streamed at one row in ``every`` (``HistoryCSV``, ``outputs.csv_stride``)."""

from __future__ import annotations

import numpy as np
import pytest

from femrub.output.csv_rows import decimate_columns
from femrub.output.history_file import HistoryCSV
from femrub.output.results import flatten_columns


def _history(n: int, seed: int = 0) -> dict:
    """A run's per-step arrays: times, a signal, impulses of three contacts (zero while
    open) and their forces, as :meth:`Results.per_step` gives them."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(np.r_[0.0, rng.uniform(0.5, 1.5, n - 1)]) * 1e-6
    imp = rng.random((n, 3)) * (rng.random((n, 3)) < 0.4)
    return {
        "t": t,
        "tip_displacement": np.sin(t * 1e5),
        "contact_force": imp / 1e-6,
        "contact_impulse": imp,
    }


def _read(path):
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


@pytest.mark.parametrize("every", [1, 3, 10, 64, 500])
def test_blocks_of_any_size_give_the_decimated_table(tmp_path, every):
    n = 257
    arrays = _history(n)
    rng = np.random.default_rng(every)
    cuts = np.unique(np.r_[0, rng.integers(1, n, 12), n])  # blocks of 1 ... many rows
    sink = HistoryCSV(tmp_path / "h.csv", every=every)
    for a, b in zip(cuts[:-1], cuts[1:]):
        sink({k: v[a:b] for k, v in arrays.items()})
    sink.close()
    ref = flatten_columns(arrays)
    ref = decimate_columns(ref, every) if every > 1 else ref  # 1: every row as it came
    table = np.column_stack(list(ref.values()))
    got = _read(tmp_path / "h.csv")
    assert got.shape == table.shape and sink.rows == table.shape[0] and sink.received == n
    np.testing.assert_allclose(got, table, rtol=1e-13, atol=1e-13 * np.abs(table).max())
    cols = list(ref)
    imp = [j for j, c in enumerate(cols) if c.startswith("contact_impulse")]
    np.testing.assert_allclose(got[:, imp].sum(axis=0), arrays["contact_impulse"].sum(axis=0))
    header = (tmp_path / "h.csv").read_text().splitlines()[0]
    assert header.startswith("t [s],") and "contact_impulse_2 [N s]" in header


def test_a_stride_below_one_is_refused(tmp_path):
    with pytest.raises(ValueError):
        HistoryCSV(tmp_path / "h.csv", every=0)
