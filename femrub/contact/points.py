"""Contact points of a blade: where they are, their dofs, normals and heat weights.

:func:`locate_contacts` finds, for each contact point ``p_i`` of a
:class:`~femrub.fem.discretisation.Discretisation`, its displacement dofs, the casing
normal ``n_i`` (the radial direction, away from the machine axis; ``+x`` on the paper's
bar), its radius ``r_i`` and angular position ``φ_i`` around the axis, and the weights that
spread its frictional heat over its tributary part of the tip face (see
:func:`tributary_heat_weights`). On a 3D blade with a tip face the contact acts on that same
part of the tip (:mod:`femrub.contact.patches`: the weighted mean displacement, the force
spread with the heat's weights); ``spread="node"`` keeps it on the point's node.
:meth:`ContactPoints.restrict` keeps a subset (the points the casing can reach), before any
model exists.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .patches import patch_rows, tip_patch_weights

__all__ = ["ContactPoints", "locate_contacts", "tributary_heat_weights"]

#: How a contact acts on the blade: on its part of the tip face, or on its node.
SPREADS = ("patch", "node")
#: Distance (relative to the blade size) within which a point is taken to be a mesh node.
NODE_TOLERANCE = 1e-6


@dataclass(frozen=True)
class ContactPoints:
    """Contact points of a discretised blade (full dof numbering of the bases).

    Attributes
    ----------
    points : (dim, n_c) coordinates (m).
    normals : (dim, n_c) outward radial unit vectors.
    radii : (n_c,) distance to the machine axis (m).
    angles : (n_c,) angular position around the axis (rad).
    u_dofs : (dim, n_c) displacement dofs of each point (one per component).
    heat : (n_c, n_t_all) sparse weights on the temperature dofs (rows sum to 1).
    vertices : (n_c,) the mesh vertex nearest to each point (where output draws its force).
    names : labels of the points.
    tangents : (dim, 2, n_c) casing tangents at each point: the axial direction and the
        circumferential one ``axis × n`` (the direction of rotation for Ω > 0); ``None`` on
        the bar.
    patch : (dim n_c, n_u_all) rows of the patch mean displacements (row ``dim i + k``:
        component k of contact i, full dof numbering; :mod:`femrub.contact.patches`), or
        ``None``: each contact acts on its node's dofs ``u_dofs``.
    """

    points: np.ndarray
    normals: np.ndarray
    radii: np.ndarray
    angles: np.ndarray
    u_dofs: np.ndarray
    heat: sp.csr_matrix
    vertices: np.ndarray
    names: tuple[str, ...]
    tangents: np.ndarray | None = None
    patch: sp.csr_matrix | None = None

    @property
    def n(self) -> int:
        return self.points.shape[1]

    def restrict(self, keep) -> ContactPoints:
        """The points where the boolean mask (or index array) ``keep`` holds."""
        idx = np.flatnonzero(keep) if np.asarray(keep).dtype == bool else np.asarray(keep)
        return replace(
            self,
            points=self.points[:, idx],
            normals=self.normals[:, idx],
            radii=self.radii[idx],
            angles=self.angles[idx],
            u_dofs=self.u_dofs[:, idx],
            heat=self.heat[idx],
            vertices=self.vertices[idx],
            names=tuple(self.names[i] for i in idx),
            tangents=None if self.tangents is None else self.tangents[:, :, idx],
            patch=None
            if self.patch is None
            else self.patch[(self.u_dofs.shape[0] * idx[:, None] + np.arange(self.dim)).ravel()],
        )

    @property
    def dim(self) -> int:
        return self.u_dofs.shape[0]

    def _means(self, n_u_all: int) -> sp.csr_matrix:
        """(dim n_c, n_u_all) rows of the displacement each contact acts on (full numbering)."""
        if self.patch is not None:
            return self.patch
        n = self.u_dofs.size
        return sp.csr_matrix((np.ones(n), (np.arange(n), self.u_dofs.T.ravel())), (n, n_u_all))

    def mean_rows(self, mats) -> sp.csr_matrix:
        """(dim n_c, n_u) rows of the contacts' displacements (patch means) on the free dofs."""
        rows = sp.coo_matrix(self._means(mats.n_u_all))
        cols = mats.u_index(rows.col)
        return sp.csr_matrix((rows.data, (rows.row, cols)), shape=(rows.shape[0], mats.n_u))

    def _directions(self, vectors: np.ndarray) -> sp.csr_matrix:
        """(m n_c, dim n_c): row ``m i + j`` takes direction ``vectors[:, j, i]`` of contact i."""
        dim, m, nc = vectors.shape
        rows = np.repeat(np.arange(m * nc), dim)
        cols = (dim * np.arange(nc)[:, None, None] + np.arange(dim)).repeat(m, axis=1).ravel()
        vals = np.transpose(vectors, (2, 1, 0)).ravel()
        return sp.csr_matrix((vals, (rows, cols)), shape=(m * nc, dim * nc))

    def normal_rows(self, mats) -> sp.csr_matrix:
        """(n_c, n_u) rows giving the normal displacement ``n_i · ū_i`` on the free dofs."""
        return sp.csr_matrix(self._directions(self.normals[:, None, :]) @ self.mean_rows(mats))

    def tangent_rows(self, mats) -> sp.csr_matrix:
        """(2 n_c, n_u) rows ``t_ij · ū_i`` (row ``2 i + j``) on the free dofs."""
        return sp.csr_matrix(self._directions(self.tangents) @ self.mean_rows(mats))

    def normal_displacement(self, u: np.ndarray) -> np.ndarray:
        """``n_i · ū_i`` (..., n_c) of displacement fields ``u`` (..., n_u_all) (full numbering)."""
        u = np.asarray(u, dtype=float)
        N = self._directions(self.normals[:, None, :]) @ self._means(u.shape[-1])
        return (N @ u.reshape(-1, u.shape[-1]).T).T.reshape(u.shape[:-1] + (self.n,))

    def frames(self) -> np.ndarray:
        """(n_c, 3, dim): unit normal, axial and circumferential tangents of each point."""
        return np.concatenate(
            [self.normals.T[:, None, :], np.transpose(self.tangents, (2, 1, 0))], 1
        )

    def heat_rows(self, mats) -> sp.csr_matrix:
        """(n_c, n_θ) heat weights on the free temperature dofs."""
        return sp.csr_matrix(self.heat[:, mats.free_t])


