"""Physical stop criteria of a run: ``{signal name or "contact_force": max |value|}``.

:class:`~femrub.output.recorder.Recorder` checks each chunk of rows against them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["limit_index", "limit_hit"]


def limit_index(limits, names, sizes):
    """Columns of each observed signal in the observation rows; checks the limit names."""
    idx, col = {}, 0
    for name, size in zip(names, sizes):
        idx[name] = slice(col, col + size)
        col += size
    for key in limits:
        if key != "contact_force" and key not in idx:
            raise ValueError(f"stop limit on unknown signal {key!r}; use one of {names}")
    return idx


def limit_hit(limits, idx, rows, force):
    """First ``(row, message)`` where a stop limit is exceeded in a block, or ``None``."""
    first = None
    for key, bound in limits.items():
        vals = force if key == "contact_force" else rows[:, idx[key]]
        if vals.size:
            over = np.any(np.abs(vals) > bound, axis=1)
            if over.any() and (first is None or np.argmax(over) < first[0]):
                first = (int(np.argmax(over)), f"{key} exceeded {bound:g}")
    return first
