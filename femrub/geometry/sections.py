"""Airfoil section files (x, y, z point lists) and their split into two sides."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .errors import GeometryError
from .units import length_scale

__all__ = ["orient_sides", "read_section", "read_sections", "section_files", "split_section"]


def read_section(path: str | Path, length_unit: str = "cm") -> np.ndarray:
    """Read one closed section from a text file of ``x, y, z`` rows.

    Comma- or whitespace-separated; a non-numeric header line (possibly with a
    byte-order mark) is skipped. A repeated closing point is removed.

    Parameters
    ----------
    path : str or pathlib.Path
        Section file, e.g. ``R37_profile01.csv``.
    length_unit : str, optional
        Unit of the coordinates (``"m"``, ``"cm"``, ``"mm"``).

    Returns
    -------
    numpy.ndarray
        Section points in metres, shape ``(3, n)``, open (first != last).

    Raises
    ------
    GeometryError
        If the file cannot be read or has fewer than 3 columns or 6 points.
    """
    scale = length_scale(length_unit)
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise GeometryError(
            f"Cannot read section file {str(path)!r}: {exc}; check the path."
        ) from exc
    rows = []
    for line in lines:
        fields = line.replace(",", " ").replace(";", " ").split()
        try:
            rows.append([float(v) for v in fields[:3]])
        except ValueError:
            if rows:
                raise GeometryError(
                    f"Non-numeric row {line!r} in section file {str(path)!r}."
                ) from None
    pts = np.array([r for r in rows if len(r) == 3], dtype=float)
    if pts.shape[0] < 6 or len(rows) != pts.shape[0]:
        raise GeometryError(
            f"Section file {str(path)!r} must hold at least 6 rows of x, y, z coordinates."
        )
    if np.allclose(pts[0], pts[-1]):
        pts = pts[:-1]
    return pts.T * scale


def section_files(paths: Sequence[str | Path] | str | Path, pattern: str = "*.csv") -> list[Path]:
    """Section files in hub-to-tip order.

    Parameters
    ----------
    paths : sequence of path, or a directory
        Files in hub-to-tip order, or a directory whose files matching ``pattern``
        are taken in sorted name order.
    pattern : str, optional
        Glob pattern used for a directory (Rotor 37: ``"R37_profile*.csv"``).

    Returns
    -------
    list of pathlib.Path
        At least two files.
    """
    if isinstance(paths, (str, Path)):
        folder = Path(paths)
        if not folder.is_dir():
            raise GeometryError(
                f"Section folder {str(folder)!r} does not exist; pass a folder or a list of files."
            )
        files = sorted(folder.glob(pattern))
    else:
        files = [Path(p) for p in paths]
    if len(files) < 2:
        raise GeometryError(
            f"Found {len(files)} section files (pattern {pattern!r}); need at least 2 hub to tip"
            " (pass pattern=... or a list of files)."
        )
    return files


def read_sections(
    paths: Sequence[str | Path] | str | Path, length_unit: str = "cm", pattern: str = "*.csv"
) -> list[np.ndarray]:
    """Read several sections, hub to tip.

    Parameters
    ----------
    paths : sequence of path, or a directory
        See :func:`section_files`.
    length_unit : str, optional
        Unit of the coordinates.
    pattern : str, optional
        Glob pattern used when ``paths`` is a directory.

    Returns
    -------
    list of numpy.ndarray
        Sections in metres, each ``(3, n)``.
    """
    return [read_section(p, length_unit) for p in section_files(paths, pattern)]


def split_section(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split a closed section at its leading and trailing edge into two sides.

    The edges are the two points farthest apart (the chord ends); which one is
    the leading edge is irrelevant for meshing, the first is the one with the
    smaller coordinate along the largest-extent direction.

    Parameters
    ----------
    points : numpy.ndarray
        Closed section without repeated end point, shape ``(3, n)``.

    Returns
    -------
    side_a, side_b : numpy.ndarray
        Sides ``(3, m)`` from the leading to the trailing edge, sharing end points.
    """
    from scipy.spatial import ConvexHull
    from scipy.spatial.distance import pdist, squareform

    pts = np.asarray(points, dtype=float)
    try:
        hull = ConvexHull(pts.T, qhull_options="QJ").vertices
    except Exception:  # pragma: no cover - degenerate input
        hull = np.arange(pts.shape[1])
    dist = squareform(pdist(pts[:, hull].T))
    i, j = np.unravel_index(np.argmax(dist), dist.shape)
    i, j = hull[i], hull[j]
    direction = pts[:, j] - pts[:, i]
    if direction[np.argmax(np.abs(direction))] < 0:
        i, j = j, i
    n = pts.shape[1]
    chord = float(np.linalg.norm(direction))
    gap = float(np.linalg.norm(pts[:, -1] - pts[:, 0]))
    if gap > 0.2 * chord or min((j - i) % n, (i - j) % n) < 2:
        raise GeometryError(
            f"Points do not form a closed airfoil section (end gap {gap:.3g} vs chord {chord:.3g})."
        )
    rolled = np.roll(pts, -i, axis=1)
    k = (j - i) % n
    side_a = rolled[:, : k + 1]
    side_b = np.hstack([rolled[:, k:], rolled[:, :1]])[:, ::-1]
    return side_a, side_b


def _side_normal(side_a: np.ndarray) -> np.ndarray:
    """``(TE − LE) × (m − LE)``, ``m`` the middle point of side ``a``: which side it is."""
    le, te, mid = side_a[:, 0], side_a[:, -1], side_a[:, side_a.shape[1] // 2]
    return np.cross(te - le, mid - le)


def orient_sides(sides: list[tuple[np.ndarray, np.ndarray]]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Sections' sides (:func:`split_section`) made to match the first section's.

    :func:`split_section` names the leading edge by the sign of the chord's largest
    component, which can flip from section to section of a twisted blade; a loft between
    mismatched sections crosses itself. Section ``k`` is turned end for end when its first
    point lies nearer to the trailing edge of section ``k − 1`` than to its leading edge, and
    its sides are swapped when side ``a`` lies on the other side of the chord than section
    ``k − 1``'s side ``a`` (the sign of ``n_k · n_{k−1}``, ``n = (TE − LE) × (m − LE)``,
    ``m`` the side's middle point; consecutive sections twist by less than 90°).

    Parameters
    ----------
    sides : list of (numpy.ndarray, numpy.ndarray)
        Each section's two sides ``(3, m)``, hub to tip.

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray)
        The same sides, from the same edge and in the same order as the first section's.
    """
    out = [sides[0]]
    for a, b in sides[1:]:
        pa = out[-1][0]
        if np.linalg.norm(a[:, 0] - pa[:, 0]) > np.linalg.norm(a[:, 0] - pa[:, -1]):
            a, b = b[:, ::-1], a[:, ::-1]
        if _side_normal(a) @ _side_normal(pa) < 0:
            a, b = b, a
        out.append((a, b))
    return out
