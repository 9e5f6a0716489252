"""The paper's blade as a geometry: a radial line of linear elements (``skfem.MeshLine``).

The bar runs along ``x`` from the root (``x = 0``, node set ``root``) to the tip
(``x = L``, node sets ``tip`` and ``contact``); its radial direction is ``+x``. Nodes sit at
``x = L (1 − (1 − ξ)^p)`` with ``ξ`` uniform and ``p = grading`` (1: uniform; > 1: elements
refined towards the tip).
"""

from __future__ import annotations

import numpy as np
import skfem

from .blade_mesh import BladeMesh
from .errors import GeometryError

__all__ = ["bar_mesh"]


def bar_mesh(length: float, n_elements: int, grading: float = 1.0) -> BladeMesh:
    """A :class:`BladeMesh` of ``n_elements`` linear elements over ``[0, length]`` (m)."""
    if not (np.isfinite(length) and length > 0):
        raise GeometryError(f"bar length must be finite and > 0 (m), got {length!r}")
    if not (isinstance(n_elements, int | np.integer) and n_elements >= 1):
        raise GeometryError(f"n_elements must be a positive integer, got {n_elements!r}")
    xi = np.linspace(0.0, 1.0, int(n_elements) + 1)
    mesh = skfem.MeshLine(length * (1.0 - (1.0 - xi) ** grading))
    x = mesh.p[0]
    root, tip = int(np.argmin(x)), int(np.argmax(x))
    return BladeMesh(
        mesh=mesh,
        node_sets={"root": np.array([root]), "tip": np.array([tip]), "contact": np.array([tip])},
        contact_points=mesh.p[:, [tip]],
        radial_axis="z",
        source=f"bar, L = {length:g} m, {n_elements} elements"
        + (f", grading {grading:g}" if grading != 1.0 else ""),
    )
