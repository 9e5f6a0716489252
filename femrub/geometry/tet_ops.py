"""Elementary operations on linear tetrahedral connectivity (numpy only)."""

from __future__ import annotations

import numpy as np

from .errors import GeometryError

__all__ = [
    "compact_vertices",
    "edge_lengths",
    "orient_positive",
    "outward_boundary_facets",
    "tet_volumes",
]


def tet_volumes(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Signed volumes of linear tetrahedra.

    Parameters
    ----------
    p : numpy.ndarray
        Vertex coordinates, shape ``(3, n_vertices)``.
    t : numpy.ndarray
        Connectivity, shape ``(4, n_tets)``.

    Returns
    -------
    numpy.ndarray
        Signed volumes, shape ``(n_tets,)``; positive when vertex 3 lies on the
        side of the face (0, 1, 2) given by the right-hand rule.
    """
    a = p[:, t[1]] - p[:, t[0]]
    b = p[:, t[2]] - p[:, t[0]]
    c = p[:, t[3]] - p[:, t[0]]
    return np.einsum("ij,ij->j", np.cross(a, b, axis=0), c) / 6.0


def orient_positive(p: np.ndarray, t: np.ndarray, rtol: float = 1e-12) -> np.ndarray:
    """Return a copy of ``t`` with every tetrahedron positively oriented.

    Parameters
    ----------
    p : numpy.ndarray
        Vertex coordinates, shape ``(3, n_vertices)``.
    t : numpy.ndarray
        Connectivity, shape ``(4, n_tets)``.
    rtol : float, optional
        Tetrahedra with ``|volume| <= rtol * max|volume|`` are degenerate.

    Returns
    -------
    numpy.ndarray
        Connectivity with vertices 2 and 3 swapped where the volume was negative.

    Raises
    ------
    GeometryError
        If a tetrahedron is degenerate (zero volume).
    """
    t = np.array(t, dtype=np.int64, copy=True)
    vol = tet_volumes(p, t)
    scale = np.max(np.abs(vol)) if vol.size else 0.0
    bad = np.flatnonzero(np.abs(vol) <= rtol * scale)
    if bad.size:
        raise GeometryError(
            f"{bad.size} degenerate (zero-volume) tetrahedra, first at index {bad[0]};"
            " check the element connectivity and coordinates of the source mesh."
        )
    neg = vol < 0
    t[2, neg], t[3, neg] = t[3, neg].copy(), t[2, neg].copy()
    return t


def compact_vertices(p: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Drop vertices not referenced by any tetrahedron and renumber.

    Parameters
    ----------
    p : numpy.ndarray
        Coordinates, shape ``(3, n_points)``.
    t : numpy.ndarray
        Connectivity into ``p``, shape ``(4, n_tets)``.

    Returns
    -------
    p_new : numpy.ndarray
        Coordinates of used vertices, shape ``(3, n_vertices)``.
    t_new : numpy.ndarray
        Renumbered connectivity.
    old_to_new : numpy.ndarray
        Map from old point index to new vertex index, ``-1`` for dropped points.
    """
    used = np.unique(t)
    old_to_new = -np.ones(p.shape[1], dtype=np.int64)
    old_to_new[used] = np.arange(used.size)
    return p[:, used], old_to_new[t], old_to_new


def outward_boundary_facets(p: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boundary triangles of a tetrahedral mesh with outward unit normals.

    Parameters
    ----------
    p : numpy.ndarray
        Coordinates, shape ``(3, n_vertices)``.
    t : numpy.ndarray
        Connectivity, shape ``(4, n_tets)``.

    Returns
    -------
    facets : numpy.ndarray
        Vertex indices of boundary triangles, shape ``(3, n_facets)``.
    normals : numpy.ndarray
        Outward unit normals, shape ``(3, n_facets)``.
    """
    local = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])
    faces = np.concatenate([t[row] for row in local], axis=1)
    opposite = np.concatenate([t[k] for k in range(4)])
    key = np.sort(faces, axis=0)
    _, inverse, counts = np.unique(key, axis=1, return_inverse=True, return_counts=True)
    boundary = counts[inverse.reshape(-1)] == 1
    facets, apex = faces[:, boundary], opposite[boundary]
    n = np.cross(p[:, facets[1]] - p[:, facets[0]], p[:, facets[2]] - p[:, facets[0]], axis=0)
    inward = np.einsum("ij,ij->j", n, p[:, apex] - p[:, facets[0]]) > 0
    n[:, inward] *= -1.0
    facets[1, inward], facets[2, inward] = facets[2, inward].copy(), facets[1, inward].copy()
    return facets, n / np.linalg.norm(n, axis=0)


def edge_lengths(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Lengths of the unique edges of a tetrahedral mesh.

    Parameters
    ----------
    p : numpy.ndarray
        Coordinates, shape ``(3, n_vertices)``.
    t : numpy.ndarray
        Connectivity, shape ``(4, n_tets)``.

    Returns
    -------
    numpy.ndarray
        Edge lengths, shape ``(n_edges,)``.
    """
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    edges = np.concatenate([np.sort(t[[i, j]], axis=0) for i, j in pairs], axis=1)
    edges = np.unique(edges, axis=1)
    return np.linalg.norm(p[:, edges[0]] - p[:, edges[1]], axis=0)
