"""Common result type of all blade geometries and mesh readers."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import skfem

from .axes import axis_vector, radial_coordinates
from .errors import GeometryError
from .tet_ops import tet_volumes

__all__ = ["BladeMesh"]

_HINTS = {
    "root": "add a physical group named 'root' (gmsh), or pass root=NSET_NAME"
    " (Abaqus/CalculiX; default: the *BOUNDARY nodes)",
    "tip": "add a physical group named 'tip' (gmsh), pass tip=NSET_NAME,"
    " or pass tip=None to detect the tip face from the rotation axis",
    "contact": "pass contact=NSET_NAME or a list of node ids to the reader,"
    " or n_contact>0 to a geometry builder",
}


@dataclass
class BladeMesh:
    """A blade discretised by linear tetrahedra (or, for the paper's bar, a radial line of
    linear elements along ``+x``), with its named node groups.

    Attributes
    ----------
    mesh : skfem.MeshTet1
        Linear tetrahedra, coordinates in metres, every element positively oriented.
    node_sets : dict of str to numpy.ndarray
        Vertex indices of named groups; at least ``"root"`` (clamped face) and
        ``"tip"`` (contact face) for meshes built or read by this package.
    contact_points : numpy.ndarray
        Coordinates in metres of the contact nodes, shape ``(dim, n_c)``. They may be
        mid-side nodes of a quadratic source mesh and so not mesh vertices.
    radial_axis : str or numpy.ndarray
        Rotation axis of the machine (``"x"``, ``"y"``, ``"z"`` or a 3-vector); the
        casing radial direction at a point is its direction away from this axis.
    source : str
        Human-readable origin (generator parameters or file path).
    point_sets : dict of str to numpy.ndarray
        Coordinates ``(3, n)`` of source node sets including nodes that are not
        vertices (mid-side nodes of quadratic elements).
    vertex_ids : numpy.ndarray or None
        Node numbers of the mesh vertices in the source file, if any.
    info : dict
        Free-form metadata (CAD volume, timings, contact-node mapping, ...).
    """

    mesh: skfem.MeshTet1
    node_sets: dict[str, np.ndarray]
    contact_points: np.ndarray
    radial_axis: str | np.ndarray
    source: str
    point_sets: dict[str, np.ndarray] = field(default_factory=dict)
    vertex_ids: np.ndarray | None = None
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        axis_vector(self.radial_axis)
        dim = self.mesh.p.shape[0]
        self.contact_points = np.asarray(self.contact_points, dtype=float).reshape(dim, -1)
        n_vertices = self.mesh.p.shape[1]
        for name, idx in list(self.node_sets.items()):
            idx = np.asarray(idx, dtype=np.int64).reshape(-1)
            if idx.size and (idx.min() < 0 or idx.max() >= n_vertices):
                raise GeometryError(f"Node set {name!r} has indices outside 0..{n_vertices - 1}.")
            self.node_sets[name] = idx

    def require(self, name: str) -> np.ndarray:
        """Return the vertex indices of a node set, or fail with a clear message.

        Parameters
        ----------
        name : str
            Name of the node set, e.g. ``"root"`` or ``"tip"``.

        Returns
        -------
        numpy.ndarray
            Vertex indices of the set.

        Raises
        ------
        GeometryError
            If the set is missing or empty; the message lists available sets and
            how to provide the missing one.
        """
        idx = self.node_sets.get(name)
        if idx is not None and idx.size > 0:
            return idx
        available = ", ".join(sorted(self.node_sets)) or "none"
        state = "is empty" if idx is not None else "is missing"
        hint = _HINTS.get(name, f"add a node set or physical group named {name!r}")
        raise GeometryError(
            f"Node set {name!r} {state} in blade mesh from {self.source}"
            f" (available: {available}); {hint}."
        )

    @property
    def axis(self) -> np.ndarray:
        """Unit vector of the rotation axis, shape ``(3,)``."""
        return axis_vector(self.radial_axis)

    @property
    def dim(self) -> int:
        """Space dimension: 3 for a blade, 1 for the paper's bar."""
        return int(self.mesh.p.shape[0])

    @property
    def n_vertices(self) -> int:
        """Number of mesh vertices."""
        return int(self.mesh.p.shape[1])

    @property
    def n_tets(self) -> int:
        """Number of tetrahedra."""
        return int(self.mesh.t.shape[1])

    def radius(self, points: np.ndarray | None = None) -> np.ndarray:
        """Distance to the rotation axis of ``points`` (default: mesh vertices).

        A bar is radial: its ``x`` coordinate is the distance from its root."""
        pts = self.mesh.p if points is None else points
        if self.dim == 1:
            return np.asarray(pts, dtype=float).reshape(-1)
        return radial_coordinates(pts, self.axis)[0]

    def radial_direction(self, points: np.ndarray | None = None) -> np.ndarray:
        """Unit radial direction at ``points`` (default: contact points), shape ``(3, n)``."""
        pts = self.contact_points if points is None else points
        if self.dim == 1:
            return np.ones((1, np.asarray(pts).reshape(1, -1).shape[1]))
        return radial_coordinates(pts, self.axis)[1]

    def volume(self) -> float:
        """Total volume of the tetrahedra in cubic metres."""
        return float(np.sum(np.abs(tet_volumes(self.mesh.p, self.mesh.t))))

    def summary(self) -> str:
        """One-line description: sizes, sets, radius range and source."""
        if self.dim == 1:
            return f"1D {self.source}"
        r = self.radius()
        sets = ", ".join(f"{k}:{v.size}" for k, v in self.node_sets.items())
        return (
            f"{self.n_tets} tets, {self.n_vertices} vertices, volume {self.volume():.6g} m^3,"
            f" radius {r.min():.6g}..{r.max():.6g} m, {self.contact_points.shape[1]}"
            f" contact points, sets [{sets}] from {self.source}"
        )

    def save(self, path: str | Path, binary: bool = False) -> Path:
        """Write the mesh and its node sets to ``.msh`` (gmsh 2.2) or ``.vtu``.

        Parameters
        ----------
        path : str or pathlib.Path
            Output file; the suffix selects the format.
        binary : bool, optional
            Binary instead of ASCII ``.msh`` (``.vtu`` is always compressed binary).

        Returns
        -------
        pathlib.Path
            The written path.
        """
        from .mesh_writer import write_blade_mesh

        return write_blade_mesh(self, path, binary=binary)
