"""Twisted, tapered blade of NACA 4-digit sections lofted with gmsh."""

from __future__ import annotations

import numpy as np

from .blade_mesh import BladeMesh
from .contact_line import chord_fractions
from .errors import GeometryError, check_positive
from .loft import loft_blade
from .mesh_size import MeshSize
from .naca import naca4_parameters, naca4_sides

__all__ = ["naca_blade", "naca_sections"]


def naca_sections(
    code: str = "0012",
    span: float = 0.1,
    root_chord: float = 0.05,
    tip_chord: float = 0.035,
    twist: float = 20.0,
    n_sections: int = 5,
    *,
    hub_radius: float = 0.0,
    stacking: float = 0.25,
    n_points: int = 40,
):
    """Sections of a linearly tapered and twisted NACA 4-digit blade.

    Section k sits in the plane ``z = hub_radius + span * k / (n_sections - 1)``;
    its chord varies linearly from ``root_chord`` to ``tip_chord`` and it is
    rotated about the z-parallel stacking line through ``x = y = 0`` by
    ``twist * k / (n_sections - 1)`` degrees (counter-clockwise seen from the tip,
    i.e. from +x towards +y). The stacking point lies at chord fraction
    ``stacking`` of every section, so the root leading edge is at
    ``x = -stacking * root_chord``.

    Parameters
    ----------
    code : str, optional
        NACA 4-digit designation.
    span, root_chord, tip_chord : float, optional
        Lengths in metres.
    twist : float, optional
        Tip twist relative to the root in degrees.
    n_sections : int, optional
        Number of lofted sections (>= 2).
    hub_radius : float, optional
        z of the root section in metres.
    stacking : float, optional
        Chord fraction of the stacking (twist) axis.
    n_points : int, optional
        Points per section side.

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray)
        Two sides ``(3, n_points)`` per section, leading to trailing edge.
    """
    naca4_parameters(code)
    if n_sections < 2:
        raise GeometryError(f"n_sections must be >= 2, got {n_sections}.")
    check_positive("NACA blade", span=span, root_chord=root_chord, tip_chord=tip_chord)
    upper, lower = naca4_sides(code, n_points)
    sections = []
    for s in np.linspace(0.0, 1.0, n_sections):
        chord = root_chord + s * (tip_chord - root_chord)
        angle = np.radians(twist * s)
        rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        z = hub_radius + s * span
        sides = []
        for side in (upper, lower):
            xy = rot @ ((side - np.array([[stacking], [0.0]])) * chord)
            sides.append(np.vstack([xy, np.full(side.shape[1], z)]))
        sections.append(tuple(sides))
    return sections


def naca_blade(  # noqa: PLR0913 (keyword options, one per `femrub mesh naca` flag)
    code: str = "0012",
    span: float = 0.1,
    root_chord: float = 0.05,
    tip_chord: float = 0.035,
    twist: float = 20.0,
    n_sections: int = 5,
    *,
    h: float | None = None,
    h_min: float | None = None,
    hub_radius: float = 0.0,
    stacking: float = 0.25,
    n_points: int = 40,
    n_contact: int = 10,
    contact_margin: float = 0.05,
    verbose: bool = False,
) -> BladeMesh:
    """Mesh a twisted, tapered NACA 4-digit blade with linear tetrahedra.

    Geometry as in :func:`naca_sections`: span along z (root face at
    ``hub_radius``), chord roughly along x, machine rotation axis x. Contact
    nodes are embedded on the exact camber line of the tip section.

    Parameters
    ----------
    code, span, root_chord, tip_chord, twist, n_sections, hub_radius, stacking, n_points
        See :func:`naca_sections`.
    h : float, optional
        Target element size in metres (default: the tip section's maximum thickness).
    h_min : float, optional
        Lower bound of the element size (default ``h / 4``).
    n_contact : int, optional
        Number of contact nodes on the tip camber line.
    contact_margin : float, optional
        Chord fraction kept free of contact nodes at each edge.
    verbose : bool, optional
        Show gmsh messages.

    Returns
    -------
    BladeMesh
        Node sets ``root``, ``tip``, ``contact``; ``info["cad_volume"]`` is the
        OpenCASCADE volume of the loft.
    """
    _, _, thick = naca4_parameters(code)
    size = MeshSize(thick * tip_chord if h is None else h, h_min)
    sections = naca_sections(
        code,
        span,
        root_chord,
        tip_chord,
        twist,
        n_sections,
        hub_radius=hub_radius,
        stacking=stacking,
        n_points=n_points,
    )
    s = chord_fractions(n_contact, contact_margin)
    upper, lower = sections[-1]
    # the k-th points of the two sides straddle the camber line symmetrically
    camber = 0.5 * (upper + lower)
    u = np.linspace(0.0, 1.0, camber.shape[1])
    x_c = 0.5 * (1.0 - np.cos(np.pi * u))
    targets = np.vstack([np.interp(s, x_c, row) for row in camber])
    source = (
        f"naca_blade(code={code!r}, span={span}, root_chord={root_chord}, tip_chord={tip_chord},"
        f" twist={twist}, n_sections={n_sections}, h={size.h})"
    )
    return loft_blade(
        sections,
        size,
        "x",
        contact_targets=targets,
        verbose=verbose,
        source=source,
        twist_deg=twist,
        code=code,
    )
