"""Shared last step of the gmsh blade builders: groups, contact nodes, meshing."""

from __future__ import annotations

import time

import gmsh
import numpy as np

from .blade_mesh import BladeMesh
from .contact_line import embed_points_on_surface
from .gmsh_extract import to_blade_mesh
from .gmsh_session import GmshSession
from .mesh_size import MeshSize

__all__ = ["end_surfaces", "mesh_blade_volume"]


def end_surfaces(volume: int, span_coordinate) -> tuple[int, int]:
    """Boundary surfaces of a volume with the smallest and largest span coordinate.

    Parameters
    ----------
    volume : int
        Volume tag in the synchronised model.
    span_coordinate : callable
        Maps a centre of mass ``(3,)`` to a scalar spanwise position.

    Returns
    -------
    root, tip : int
        Surface tags.
    """
    surfaces = [tag for _, tag in gmsh.model.getBoundary([(3, volume)], oriented=False)]
    values = [span_coordinate(np.array(gmsh.model.occ.getCenterOfMass(2, s))) for s in surfaces]
    return surfaces[int(np.argmin(values))], surfaces[int(np.argmax(values))]


def mesh_blade_volume(
    session: GmshSession,
    volume: int,
    root: int,
    tip: int,
    contact_targets: np.ndarray,
    size: MeshSize,
    radial_axis,
    source: str,
    **info,
) -> BladeMesh:
    """Embed contact nodes in the tip, define groups, mesh in 3D and extract.

    Parameters
    ----------
    session : GmshSession
        Active session (options are set through it).
    volume, root, tip : int
        Tags of the blade volume and of its root and tip faces (synchronised model).
    contact_targets : numpy.ndarray
        Approximate contact-node locations ``(3, n)``, projected onto the tip face.
    size : MeshSize
        Mesh-size parameters.
    radial_axis : str or array_like
        Rotation axis of the machine.
    source : str
        Description stored in the result.
    **info
        Extra metadata stored in :attr:`BladeMesh.info`.

    Returns
    -------
    BladeMesh
        Mesh in metres with node sets ``root``, ``tip`` and ``contact``.
    """
    start = time.perf_counter()
    cad_volume = gmsh.model.occ.getMass(3, volume)
    size.apply(session)
    contact = embed_points_on_surface(contact_targets, tip, size.h)
    gmsh.model.addPhysicalGroup(3, [volume], name="blade")
    gmsh.model.addPhysicalGroup(2, [root], name="root")
    gmsh.model.addPhysicalGroup(2, [tip], name="tip")
    if contact:
        gmsh.model.addPhysicalGroup(0, contact, name="contact")
    gmsh.model.mesh.generate(3)
    blade = to_blade_mesh(
        radial_axis,
        source,
        cad_volume=cad_volume,
        h=size.h,
        h_min=size.h_min,
        mesh_time_s=time.perf_counter() - start,
        **info,
    )
    blade.require("root"), blade.require("tip")
    return blade
