"""Find the blade tip face of a mesh from the rotation axis (outward radial facets)."""

from __future__ import annotations

import numpy as np

from .axes import radial_coordinates
from .errors import GeometryError
from .tet_ops import outward_boundary_facets

__all__ = ["detect_tip"]


def detect_tip(
    p: np.ndarray, t: np.ndarray, axis, min_cos: float = 0.7, span_fraction: float = 0.8
) -> np.ndarray:
    """Vertices of the boundary facets that face the casing.

    A boundary facet belongs to the tip when its outward normal makes an angle
    of less than ``arccos(min_cos)`` with the local radial direction and its
    centroid lies in the outer ``1 - span_fraction`` of the radial extent.

    Parameters
    ----------
    p : numpy.ndarray
        Vertex coordinates, shape ``(3, n_vertices)``.
    t : numpy.ndarray
        Tetrahedra, shape ``(4, n_tets)``.
    axis : str or array_like
        Machine rotation axis.
    min_cos : float, optional
        Minimum cosine between facet normal and radial direction.
    span_fraction : float, optional
        Facets must lie above ``r_min + span_fraction * (r_max - r_min)``.

    Returns
    -------
    numpy.ndarray
        Sorted vertex indices of the tip face.

    Raises
    ------
    GeometryError
        If no facet qualifies.
    """
    facets, normals = outward_boundary_facets(p, t)
    centroids = p[:, facets].mean(axis=1)
    radius, e_r = radial_coordinates(centroids, axis)
    r_all = radial_coordinates(p, axis)[0]
    threshold = r_all.min() + span_fraction * (r_all.max() - r_all.min())
    keep = (np.einsum("ij,ij->j", normals, e_r) >= min_cos) & (radius >= threshold)
    if not keep.any():
        raise GeometryError(
            "Could not detect a tip face facing away from the rotation axis; check radial_axis"
            " or pass tip=NSET_NAME / a physical group named 'tip'."
        )
    return np.unique(facets[:, keep])
