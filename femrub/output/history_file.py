"""``history.csv`` appended block by block while a run goes (flushed to disk each time).

:class:`HistoryCSV` is an ``on_rows`` sink of :class:`~femrub.output.recorder.Recorder`:
each checked block of rows is flattened (:func:`~femrub.output.results.flatten_columns`,
any trailing shape) and appended, then the file is flushed and synced, so a run killed by
any signal (even SIGKILL) leaves a readable history of every block checked before it. The
header (written with the first block) carries the units (``t [s]``).

With ``every > 1`` (``outputs.csv_stride``) it writes the rows that
:meth:`~femrub.output.results.Results.save_csv` writes with the same ``every``: the first
step, every ``every``-th one and, on :meth:`HistoryCSV.close`, the last; ``contact_impulse*``
summed over the steps since the previous row written (carried from block to block) and
``contact_force*`` that impulse over the time since that row
(:func:`~femrub.output.csv_rows.decimate_columns`).
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from .csv_rows import write_csv_rows
from .results import UNITS, csv_header, flatten_columns
from .safe_write import naming, open_nofollow

__all__ = ["HistoryCSV", "NoHistoryCSV"]

_IMPULSE, _FORCE = "contact_impulse", "contact_force"


class HistoryCSV:
    """Append blocks of per-step arrays to ``path``, one row in ``every`` (module docstring);
    ``units``: units of signals :data:`~femrub.output.results.UNITS` does not know (probes).

    Attributes
    ----------
    rows : rows written to the file.
    received : steps received (rows of the run's history so far).
    """

    def __init__(self, path, every: int = 1, units: dict | None = None):
        self.path = Path(path)
        self.units = {**UNITS, **(units or {})}  # probes' units by signal name
        self.every = int(every)
        if self.every < 1:
            raise ValueError(f"HistoryCSV: every must be >= 1, got {every!r}")
        self.rows = self.received = 0
        self._fh = None
        self._columns: list[str] | None = None
        self._tail = None  # the last row received, unless written
        self._t_written = 0.0  # time of the last row written
        self._carry = None  # impulses since the last row written, through the last received
        self.error: OSError | None = None  # the write error that stopped the file
        self._good = 0  # bytes of the file up to its last complete block

    def __call__(self, arrays: dict[str, np.ndarray]) -> None:
        """Append a block; the first write error (a full disk) is raised once, with the
        file's name, and kept in :attr:`error` (later blocks are dropped: the run stops)."""
        if self.error is not None:
            return
        try:
            with naming(self.path):
                self._append(arrays)
        except OSError as exc:
            self.error = exc
            self._cut()
            raise

    def _cut(self) -> None:
        """Cut the file back to its last complete block (a write that failed half-way)."""
        if self._fh is None:
            return
        try:
            self._fh.flush()
        except OSError:
            pass
        try:
            os.truncate(self._fh.fileno(), self._good)
        except OSError:
            pass

    def _append(self, arrays: dict[str, np.ndarray]) -> None:
        cols = flatten_columns(arrays)
        if self._fh is None:
            self._fh = open_nofollow(self.path, "w", newline="")
            self._columns = list(cols)
            csv.writer(self._fh).writerow(csv_header(self._columns, self.units))
            self._fh.flush()
            self._good = self._fh.tell()
            self._imp = [j for j, k in enumerate(cols) if k.startswith(_IMPULSE)]
            names = {k: j for j, k in enumerate(cols)}
            self._frc = [
                names.get(_FORCE + self._columns[j][len(_IMPULSE) :], -1) for j in self._imp
            ]
            self._carry = np.zeros(len(self._imp))
        elif list(cols) != self._columns:
            raise ValueError(f"history columns changed during the run: {list(cols)}")
        block = np.column_stack(list(cols.values()))
        if block.shape[0] == 0:
            return
        if self.every > 1:
            block = self._decimated(block)
        else:
            self.received += block.shape[0]
        self._write(block)

    def _decimated(self, block: np.ndarray) -> np.ndarray:
        """The rows of ``block`` to write (module docstring); keeps the carry and the tail."""
        m, first = block.shape[0], self.received
        keep = np.flatnonzero((first + np.arange(m)) % self.every == 0)
        self.received += m
        self._tail = None if keep.size and keep[-1] == m - 1 else block[-1].copy()
        out = block[keep]
        if not self._imp:
            return out
        imp = block[:, self._imp]
        if not keep.size:
            self._carry = self._carry + imp.sum(axis=0)
            return out
        starts = np.r_[0, keep + 1]
        sums = np.add.reduceat(imp, starts[starts < m], axis=0)  # (previous row, kept row]
        sums[0] += self._carry
        self._carry = sums[keep.size] if sums.shape[0] > keep.size else np.zeros(imp.shape[1])
        self._set_impulses(out, sums[: keep.size], first + keep == 0)
        self._t_written = block[keep[-1], 0]
        return out

    def _set_impulses(self, rows: np.ndarray, impulse: np.ndarray, at_start: np.ndarray) -> None:
        """Write the summed ``impulse`` into ``rows`` (not the run's first row, which keeps its
        own) and the mean forces over the time since the previous row written."""
        t_prev = np.r_[self._t_written, rows[:-1, 0]]
        dt = rows[:, 0] - t_prev
        later = ~at_start
        for c, (j, f) in enumerate(zip(self._imp, self._frc)):
            rows[later, j] = impulse[later, c]
            if f >= 0:
                rows[later, f] = impulse[later, c] / np.where(dt[later] > 0, dt[later], np.inf)

    def _write(self, block: np.ndarray) -> None:
        write_csv_rows(self._fh, block)
        self.rows += block.shape[0]
        self._fh.flush()
        os.fsync(self._fh.fileno())
        self._good = self._fh.tell()

    def close(self) -> None:
        """Write the last row received when one row in ``every`` left it out, and close."""
        if self._fh is None:
            return
        if self._tail is not None and self.error is None:
            row = self._tail[None, :].copy()
            if self._imp:
                self._set_impulses(row, self._carry[None, :], np.zeros(1, dtype=bool))
            try:
                with naming(self.path):
                    self._write(row)
            except OSError as exc:
                self.error = exc
                self._cut()
            self._tail = None
        try:
            self._fh.close()
        except OSError as exc:
            self.error = self.error or exc
        self._fh = None


class NoHistoryCSV:
    """What a run keeps instead of :class:`HistoryCSV` with ``outputs.csv_stride = 0``: no
    file (the run streams it no rows)."""

    rows = received = 0
    error = None

    def close(self) -> None:
        """Nothing to close."""
