"""Length units accepted by the mesh readers and section loaders."""

from __future__ import annotations

from .errors import GeometryError

__all__ = ["LENGTH_UNITS", "length_scale"]

#: Factor converting one unit of length to metres.
LENGTH_UNITS: dict[str, float] = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}


def length_scale(unit: str) -> float:
    """Return the factor converting lengths in ``unit`` to metres.

    Parameters
    ----------
    unit : str
        One of ``"m"``, ``"cm"`` or ``"mm"`` (case-insensitive).

    Returns
    -------
    float
        Multiply coordinates in ``unit`` by this factor to get metres.

    Raises
    ------
    GeometryError
        If the unit is not recognised.
    """
    key = str(unit).strip().lower() if isinstance(unit, str) else None
    if key not in LENGTH_UNITS:
        choices = ", ".join(repr(u) for u in LENGTH_UNITS)
        raise GeometryError(f"Unknown length_unit {unit!r}; use one of {choices}.")
    return LENGTH_UNITS[key]
