"""Blade lofted from section files (e.g. NASA Rotor 37 profiles) with gmsh."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .blade_mesh import BladeMesh
from .errors import GeometryError
from .loft import loft_blade
from .mesh_size import MeshSize
from .sections import orient_sides, read_section, section_files, split_section

__all__ = ["sections_blade"]


#: largest number of tetrahedra a lofted blade may get (as a box or NACA blade)
MAX_TETS = 2_000_000
# tetrahedra per h³ of volume in a gmsh mesh of size h (regular tetrahedra: 6 √2)
_TETS_PER_H3 = 8.5


def estimate_section_tets(sections: list[np.ndarray], h: float) -> float:
    """Tetrahedra of a blade lofted through the closed ``sections`` ((3, m) points, m) at
    element size ``h`` (m): its volume (section areas times the distances between their
    centroids) over ``h² min(t, h)``, ``t`` the thinnest section's area over its chord."""
    areas, centres, thin = [], [], np.inf
    for pts in sections:
        nxt = np.roll(pts, -1, axis=1)
        area = 0.5 * float(np.linalg.norm(np.cross(pts.T, nxt.T).sum(axis=0)))
        chord = float(np.linalg.norm(np.ptp(pts, axis=1))) or 1.0
        areas.append(area)
        centres.append(pts.mean(axis=1))
        thin = min(thin, area / chord)
    gaps = np.linalg.norm(np.diff(np.array(centres), axis=0), axis=1)
    volume = float(np.sum(0.5 * (np.array(areas[1:]) + np.array(areas[:-1])) * gaps))
    t = min(thin, h) if thin > 0 else h
    return _TETS_PER_H3 * (volume / h) / h / t


def sections_blade(
    paths: Sequence[str | Path] | str | Path,
    *,
    length_unit: str = "cm",
    pattern: str = "*.csv",
    radial_axis="x",
    h: float | None = None,
    h_min: float | None = None,
    n_contact: int = 16,
    contact_margin: float = 0.05,
    interpolate: bool = False,
    ruled: bool = False,
    verbose: bool = False,
) -> BladeMesh:
    """Loft and mesh a blade through section point files.

    Each file is a closed section of ``x, y, z`` points (see
    :func:`~femrub.geometry.sections.read_section`), given hub to tip. The
    sections need not be planar: non-planar end sections are capped with
    filling surfaces. Contact nodes are placed on the tip camber line (midpoints
    of the two sides at equal chord fractions) projected onto the tip face.

    Parameters
    ----------
    paths : sequence of path, or a directory
        Section files hub to tip, or a folder of ``*.csv`` files (sorted by name).
    length_unit : str, optional
        Unit of the coordinates in the files (Rotor 37 profiles: ``"cm"``).
    pattern : str, optional
        Glob pattern when ``paths`` is a folder (Rotor 37: ``"R37_profile*.csv"``).
    radial_axis : str or array_like, optional
        Rotation axis of the machine (Rotor 37 profiles: ``"x"``).
    h : float, optional
        Target element size in metres (default: 1/12 of the tip chord).
    h_min : float, optional
        Lower bound of the element size (default ``h / 4``).
    n_contact : int, optional
        Number of contact nodes on the tip camber line.
    contact_margin : float, optional
        Chord fraction kept free of contact nodes at each edge.
    interpolate : bool, optional
        Interpolating splines (True) or B-splines with the points as control
        points (False, default; smoother on dense measured data).
    ruled : bool, optional
        Ruled loft between sections.
    verbose : bool, optional
        Show gmsh messages.

    Returns
    -------
    BladeMesh
        Mesh in metres with node sets ``root``, ``tip``, ``contact``.
    """
    sections, raw = [], []
    files = section_files(paths, pattern)
    for path in files:
        try:
            raw.append(read_section(path, length_unit))
            sections.append(split_section(raw[-1]))
        except GeometryError as exc:
            raise GeometryError(
                f"Section file {str(path)!r}: {exc} Pass pattern=... or only airfoil section files."
            ) from exc
    sections = orient_sides(sections)
    tip_chord = float(np.linalg.norm(sections[-1][0][:, -1] - sections[-1][0][:, 0]))
    size = MeshSize(tip_chord / 12 if h is None else h, h_min)
    n = estimate_section_tets(raw, size.h)
    if n > MAX_TETS:
        raise GeometryError(
            f"h = {size.h:.4g} m gives about {min(n, 1e300):.2g} tetrahedra between these "
            f"sections (at most {MAX_TETS:.0e}, estimated before meshing); raise h"
        )
    names = [f.name for f in files]
    source = f"sections_blade({', '.join(names)}, unit={length_unit}, h={size.h:.4g})"
    return loft_blade(
        sections,
        size,
        radial_axis,
        n_contact=n_contact,
        contact_margin=contact_margin,
        interpolate=interpolate,
        ruled=ruled,
        verbose=verbose,
        source=source,
    )
