"""Contact-node targets on the blade tip: points along the tip camber line."""

from __future__ import annotations

import gmsh
import numpy as np

from .errors import GeometryError

__all__ = ["camber_points", "chord_fractions", "embed_points_on_surface"]


def chord_fractions(n: int, margin: float = 0.05) -> np.ndarray:
    """Evenly spaced chord fractions in ``[margin, 1 - margin]``.

    Parameters
    ----------
    n : int
        Number of points (>= 0).
    margin : float, optional
        Distance from leading and trailing edge as a fraction of chord, in ``[0, 0.5)``.

    Returns
    -------
    numpy.ndarray
        Shape ``(n,)``; a single point sits at mid-chord.
    """
    if n < 0 or not 0.0 <= margin < 0.5:
        raise GeometryError(f"Need n_contact >= 0 and 0 <= margin < 0.5, got {n} and {margin}.")
    return np.full(1, 0.5) if n == 1 else np.linspace(margin, 1.0 - margin, n)


def _at_chord_fraction(side: np.ndarray, le: np.ndarray, chord: np.ndarray, s: np.ndarray):
    """Interpolate a side polyline at chordwise fractions ``s`` (projection on the chord)."""
    u = (chord @ (side - le[:, None])) / (chord @ chord)
    order = np.argsort(u)
    u, side = u[order], side[:, order]
    keep = np.concatenate([[True], np.diff(u) > 0])
    return np.vstack([np.interp(s, u[keep], row[keep]) for row in side])


def camber_points(side_a: np.ndarray, side_b: np.ndarray, fractions: np.ndarray) -> np.ndarray:
    """Points on the mean (camber) line of a section given by its two sides.

    Both sides run from the leading edge to the trailing edge; the camber point
    at chord fraction ``s`` is the midpoint of the two sides at that fraction of
    the leading-to-trailing-edge chord.

    Parameters
    ----------
    side_a, side_b : numpy.ndarray
        Side polylines, shape ``(3, m)``, sharing first and last points.
    fractions : numpy.ndarray
        Chord fractions in ``[0, 1]``.

    Returns
    -------
    numpy.ndarray
        Camber-line points, shape ``(3, len(fractions))``.
    """
    le = 0.5 * (side_a[:, 0] + side_b[:, 0])
    te = 0.5 * (side_a[:, -1] + side_b[:, -1])
    chord = te - le
    a = _at_chord_fraction(side_a, le, chord, fractions)
    b = _at_chord_fraction(side_b, le, chord, fractions)
    return 0.5 * (a + b)


def embed_points_on_surface(targets: np.ndarray, surface: int, size: float) -> list[int]:
    """Project points onto a model surface and embed them in its mesh.

    The OpenCASCADE model must be synchronised before the call; it is
    synchronised again afterwards.

    Parameters
    ----------
    targets : numpy.ndarray
        Approximate locations, shape ``(3, n)``.
    surface : int
        Tag of the surface (dimension 2).
    size : float
        Mesh size prescribed at the embedded points.

    Returns
    -------
    list of int
        Tags of the new point entities, in the order of ``targets``.
    """
    tags = []
    for x in np.asarray(targets, dtype=float).T:
        on_surface = gmsh.model.getClosestPoint(2, surface, x.tolist())[0]
        tags.append(gmsh.model.occ.addPoint(*on_surface))
    gmsh.model.occ.synchronize()
    if tags:
        gmsh.model.mesh.embed(0, tags, 2, surface)
        gmsh.model.mesh.setSize([(0, tag) for tag in tags], size)
    return tags
