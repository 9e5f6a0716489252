"""Read ``.vtu`` files written by :meth:`BladeMesh.save` (or other meshio formats)."""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np
import skfem

from .blade_mesh import BladeMesh
from .errors import GeometryError
from .tet_ops import compact_vertices, orient_positive
from .tip_detection import detect_tip
from .units import length_scale

__all__ = ["read_meshio"]


def read_meshio(
    path: str | Path,
    length_unit: str = "m",
    *,
    radial_axis="z",
    root: str = "root",
    tip: str | None = "tip",
) -> BladeMesh:
    """Read a tetrahedral mesh with ``set_<name>`` point-data flags via meshio.

    Contact points are the points with ``contact_order >= 0`` (in that order).
    Do not use this for gmsh MSH 4.1 files; use :func:`read_gmsh`.

    Parameters
    ----------
    path : str or pathlib.Path
        Mesh file readable by meshio (``.vtu``, ``.vtk``, ``.xdmf``...).
    length_unit : str, optional
        Unit of the coordinates.
    radial_axis : str or array_like, optional
        Rotation axis (not stored in ``.vtu`` files).
    root : str, optional
        Name of the root flag (``set_<root>``).
    tip : str or None, optional
        Name of the tip flag; ``None`` detects the tip from the axis.

    Returns
    -------
    BladeMesh
        Mesh in metres.

    Raises
    ------
    GeometryError
        Unreadable file, no tetrahedra, or missing root/tip flags.
    """
    scale = length_scale(length_unit)
    try:
        data = meshio.read(path)
    except (Exception, SystemExit) as exc:  # meshio's vtu reader calls sys.exit on bad XML
        reason = "not a valid file of its format" if isinstance(exc, SystemExit) else exc
        raise GeometryError(
            f"Cannot read mesh file {str(path)!r} with meshio: {reason}; check path and format."
        ) from None
    blocks = [c.data.T for c in data.cells if c.type in ("tetra", "tetra10")]
    if not blocks:
        raise GeometryError(
            f"No tetrahedra in {str(path)!r}; only tetrahedral meshes are read via meshio."
        )
    pts = np.asarray(data.points, dtype=float).T * scale
    p, t, old_to_new = compact_vertices(pts, np.hstack([b[:4] for b in blocks]))
    t = orient_positive(p, t)
    node_sets = {}
    for key, flag in data.point_data.items():
        if key.startswith("set_"):
            idx = old_to_new[np.flatnonzero(np.asarray(flag).reshape(-1) > 0)]
            node_sets[key[4:]] = np.unique(idx[idx >= 0])
    for wanted, role in ((root, "root"), (tip, "tip")):
        if wanted is not None and wanted in node_sets:
            node_sets[role] = node_sets[wanted]
    order = np.asarray(data.point_data.get("contact_order", -np.ones(pts.shape[1]))).reshape(-1)
    chosen = np.flatnonzero(order >= 0)
    contact = pts[:, chosen[np.argsort(order[chosen])]]
    if tip is None:
        node_sets["tip"] = detect_tip(p, t, radial_axis)
    blade = BladeMesh(
        mesh=skfem.MeshTet1(np.ascontiguousarray(p), np.ascontiguousarray(t)),
        node_sets=node_sets,
        contact_points=contact,
        radial_axis=radial_axis,
        source=f"{path} ({length_unit})",
    )
    blade.require("root")
    blade.require("tip")
    return blade
