"""Solid blade lofted through airfoil sections with gmsh/OpenCASCADE ``addThruSections``."""

from __future__ import annotations

from collections.abc import Sequence

import gmsh
import numpy as np

from .blade_mesh import BladeMesh
from .contact_line import camber_points, chord_fractions
from .errors import GeometryError
from .gmsh_blade import mesh_blade_volume
from .gmsh_session import gmsh_session
from .mesh_size import MeshSize

__all__ = ["Section", "loft_blade"]

#: A section as its two sides, each ``(3, m)`` in metres from leading to trailing edge.
Section = tuple[np.ndarray, np.ndarray]


def _check_sections(sections: Sequence[Section]) -> list[Section]:
    if len(sections) < 2:
        raise GeometryError(f"A loft needs at least 2 sections, got {len(sections)}.")
    out = []
    for k, (a, b) in enumerate(sections):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if (
            a.ndim != 2
            or b.ndim != 2
            or a.shape[0] != 3
            or b.shape[0] != 3
            or min(a.shape[1], b.shape[1]) < 3
        ):
            raise GeometryError(f"Section {k}: each side must be a (3, m>=3) array of coordinates.")
        scale = np.linalg.norm(a[:, -1] - a[:, 0])
        if (
            np.linalg.norm(a[:, 0] - b[:, 0]) > 1e-9 * scale
            or np.linalg.norm(a[:, -1] - b[:, -1]) > 1e-9 * scale
        ):
            raise GeometryError(
                f"Section {k}: both sides must start at the leading and end at the trailing edge."
            )
        out.append((a, b))
    return out


def _add_wire(side_a: np.ndarray, side_b: np.ndarray, interpolate: bool) -> int:
    occ = gmsh.model.occ
    le, te = occ.addPoint(*side_a[:, 0]), occ.addPoint(*side_a[:, -1])
    curves = []
    for side in (side_a, side_b):
        tags = [le] + [occ.addPoint(*x) for x in side[:, 1:-1].T] + [te]
        curves.append(occ.addSpline(tags) if interpolate else occ.addBSpline(tags))
    return occ.addWire(curves)


def _is_planar(side_a: np.ndarray, side_b: np.ndarray, rtol: float = 1e-9) -> bool:
    pts = np.hstack([side_a, side_b])
    s = np.linalg.svd(pts - pts.mean(axis=1, keepdims=True), compute_uv=False)
    return bool(s[-1] <= rtol * s[0])


def _cap(wire: int, planar: bool) -> int:
    occ = gmsh.model.occ
    return occ.addPlaneSurface([wire]) if planar else occ.addSurfaceFilling(wire)


def loft_blade(
    sections: Sequence[Section],
    size: MeshSize,
    radial_axis="x",
    *,
    contact_targets: np.ndarray | None = None,
    n_contact: int = 10,
    contact_margin: float = 0.05,
    interpolate: bool = True,
    ruled: bool = False,
    verbose: bool = False,
    source: str = "loft_blade",
    **info,
) -> BladeMesh:
    """Loft a solid through sections, cap its ends and mesh it with tetrahedra.

    The first section becomes the clamped ``root`` face and the last one the
    ``tip`` (contact) face. End caps are planar faces for planar sections and
    OpenCASCADE filling surfaces otherwise; the shell is sewn into a solid.

    Parameters
    ----------
    sections : sequence of (numpy.ndarray, numpy.ndarray)
        Hub-to-tip sections, each given by two sides ``(3, m)`` in metres running
        from the leading edge to the trailing edge (shared end points).
    size : MeshSize
        Mesh-size parameters.
    radial_axis : str or array_like, optional
        Rotation axis of the machine.
    contact_targets : numpy.ndarray, optional
        Contact-node locations ``(3, n)``, projected onto the tip face. Default:
        ``n_contact`` points along the camber line of the last section.
    n_contact : int, optional
        Number of contact nodes when ``contact_targets`` is not given.
    contact_margin : float, optional
        Chord fraction kept free of contact nodes at each edge.
    interpolate : bool, optional
        Interpolating splines through the points (True) or B-splines using them
        as control points (False, smoother for dense noisy data).
    ruled : bool, optional
        Ruled (piecewise linear) loft between sections instead of a smooth one.
    verbose : bool, optional
        Show gmsh messages.
    source : str, optional
        Description stored in the result.
    **info
        Extra metadata stored in :attr:`BladeMesh.info`.

    Returns
    -------
    BladeMesh
        Node sets ``root``, ``tip``, ``contact``; ``info["cad_volume"]`` is the
        OpenCASCADE volume of the lofted solid.
    """
    sections = _check_sections(sections)
    if contact_targets is None:
        fractions = chord_fractions(n_contact, contact_margin)
        contact_targets = camber_points(*sections[-1], fractions)
    occ = gmsh.model.occ
    with gmsh_session(verbose, "loft") as session:
        wires = [_add_wire(a, b, interpolate) for a, b in sections]
        lateral = [
            tag
            for dim, tag in occ.addThruSections(wires, makeSolid=False, makeRuled=ruled)
            if dim == 2
        ]
        caps = [_cap(wires[k], _is_planar(*sections[k])) for k in (0, -1)]
        centres = [np.array(occ.getCenterOfMass(2, c)) for c in caps]
        loop = occ.addSurfaceLoop(lateral + caps, sewing=True)
        volume = occ.addVolume([loop])
        occ.remove([(2, s) for s in lateral + caps], recursive=True)
        occ.synchronize()
        faces = [tag for _, tag in gmsh.model.getBoundary([(3, volume)], oriented=False)]
        faces_com = np.array([occ.getCenterOfMass(2, f) for f in faces])
        root, tip = (faces[int(np.argmin(np.linalg.norm(faces_com - c, axis=1)))] for c in centres)
        if root == tip or len(faces) < 3:
            raise GeometryError(
                "Lofting failed to produce distinct root and tip faces;"
                " check the section order and shapes."
            )
        return mesh_blade_volume(
            session,
            volume,
            root,
            tip,
            contact_targets,
            size,
            radial_axis,
            source,
            n_sections=len(sections),
            **info,
        )
