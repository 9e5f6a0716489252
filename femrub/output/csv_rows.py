"""CSV rows of a numeric table, written fast and byte-identical to :mod:`csv`.

``history.csv`` of a long run holds millions of numbers; :func:`write_csv_rows` formats them
by one ``%`` per block of rows instead of one Python call per row (``docs/api.md``);
:func:`decimate_columns` thins a table to a sensible resolution, impulses summed.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CSV_ROWS", "decimate_columns", "write_csv_rows"]

#: rows formatted per call of :func:`write_csv_rows` (bounds its temporary strings)
CSV_ROWS = 4096


def write_csv_rows(fh, table: np.ndarray) -> None:
    """Write the rows of a 2D ``table`` to the text file ``fh`` as :mod:`csv` writes them
    (``repr`` of each number, ``,`` between, ``\\r\\n`` after: the same bytes as
    ``csv.writer(fh).writerows(table.tolist())``), formatted by one ``%`` per block of
    :data:`CSV_ROWS` rows instead of a Python call per row."""
    if table.ndim != 2 or table.shape[0] == 0:
        return
    line = ",".join(["%r"] * table.shape[1]) + "\r\n"
    for i in range(0, table.shape[0], CSV_ROWS):
        block = table[i : i + CSV_ROWS]
        fh.write((line * block.shape[0]) % tuple(block.ravel().tolist()))


def decimate_columns(cols: dict, every: int) -> dict:
    """Rows ``0, every, 2 every, …, last`` of ``cols``, impulses summed over the rows left out
    (:meth:`~femrub.output.results.Results.save_csv`)."""
    t = cols["t"]
    idx = np.unique(np.r_[np.arange(0, t.size, every), t.size - 1]) if t.size else t.astype(int)
    out = {k: np.asarray(v)[idx].copy() for k, v in cols.items()}
    if idx.size < 2:
        return out
    dt = np.diff(t[idx])
    for k in cols:
        if k.startswith("contact_impulse"):
            total = np.add.reduceat(np.asarray(cols[k]), idx[:-1] + 1)  # (idx[j-1], idx[j]]
            out[k][1:] = total
            force = "contact_force" + k[len("contact_impulse") :]
            if force in out:
                out[force][1:] = total / np.where(dt > 0, dt, np.inf)
    return out
