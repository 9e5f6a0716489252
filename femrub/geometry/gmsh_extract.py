"""Pull nodes, tetrahedra and physical groups out of the current gmsh model.

Everything is read through the gmsh API (no MSH file round trip), so it works
both right after meshing and after :func:`gmsh.open` on any MSH version.
"""

from __future__ import annotations

import gmsh
import numpy as np
import skfem

from .blade_mesh import BladeMesh
from .cell_split import split_into_tets
from .errors import GeometryError
from .tet_ops import compact_vertices, orient_positive

__all__ = ["GmshMesh", "physical_groups", "read_current_model", "to_blade_mesh"]

# gmsh element type -> (cell kind, number of corner nodes); corners come first.
_VOLUME_TYPES = {
    4: ("tetra", 4),
    11: ("tetra", 4),
    29: ("tetra", 4),
    30: ("tetra", 4),
    5: ("hexahedron", 8),
    12: ("hexahedron", 8),
    17: ("hexahedron", 8),
    6: ("wedge", 6),
    13: ("wedge", 6),
    18: ("wedge", 6),
}


class GmshMesh:
    """Nodes and corner-node tetrahedra of the current gmsh model.

    Attributes
    ----------
    points : numpy.ndarray
        Coordinates of all gmsh nodes, shape ``(3, n_nodes)``.
    tags : numpy.ndarray
        gmsh node tag of each column of ``points``.
    tets : numpy.ndarray
        Tetrahedra as column indices into ``points``, shape ``(4, n_tets)``.
    """

    def __init__(self, volume_group: str | None = "blade") -> None:
        tags, coords, _ = gmsh.model.mesh.getNodes()
        order = np.argsort(tags)  # gmsh lists nodes per entity; keep file numbering order
        self.tags = np.asarray(tags, dtype=np.int64)[order]
        self.points = np.asarray(coords, dtype=float).reshape(-1, 3)[order].T
        self._lookup = -np.ones(int(self.tags.max(initial=0)) + 1, dtype=np.int64)
        self._lookup[self.tags] = np.arange(self.tags.size)
        self.tets = self._collect_tets(volume_group)

    def index(self, node_tags: np.ndarray) -> np.ndarray:
        """Column indices into :attr:`points` of gmsh node tags."""
        return self._lookup[np.asarray(node_tags, dtype=np.int64)]

    def _volume_entities(self, volume_group: str | None) -> list[int]:
        groups = physical_groups()
        if volume_group is not None and volume_group in groups:
            dim, tag = groups[volume_group]
            return list(gmsh.model.getEntitiesForPhysicalGroup(dim, tag))
        return [tag for _, tag in gmsh.model.getEntities(3)]

    def _collect_tets(self, volume_group: str | None) -> np.ndarray:
        blocks = []
        for entity in self._volume_entities(volume_group):
            types, _, node_tags = gmsh.model.mesh.getElements(3, entity)
            for etype, ntags in zip(types, node_tags, strict=True):
                if int(etype) not in _VOLUME_TYPES:
                    name = gmsh.model.mesh.getElementProperties(int(etype))[0]
                    raise GeometryError(
                        f"Unsupported gmsh volume element {name!r} (type {etype});"
                        " re-mesh with tetrahedra, prisms or hexahedra only."
                    )
                kind, n_corner = _VOLUME_TYPES[int(etype)]
                n_node = gmsh.model.mesh.getElementProperties(int(etype))[3]
                conn = np.asarray(ntags, dtype=np.int64).reshape(-1, n_node)[:, :n_corner].T
                blocks.append(split_into_tets(kind, self.index(conn), global_ids=conn))
        if not blocks:
            raise GeometryError(
                "The gmsh model has no volume elements; generate a 3D mesh"
                " (gmsh -3) or check the physical group of the blade volume."
            )
        return np.hstack(blocks)


def physical_groups() -> dict[str, tuple[int, int]]:
    """Map physical-group name to ``(dim, tag)``; unnamed groups get ``"<dim>:<tag>"``."""
    out = {}
    for dim, tag in gmsh.model.getPhysicalGroups():
        name = gmsh.model.getPhysicalName(dim, tag) or f"{dim}:{tag}"
        out[name] = (dim, tag)
    return out


def _group_node_tags(dim: int, tag: int) -> np.ndarray:
    """Node tags of a physical group in element order (point groups keep their order)."""
    if dim > 0:
        return np.asarray(gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)[0], dtype=np.int64)
    out = []
    for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        _, _, ntags = gmsh.model.mesh.getElements(0, entity)
        if ntags:
            out.extend(np.asarray(ntags[0], dtype=np.int64).tolist())
        else:
            out.extend(np.asarray(gmsh.model.mesh.getNodes(0, entity)[0]).tolist())
    return np.asarray(out, dtype=np.int64)


def read_current_model(volume_group: str | None = "blade"):
    """Mesh data of the current model: vertices, tets, node sets, contact points.

    Parameters
    ----------
    volume_group : str or None, optional
        Physical group of the blade volume; all volumes if missing or None.

    Returns
    -------
    p : numpy.ndarray
        Vertex coordinates (model units), shape ``(3, n_vertices)``.
    t : numpy.ndarray
        Positively oriented tetrahedra, shape ``(4, n_tets)``.
    node_sets : dict of str to numpy.ndarray
        Vertex indices of every physical group of dimension < 3.
    contact_points : numpy.ndarray
        Coordinates of the nodes of the point group ``contact``, in order.
    node_tags : numpy.ndarray
        gmsh node tag of each vertex.
    """
    gm = GmshMesh(volume_group)
    p, t, old_to_new = compact_vertices(gm.points, gm.tets)
    t = orient_positive(p, t)
    node_sets, contact = {}, np.zeros((3, 0))
    for name, (dim, tag) in physical_groups().items():
        if dim == 3:
            continue
        cols = gm.index(_group_node_tags(dim, tag))
        if name == "contact":
            contact = gm.points[:, cols]
        idx = old_to_new[cols]
        node_sets[name] = idx[idx >= 0] if name == "contact" else np.unique(idx[idx >= 0])
    return p, t, node_sets, contact, gm.tags[old_to_new >= 0]


def to_blade_mesh(radial_axis, source: str, scale: float = 1.0, **info) -> BladeMesh:
    """Build a :class:`BladeMesh` from the meshed current gmsh model.

    Parameters
    ----------
    radial_axis : str or array_like
        Rotation axis of the machine.
    source : str
        Description stored in the result.
    scale : float, optional
        Factor converting model coordinates to metres.
    **info
        Stored in :attr:`BladeMesh.info`.

    Returns
    -------
    BladeMesh
        Mesh with node sets named after the physical groups.
    """
    p, t, node_sets, contact, tags = read_current_model("blade")
    mesh = skfem.MeshTet1(np.ascontiguousarray(p * scale), np.ascontiguousarray(t))
    return BladeMesh(
        mesh=mesh,
        node_sets=node_sets,
        contact_points=contact * scale,
        radial_axis=radial_axis,
        source=source,
        vertex_ids=tags,
        info=dict(info),
    )
