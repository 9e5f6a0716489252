"""Rotation-axis handling: axis vectors, radii and radial directions."""

from __future__ import annotations

import numpy as np

from .errors import GeometryError

__all__ = ["axis_vector", "radial_coordinates"]

_NAMED = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def axis_vector(axis) -> np.ndarray:
    """Return the unit vector of a machine rotation axis.

    Parameters
    ----------
    axis : str or array_like
        ``"x"``, ``"y"`` or ``"z"`` (case-insensitive), or a non-zero 3-vector.

    Returns
    -------
    numpy.ndarray
        Unit vector of shape ``(3,)``.

    Raises
    ------
    GeometryError
        If ``axis`` is neither a known name nor a non-zero 3-vector.
    """
    if isinstance(axis, str):
        key = axis.strip().lower()
        if key not in _NAMED:
            raise GeometryError(f"Unknown rotation axis {axis!r}; use 'x', 'y', 'z' or a 3-vector.")
        return np.array(_NAMED[key])
    vec = np.asarray(axis, dtype=float).reshape(-1)
    norm = np.linalg.norm(vec) if vec.shape == (3,) else 0.0
    if not np.isfinite(norm) or norm == 0.0:
        raise GeometryError(f"Invalid rotation axis {axis!r}; use 'x', 'y', 'z' or a 3-vector.")
    return vec / norm


def radial_coordinates(points: np.ndarray, axis) -> tuple[np.ndarray, np.ndarray]:
    """Return radius and unit radial direction of points about an axis through the origin.

    Parameters
    ----------
    points : numpy.ndarray
        Coordinates, shape ``(3, n)``.
    axis : str or array_like
        Rotation axis, see :func:`axis_vector`.

    Returns
    -------
    radius : numpy.ndarray
        Distance to the axis, shape ``(n,)``.
    e_r : numpy.ndarray
        Unit radial direction, shape ``(3, n)`` (zero for points on the axis).
    """
    a = axis_vector(axis)
    pts = np.asarray(points, dtype=float).reshape(3, -1)
    perp = pts - np.outer(a, a @ pts)
    radius = np.linalg.norm(perp, axis=0)
    e_r = np.divide(perp, radius, out=np.zeros_like(perp), where=radius > 0)
    return radius, e_r