def _component_of(basis) -> np.ndarray:
    """Component of every dof of a vector Lagrange basis (rows interleave components)."""
    comp = np.full(basis.N, -1)
    dim = basis.mesh.p.shape[0]
    for name in ("nodal_dofs", "edge_dofs", "facet_dofs", "interior_dofs"):
        d = getattr(basis, name, None)
        if d is not None and d.size:
            comp[d] = (np.arange(d.shape[0]) % dim)[:, None]
    return comp


def _axis_frame(axis):
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    e1 = np.eye(3)[np.argmin(np.abs(a))]
    e1 = e1 - (e1 @ a) * a
    e1 /= np.linalg.norm(e1)
    return a, e1, np.cross(a, e1)


def locate_contacts(disc, points=None, spread: str = "patch") -> ContactPoints:
    """Dofs, normals, radii, angles and heat weights of the contact points of ``disc``.

    ``points`` defaults to ``disc.blade.contact_points``. ``spread``: ``"patch"`` makes each
    contact act on its part of the tip face where the blade has one
    (:mod:`femrub.contact.patches`), ``"node"`` on its node.
    """
    if spread not in SPREADS:
        raise ValueError(f"contact spread must be one of {SPREADS}, got {spread!r}")
    blade, basis_u = disc.blade, disc.dofs_u
    dim = blade.dim
    pts = np.asarray(blade.contact_points if points is None else points, dtype=float)
    pts = pts.reshape(dim, -1)
    if pts.shape[1] == 0:
        raise ValueError(f"blade mesh from {blade.source} has no contact points; give some")
    scale = float(np.ptp(blade.mesh.p, axis=1).max())
    tol = NODE_TOLERANCE * scale
    dist, idx = cKDTree(basis_u.doflocs.T).query(pts.T, k=dim)
    dist, idx = dist.reshape(pts.shape[1], dim), idx.reshape(pts.shape[1], dim)
    if np.any(dist > tol):
        bad = int(np.argmax(dist.max(axis=1)))
        raise ValueError(
            f"contact point {bad} at {pts[:, bad]} is not a displacement node; use P2 "
            "displacement (order=2) for mid-edge points or pick mesh nodes"
        )
    comp = _component_of(basis_u)[idx]  # (n_c, dim)
    if np.any(np.sort(comp, axis=1) != np.arange(dim)):
        raise ValueError("a contact point does not have one displacement dof per component")
    u_dofs = np.empty((dim, pts.shape[1]), dtype=int)
    u_dofs[comp.T, np.arange(pts.shape[1])] = idx.T
    vertices = cKDTree(blade.mesh.p.T).query(pts.T)[1]
    weights, on_face = tributary_heat_weights(blade, pts, tol, vertices)
    tdofs = disc.dofs_t.nodal_dofs[0]
    heat = sp.csr_matrix(
        (weights.data, tdofs[weights.indices], weights.indptr),
        shape=(pts.shape[1], disc.dofs_t.N),
    )
    radii = blade.radius(pts)
    if np.any(radii <= 0):
        raise ValueError("a contact point lies on the machine axis: no radial direction")
    normals = blade.radial_direction(pts)
    if dim == 1:
        angles = np.zeros(pts.shape[1])
    else:
        _, e1, e2 = _axis_frame(blade.axis)
        angles = np.arctan2(e2 @ pts, e1 @ pts)
    names = tuple(f"contact{i}" for i in range(pts.shape[1]))
    tangents = None
    if dim == 3:
        a = np.asarray(blade.axis, dtype=float) / np.linalg.norm(blade.axis)
        t1 = a[:, None] - (a @ normals) * normals
        t1 /= np.linalg.norm(t1, axis=0)
        tangents = np.stack([t1, np.cross(t1, normals, axis=0)], axis=1)
    patch = None
    if spread == "patch" and on_face:  # the contact acts where its heat goes
        patch = patch_rows(weights, _vertex_dofs(basis_u), basis_u.N)
    return ContactPoints(
        pts, normals, radii, angles, u_dofs, heat, vertices, names, tangents, patch
    )


