"""Write a :class:`BladeMesh` to gmsh ``.msh`` (format 2.2) or VTK ``.vtu`` via meshio.

Format 2.2 is written on purpose: meshio 5.3.5 crashes on the
``gmsh:bounding_entities`` cell sets of MSH 4.1 files, while both meshio and
gmsh read 2.2 files back without trouble. The rotation axis is stored in an
extra ``$FemrubAxis`` section, which gmsh keeps as a model attribute.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import meshio
import numpy as np

from .errors import GeometryError
from .tet_ops import outward_boundary_facets

if TYPE_CHECKING:
    from .blade_mesh import BladeMesh

__all__ = ["contact_point_vertices", "write_blade_mesh"]


def contact_point_vertices(blade: BladeMesh, rtol: float = 1e-9) -> np.ndarray:
    """Index of the mesh vertex at each contact point, ``-1`` where there is none.

    Parameters
    ----------
    blade : BladeMesh
        The blade mesh.
    rtol : float, optional
        Matching tolerance relative to the mesh bounding-box diagonal.

    Returns
    -------
    numpy.ndarray
        Vertex index per contact point, shape ``(n_c,)``.
    """
    from scipy.spatial import cKDTree

    p = blade.mesh.p
    if blade.contact_points.shape[1] == 0:
        return np.zeros(0, dtype=np.int64)
    tol = rtol * float(np.linalg.norm(p.max(axis=1) - p.min(axis=1)))
    dist, idx = cKDTree(p.T).query(blade.contact_points.T)
    return np.where(dist <= tol, idx, -1).astype(np.int64)


def _extended_points(blade: BladeMesh) -> tuple[np.ndarray, np.ndarray]:
    """Vertices plus off-mesh contact points; index of each contact point in them."""
    where = contact_point_vertices(blade)
    extra = np.flatnonzero(where < 0)
    where[extra] = blade.n_vertices + np.arange(extra.size)
    points = np.hstack([blade.mesh.p, blade.contact_points[:, extra]])
    return points.T, where


def _set_cells(blade: BladeMesh, facets: np.ndarray, name: str) -> tuple[str, np.ndarray]:
    """Triangles if the boundary facets cover the set exactly, else vertex cells."""
    idx = np.unique(blade.node_sets[name])
    inside = np.zeros(blade.n_vertices, dtype=bool)
    inside[idx] = True
    tri = facets[:, inside[facets].all(axis=0)]
    if tri.size and np.array_equal(np.unique(tri), idx):
        return "triangle", tri.T
    return "vertex", idx[:, None]


def write_blade_mesh(blade: BladeMesh, path: str | Path, binary: bool = False) -> Path:
    """Write mesh, node sets and contact points to ``.msh`` or ``.vtu``.

    In ``.msh`` files every node set becomes a physical group (triangles when the
    set is a union of boundary faces, points otherwise) and the contact points
    the point group ``contact`` in their order. In ``.vtu`` files node sets become
    ``set_<name>`` point-data flags and contact points vertex cells with a
    ``contact_order`` point-data array. Source point sets are not written.

    Parameters
    ----------
    blade : BladeMesh
        Mesh to write.
    path : str or pathlib.Path
        Output file, suffix ``.msh`` or ``.vtu``.
    binary : bool, optional
        Binary ``.msh`` output.

    Returns
    -------
    pathlib.Path
        The written path.

    Raises
    ------
    GeometryError
        For an unsupported suffix or an unwritable path.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".msh", ".vtu"):
        raise GeometryError(f"Cannot write {str(path)!r}: use a .msh or .vtu file name.")
    points, contact_idx = _extended_points(blade)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if suffix == ".vtu":
            _write_vtu(blade, path, points, contact_idx)
        else:
            _write_msh(blade, path, points, contact_idx, binary)
    except OSError as exc:
        raise GeometryError(
            f"Cannot write {str(path)!r}: {exc.strerror or exc}; choose a writable path."
        ) from exc
    return path


def _write_vtu(blade: BladeMesh, path: Path, points: np.ndarray, contact_idx: np.ndarray) -> None:
    n = points.shape[0]
    point_data = {}
    for name, idx in blade.node_sets.items():
        flag = np.zeros(n, dtype=np.uint8)
        flag[idx] = 1
        point_data[f"set_{name}"] = flag
    order = -np.ones(n, dtype=np.int32)
    order[contact_idx] = np.arange(contact_idx.size)
    point_data["contact_order"] = order
    cells = [("tetra", blade.mesh.t.T)]
    if contact_idx.size:
        cells.append(("vertex", contact_idx[:, None]))
    meshio.Mesh(points, cells, point_data=point_data).write(path, file_format="vtu")


def _write_msh(
    blade: BladeMesh, path: Path, points: np.ndarray, contact_idx: np.ndarray, binary: bool
) -> None:
    facets, _ = outward_boundary_facets(blade.mesh.p, blade.mesh.t)
    groups: list[tuple[str, str, np.ndarray]] = [("blade", "tetra", blade.mesh.t.T)]
    for name in blade.node_sets:
        if name not in ("blade", "contact") and blade.node_sets[name].size:
            groups.append((name, *_set_cells(blade, facets, name)))
    if contact_idx.size:
        groups.append(("contact", "vertex", contact_idx[:, None]))
    dims = {"tetra": 3, "triangle": 2, "vertex": 0}
    cells, physical, field_data = [], [], {}
    for tag, (name, kind, conn) in enumerate(groups, start=1):
        cells.append((kind, np.asarray(conn, dtype=np.int64)))
        physical.append(np.full(len(conn), tag, dtype=np.int32))
        field_data[name] = np.array([tag, dims[kind]])
    cell_data = {"gmsh:physical": physical, "gmsh:geometrical": [a.copy() for a in physical]}
    mesh = meshio.Mesh(points, cells, cell_data=cell_data, field_data=field_data)
    mesh.write(path, file_format="gmsh22", binary=binary)
    with open(path, "a", encoding="ascii") as fh:
        fh.write("$FemrubAxis\n{:.17g} {:.17g} {:.17g}\n$EndFemrubAxis\n".format(*blade.axis))
