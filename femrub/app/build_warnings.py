"""Warnings of a scene's build: kept in its report (``summary.json["inputs"]["build"]``),
raised as Python warnings and logged; they do not stop the build."""

from __future__ import annotations

import warnings

import numpy as np

__all__ = ["initial_penetration", "warn"]


def warn(msg: str | None, report: dict, log=None) -> None:
    """Record ``msg`` (nothing when ``None``) in ``report["warnings"]``, raise it as a
    ``UserWarning`` and log it."""
    if msg:
        report.setdefault("warnings", []).append(msg)
        warnings.warn(msg, stacklevel=3)
        if log:
            log(f"warning: {msg}")


def initial_penetration(model) -> str | None:
    """The warning when contacts start inside the casing (negative gap at t = 0): how many,
    by how much, which."""
    c = model.contact
    g = np.zeros(0) if c is None else np.asarray(c.gap_at(0.0), dtype=float)
    inside = np.flatnonzero(g < 0.0)
    if not inside.size:
        return None
    return (
        f"{inside.size} of {c.n} contacts start inside the casing at t = 0, by up to "
        f"{-g.min() * 1e6:.3g} um ({', '.join(c.names[i] for i in inside[:4])}"
        f"{', ...' if inside.size > 4 else ''}): the first steps push them out"
    )
