"""Probes: one component of one field at one node of the mesh, as an observation row.

A probe reads the displacement ``u``, the velocity ``v`` or the temperature rise ``θ`` of the
finite-element solution at a node of the mesh, along a direction ``d``::

    s_k = dᵀ u(x_n) = Σ_j d_j u_{n,j}        (displacement; the velocity likewise)
    s_k = θ(x_n)                             (temperature)

The nodes are the mesh's vertices and, on a tetrahedral mesh, the midpoints of its edges
(the P2 displacement nodes, at their curved positions; the mid-side nodes of a quadratic
deck). At a vertex the value is its dofs; at an edge midpoint the P2 dofs of the edge, and
for a P1 field (temperature, P1 displacement) the mean of the edge's two vertices, which is
the field's value there. A probe is one row ``O`` on the full state (:func:`probe_rows`), an
observation of the model like its other signals: a reduced model carries it projected,
``O R`` (:mod:`femrub.reduction.operators`), so reduced runs record the same quantity on
the probed rows only, never the whole field.

Directions ``d`` (:func:`direction`): the global axes ``x``, ``y``, ``z``, and about the
machine axis ``a`` at the node's position ``x_n``: ``axial`` ``a``, ``radial`` ``e_r`` (away
from the axis, the casing normal of the contacts) and ``circumferential`` ``a × e_r``
(counterclockwise about ``a``). The 1D bar has the one direction ``x`` (= ``radial``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..contact.points import _component_of
from .build import _observations

__all__ = ["FIELDS", "MeshNodes", "direction", "mesh_nodes", "node_rows", "probe_rows"]

#: the state block of each probed quantity
FIELDS = {"displacement": "u", "velocity": "v", "temperature": "theta"}


@dataclass(frozen=True)
class MeshNodes:
    """The nodes of a discretisation: its vertices, then (3D) its edges' midpoints.

    Attributes
    ----------
    points : (dim, n) positions (m).
    edges : (2, n_e) the vertices of each edge (node ``n_v + e`` is the midpoint of edge e).
    n_vertices : number of vertices.
    """

    points: np.ndarray
    edges: np.ndarray
    n_vertices: int

    def nearest(self, x) -> tuple[int, float]:
        """The node nearest to ``x`` (dim,) and its distance (m)."""
        dist, idx = cKDTree(self.points.T).query(np.asarray(x, dtype=float).reshape(1, -1))
        return int(idx[0]), float(dist[0])

    def weights(self, node: int) -> tuple[np.ndarray, np.ndarray]:
        """Vertices and weights of a P1 field's value at ``node`` (1, or ½ and ½)."""
        if node < self.n_vertices:
            return np.array([node]), np.ones(1)
        return self.edges[:, node - self.n_vertices], np.full(2, 0.5)


def mesh_nodes(disc) -> MeshNodes:
    """The :class:`MeshNodes` of ``disc`` (P2: the edges' curved midpoints)."""
    mesh, basis = disc.mesh, disc.dofs_u
    p = mesh.p
    if disc.dim == 1:
        return MeshNodes(p, np.zeros((2, 0), dtype=int), p.shape[1])
    edges = mesh.edges
    mid = 0.5 * (p[:, edges[0]] + p[:, edges[1]])
    edge_dofs = getattr(basis, "edge_dofs", None)
    if edge_dofs is not None and edge_dofs.size:
        mid = basis.doflocs[:, edge_dofs[0]]
    return MeshNodes(np.hstack([p, mid]), edges, p.shape[1])


def direction(blade, x, component: str) -> np.ndarray:
    """Unit vector (dim,) of ``component`` at the position ``x`` (module docstring)."""
    if blade.dim == 1:
        return np.ones(1)
    axes = {"x": 0, "y": 1, "z": 2}
    if component in axes:
        return np.eye(3)[axes[component]]
    axis = blade.axis
    radial = blade.radial_direction(np.asarray(x, dtype=float).reshape(3, 1))[:, 0]
    return {"axial": axis, "radial": radial, "circumferential": np.cross(axis, radial)}[component]


def _node_dofs(basis, nodes: MeshNodes, node: int):
    """Full displacement dofs (by component) and weights of the value at ``node``."""
    comp = _component_of(basis)
    if node < nodes.n_vertices:
        dofs = basis.nodal_dofs[:, node]
        weights = np.ones(1)
        by_comp = np.empty_like(dofs)
        by_comp[comp[dofs]] = dofs
        return by_comp[:, None], weights
    edge = node - nodes.n_vertices
    edge_dofs = getattr(basis, "edge_dofs", None)
    if edge_dofs is not None and edge_dofs.size:  # P2: the edge's own dofs
        dofs = edge_dofs[:, edge]
        by_comp = np.empty_like(dofs)
        by_comp[comp[dofs]] = dofs
        return by_comp[:, None], np.ones(1)
    verts, weights = nodes.weights(node)
    return np.column_stack([_node_dofs(basis, nodes, int(v))[0][:, 0] for v in verts]), weights


def node_rows(basis, nodes: MeshNodes, node: int, directions) -> sp.csr_matrix:
    """``(r, basis.N)`` rows ``d_iᵀ u(x_node)`` on every displacement dof of ``basis``, one
    per direction of ``directions`` ``(r, dim)`` (the global axes ``np.eye(dim)``: the
    node's displacement vector)."""
    d = np.atleast_2d(np.asarray(directions, dtype=float))
    dofs, weights = _node_dofs(basis, nodes, node)  # (dim, m), (m,)
    vals = (d[:, :, None] * weights[None, None, :]).reshape(d.shape[0], -1)
    rows = np.repeat(np.arange(d.shape[0]), vals.shape[1])
    cols = np.tile(dofs.ravel(), d.shape[0])
    return sp.csr_matrix((vals.ravel(), (rows, cols)), shape=(d.shape[0], basis.N))


def _displacement_row(disc, mats, nodes: MeshNodes, node: int, d: np.ndarray) -> sp.csr_matrix:
    """(1, n_u) row ``dᵀ u(x_node)`` on the free displacement dofs."""
    full = node_rows(disc.dofs_u, nodes, node, d)
    return sp.csr_matrix(full @ mats.prolongation_u())


def _temperature_row(disc, mats, nodes: MeshNodes, node: int) -> sp.csr_matrix:
    """(1, n_θ) row ``θ(x_node)`` on the free temperature dofs (P1)."""
    verts, weights = nodes.weights(node)
    dofs = disc.dofs_t.nodal_dofs[0][verts]
    full = sp.csr_matrix((weights, (np.zeros(dofs.size, dtype=int), dofs)), shape=(1, mats.n_t_all))
    return sp.csr_matrix(full @ mats.prolongation_t())


def probe_rows(model, disc, mats, nodes: MeshNodes, node: int, quantity: str, d=None):
    """The observation row (1, N) of ``quantity`` at ``node`` along ``d`` on ``model``'s state.

    Raises
    ------
    ValueError
        A temperature probe on a model without temperature dofs.
    """
    field = FIELDS[quantity]
    if field == "theta":
        if model.layout.n_t == 0:
            raise ValueError("the model has no temperature dofs")
        row = _temperature_row(disc, mats, nodes, node)
    else:
        row = _displacement_row(disc, mats, nodes, node, np.asarray(d, dtype=float))
    return _observations({"probe": (field, row)}, model.layout)["probe"]
