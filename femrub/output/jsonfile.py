"""Strict JSON files: written atomically, never ``NaN`` or ``Infinity`` (not JSON).

Non-finite floats (an unconditionally stable scheme's stability limit ``inf``, an energy
error ``nan`` when there is no balance) are written as ``null``; numpy scalars and arrays
become numbers and lists; anything else becomes its text.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .safe_write import write_atomic

__all__ = ["jsonable", "read_json", "write_json"]


def jsonable(x):
    """``x`` with every value a strict JSON value (non-finite floats -> ``None``)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, np.generic):
        return jsonable(x.item())
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, int | str | bool) or x is None:
        return x
    return str(x)


def write_json(path, doc: dict) -> None:
    """Write ``doc`` to ``path`` atomically (a temporary file beside it, flushed, then
    renamed: never through a symbolic link, :func:`~femrub.output.safe_write.atomic_file`)."""
    text = json.dumps(jsonable(doc), indent=2, allow_nan=False)
    write_atomic(path, text)


def read_json(path) -> dict:
    """Parse ``path``; raise ``ValueError`` (one line) when it is unreadable or not an object."""
    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"{path} is unreadable ({type(exc).__name__}: {exc})") from None
    if not isinstance(doc, dict):
        raise ValueError(f"{path} is not a JSON object")
    return doc
