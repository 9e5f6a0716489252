"""Contact patches: each contact point stands for its share of the blade's tip face.

Contact ``i`` at point ``p_i`` acts over the part ``S_i`` of the tip face closer to ``p_i``
than to any other contact point. Its kinematics is the weighted mean displacement of that
patch and its force is spread over it with the same weights::

    ū_i = Σ_j w_ij u_j,      w_ij = ∫_{S_i} N_j ds / |S_i|      (Σ_j w_ij = 1)
    f_j = w_ij λ_i                                              (virtual work λ_i · δū_i)

with ``N_j`` the linear (vertex) shape functions of the tip face's triangles: an RBE3-like
distributing coupling. The frictional heat is spread with the same weights
(:func:`~femrub.contact.points.tributary_heat_weights`), so the friction power ``λ_t · ẇ``
and the heat it produces act on the same patch. A point force on one node of a 3D mesh has
no converged compliance (it grows as the mesh or the reduction resolves the node); the
patch mean converges.

:func:`tip_patch_weights` gives the ``w_ij`` on the mesh vertices; :func:`patch_rows` turns
them into rows over the displacement dofs; :func:`patch_masters` picks, per row, the dof
whose own coordinate the reduction replaces by the patch mean
(:mod:`femrub.reduction.boundary_coordinates`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

__all__ = ["patch_masters", "patch_rows", "tip_patch_weights"]


def tip_patch_weights(blade, pts) -> sp.csr_matrix | None:
    """(n_c, n_vertices) weights ``w_ij`` of the module docstring, or ``None``.

    ``None`` when the blade has no usable ``tip`` face: not 3D, no ``tip`` node set, fewer
    tip triangles than points, or a point owning no triangle.
    """
    mesh = blade.mesh
    n_c, n_v = pts.shape[1], mesh.p.shape[1]
    tip = blade.node_sets.get("tip")
    if blade.dim != 3 or tip is None or not tip.size:
        return None
    bf = mesh.boundary_facets()
    facets = bf[np.all(np.isin(mesh.facets[:, bf], tip), axis=0)]
    if facets.size < n_c:
        return None
    tri = mesh.facets[:, facets]  # (3, n_f)
    P = mesh.p[:, tri]  # (3 coords, 3 vertices, n_f)
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], axis=0), axis=0)
    owner = cKDTree(pts.T).query(P.mean(axis=1).T)[1]
    if np.unique(owner).size != n_c:
        return None
    rows = np.repeat(owner, 3)
    vals = np.repeat(area / 3.0, 3)  # ∫ N_j ds over a linear triangle = area / 3
    W = sp.csr_matrix((vals, (rows, tri.T.ravel())), shape=(n_c, n_v))
    return sp.csr_matrix(sp.diags(1.0 / np.asarray(W.sum(axis=1)).ravel()) @ W)


def patch_rows(weights: sp.csr_matrix, vertex_dofs: np.ndarray, n_dofs: int) -> sp.csr_matrix:
    """(dim n_c, n_dofs) rows of the patch means: row ``dim i + k`` is ``ū_i`` along axis k.

    ``vertex_dofs`` (dim, n_vertices): the displacement dof of each vertex and component.
    """
    W = sp.coo_matrix(weights)
    dim = vertex_dofs.shape[0]
    rows = (dim * W.row[:, None] + np.arange(dim)).ravel()
    cols = vertex_dofs[:, W.col].T.ravel()
    vals = np.repeat(W.data, dim)
    return sp.csr_matrix((vals, (rows, cols)), shape=(dim * weights.shape[0], n_dofs))


def patch_masters(rows: sp.csr_matrix) -> np.ndarray:
    """One column per row of ``rows``: its largest weight among the columns not yet taken.

    The coordinate change of :mod:`femrub.reduction.boundary_coordinates` replaces each
    master's own coordinate by its row's patch mean; it is invertible when the rows
    restricted to their masters are (each master carries the largest weight of its row).
    """
    rows = sp.csr_matrix(rows)
    taken: set[int] = set()
    out = np.empty(rows.shape[0], dtype=int)
    for r in range(rows.shape[0]):  # one per contact component: a few dozen
        cols = rows.indices[rows.indptr[r] : rows.indptr[r + 1]]
        vals = np.abs(rows.data[rows.indptr[r] : rows.indptr[r + 1]])
        for c in cols[np.argsort(-vals, kind="stable")]:
            if int(c) not in taken:
                taken.add(int(c))
                out[r] = c
                break
        else:
            raise ValueError(f"contact row {r} has no dof of its own: patches overlap fully")
    return out
