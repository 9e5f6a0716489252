"""Straight prismatic (box) blade meshed with gmsh/OpenCASCADE."""

from __future__ import annotations

import gmsh
import numpy as np

from .blade_mesh import BladeMesh
from .contact_line import chord_fractions
from .errors import check_positive
from .gmsh_blade import end_surfaces, mesh_blade_volume
from .gmsh_session import gmsh_session
from .mesh_size import MeshSize

__all__ = ["box_blade"]


def box_blade(
    span: float = 0.1,
    chord: float = 0.03,
    thickness: float = 0.003,
    *,
    h: float | None = None,
    h_min: float | None = None,
    hub_radius: float = 0.0,
    n_contact: int = 10,
    contact_margin: float = 0.05,
    verbose: bool = False,
) -> BladeMesh:
    """Mesh a straight rectangular blade with linear tetrahedra.

    The chord runs along x from 0 to ``chord``, the thickness along y from
    ``-thickness/2`` to ``thickness/2`` and the span along z from ``hub_radius``
    (root face, clamped) to ``hub_radius + span`` (tip face, contact). The
    machine rotates about x, so the casing radial direction at the tip is ~z.

    Parameters
    ----------
    span, chord, thickness : float, optional
        Dimensions in metres.
    h : float, optional
        Target element size in metres (default: ``thickness``).
    h_min : float, optional
        Lower bound of the element size (default ``h / 4``).
    hub_radius : float, optional
        Radial position of the root face in metres.
    n_contact : int, optional
        Number of contact nodes embedded along the tip centre line (y = 0).
    contact_margin : float, optional
        Chord fraction kept free of contact nodes at each edge.
    verbose : bool, optional
        Show gmsh messages.

    Returns
    -------
    BladeMesh
        Node sets ``root``, ``tip``, ``contact``; ``info["cad_volume"]`` is exact.

    Raises
    ------
    GeometryError
        For non-positive dimensions or inconsistent mesh sizes.
    """
    check_positive("Box blade", span=span, chord=chord, thickness=thickness)
    size = MeshSize(thickness if h is None else h, h_min)
    z_tip = hub_radius + span
    s = chord_fractions(n_contact, contact_margin)
    targets = np.vstack([chord * s, np.zeros_like(s), np.full_like(s, z_tip)])
    source = f"box_blade(span={span}, chord={chord}, thickness={thickness}, h={size.h})"
    with gmsh_session(verbose, "box") as session:
        vol = gmsh.model.occ.addBox(0.0, -thickness / 2, hub_radius, chord, thickness, span)
        gmsh.model.occ.synchronize()
        root, tip = end_surfaces(vol, lambda c: c[2])
        return mesh_blade_volume(session, vol, root, tip, targets, size, "x", source)
