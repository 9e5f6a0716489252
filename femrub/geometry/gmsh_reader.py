"""Read gmsh ``.msh`` files (any version) through the gmsh API."""

from __future__ import annotations

import time
from pathlib import Path

import gmsh
import numpy as np
import skfem

from .blade_mesh import BladeMesh
from .errors import GeometryError
from .gmsh_extract import read_current_model
from .gmsh_session import gmsh_session
from .tip_detection import detect_tip
from .units import length_scale

__all__ = ["read_gmsh"]


def _stored_axis():
    """Rotation axis written by :meth:`BladeMesh.save` (``$FemrubAxis`` section)."""
    if "FemrubAxis" not in gmsh.model.getAttributeNames():
        return None
    values = " ".join(gmsh.model.getAttribute("FemrubAxis")).split()
    return np.array([float(v) for v in values[:3]])


def read_gmsh(
    path: str | Path,
    length_unit: str = "m",
    *,
    radial_axis=None,
    root: str = "root",
    tip: str | None = "tip",
    contact: str = "contact",
    volume_group: str = "blade",
    verbose: bool = False,
) -> BladeMesh:
    """Read a gmsh mesh with physical groups as linear tetrahedra.

    Uses :func:`gmsh.merge`, so MSH 2.2 and 4.1 (ASCII or binary) work and
    meshio's MSH 4.1 ``gmsh:bounding_entities`` problem is avoided. Quadratic
    elements keep their corners; prisms and hexahedra are split into
    tetrahedra. Every named physical group of dimension < 3 becomes a node set.

    Parameters
    ----------
    path : str or pathlib.Path
        ``.msh`` file.
    length_unit : str, optional
        Unit of the coordinates in the file.
    radial_axis : str or array_like, optional
        Rotation axis; default: the one stored by :meth:`BladeMesh.save`, else ``"z"``.
    root : str, optional
        Physical group of the clamped face.
    tip : str or None, optional
        Physical group of the tip face; ``None`` detects it from the axis.
    contact : str, optional
        Physical point group of the contact nodes (optional in the file).
    volume_group : str, optional
        Physical group of the blade volume (all volumes if absent).
    verbose : bool, optional
        Show gmsh messages.

    Returns
    -------
    BladeMesh
        Mesh in metres.

    Raises
    ------
    GeometryError
        Unreadable file, unknown unit, or missing ``root``/``tip`` group.
    """
    start = time.perf_counter()
    scale = length_scale(length_unit)
    path = Path(path)
    if not path.is_file():
        raise GeometryError(f"Cannot read gmsh file {str(path)!r}: no such file; check the path.")
    with gmsh_session(verbose, "read") as _:
        try:
            gmsh.merge(str(path))
        except Exception as exc:
            raise GeometryError(
                f"Cannot read gmsh file {str(path)!r}: {exc}; is it a valid .msh file?"
            ) from exc
        axis = radial_axis if radial_axis is not None else _stored_axis()
        p, t, node_sets, contact_pts, tags = read_current_model(volume_group)
    axis = "z" if axis is None else axis
    for wanted, role in ((root, "root"), (tip, "tip"), (contact, "contact")):
        if wanted is not None and wanted != role and wanted in node_sets:
            node_sets[role] = node_sets[wanted]
    if contact != "contact":
        contact_pts = np.zeros((3, 0)) if contact not in node_sets else p[:, node_sets[contact]]
    if tip is None:
        node_sets["tip"] = detect_tip(p, t, axis)
    blade = BladeMesh(
        mesh=skfem.MeshTet1(np.ascontiguousarray(p * scale), np.ascontiguousarray(t)),
        node_sets=node_sets,
        contact_points=contact_pts * scale,
        radial_axis=axis,
        source=f"{path} ({length_unit})",
        vertex_ids=tags,
        info={"read_time_s": time.perf_counter() - start},
    )
    blade.require("root")
    blade.require("tip")
    return blade