def _vertex_dofs(basis) -> np.ndarray:
    """(dim, n_vertices) displacement dof of each mesh vertex and component."""
    comp = _component_of(basis)
    nodal = basis.nodal_dofs  # (dim, n_vertices), components in some order per vertex
    out = np.empty_like(nodal)
    out[comp[nodal], np.arange(nodal.shape[1])[None, :]] = nodal
    return out


def tributary_heat_weights(blade, pts, tol, vertices) -> tuple[sp.csr_matrix, bool]:
    """(n_c, n_vertices) weights spreading each contact's heat over its share of the tip.

    The frictional heat of contact ``i`` is generated over the part ``S_i`` of the tip face
    closer to ``p_i`` than to any other contact point, as a uniform flux: the weight of
    vertex ``j`` is ``∫_{S_i} N_j ds / |S_i|`` (rows sum to 1). Dumping it into one vertex
    would make the temperature depend on the mesh (a point source in 3D); without a usable
    ``tip`` face (and on the bar) the heat goes to the point's vertex ``vertices`` (or the
    two ends of its mid-edge). Returns the weights and whether they are the tip face's
    (:func:`~femrub.contact.patches.tip_patch_weights`, the patches contacts act on).
    """
    face = tip_patch_weights(blade, pts)
    if face is not None:
        return face, True
    return _node_heat_weights(blade.mesh, pts, tol, vertices), False


def _node_heat_weights(mesh, pts, tol, vertices) -> sp.csr_matrix:
    """Heat weights of points on vertices (1) or mid-edges (1/2 to each end)."""
    n_c, n_v = pts.shape[1], mesh.p.shape[1]
    vi = np.asarray(vertices)
    on_vertex = np.linalg.norm(mesh.p[:, vi] - pts, axis=0) <= tol
    rows, cols, vals = [np.flatnonzero(on_vertex)], [vi[on_vertex]], [np.ones(on_vertex.sum())]
    off = np.flatnonzero(~on_vertex)
    if off.size:
        edges = mesh.edges
        mid = 0.5 * (mesh.p[:, edges[0]] + mesh.p[:, edges[1]])
        ed, ei = cKDTree(mid.T).query(pts[:, off].T)
        if np.any(ed > tol):
            j = off[int(np.argmax(ed))]
            raise ValueError(f"contact point {j} at {pts[:, j]} is neither a vertex nor mid-edge")
        rows += [off, off]
        cols += [edges[0, ei], edges[1, ei]]
        vals += [np.full(off.size, 0.5)] * 2
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_c, n_v)
    )
