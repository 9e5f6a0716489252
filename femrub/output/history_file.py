"""``history.csv`` appended block by block while a run goes (flushed to disk each time).

:class:`HistoryCSV` is an ``on_rows`` sink of :class:`~femrub.output.recorder.Recorder`:
each checked block of rows is flattened (:func:`~femrub.output.results.flatten_columns`,
any trailing shape) and appended, then the file is flushed and synced, so a run killed by
any signal (even SIGKILL) leaves a readable history of every block checked before it. The
header (written with the first block) carries the units (``t [s]``).
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from .csv_rows import write_csv_rows
from .results import UNITS, csv_header, flatten_columns

__all__ = ["HistoryCSV"]


class HistoryCSV:
    """Append blocks of per-step arrays to ``path`` (see module docstring)."""

    def __init__(self, path):
        self.path = Path(path)
        self.rows = 0
        self._fh = None
        self._columns: list[str] | None = None

    def __call__(self, arrays: dict[str, np.ndarray]) -> None:
        cols = flatten_columns(arrays)
        if self._fh is None:
            self._fh = self.path.open("w", newline="")
            self._writer = csv.writer(self._fh)
            self._columns = list(cols)
            self._writer.writerow(csv_header(self._columns, UNITS))
        elif list(cols) != self._columns:
            raise ValueError(f"history columns changed during the run: {list(cols)}")
        block = np.column_stack(list(cols.values()))
        write_csv_rows(self._fh, block)
        self.rows += block.shape[0]
        self._fh.flush()
        os.fsync(self._fh.fileno())

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None
