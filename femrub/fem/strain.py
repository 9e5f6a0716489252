"""The strain at each element's centroid as a sparse operator on the displacement dofs.

For the von Mises stress of the VTK frames (:mod:`femrub.output.frame_fields`):
``ε_ab = (∂_b u_a + ∂_a u_b) / 2`` at each element's centroid, for the pairs ``a ≤ b``, taken
once from a vector basis on one point per cell (the centroid:
:attr:`~femrub.fem.discretisation.Discretisation.dofs_u`) so that the output holds this
operator, not the basis; a basis on more points gives the mean over them (the same on
straight cells, whose strain is linear over the cell for quadratic displacement).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["centroid_strain"]


def centroid_strain(basis) -> tuple[sp.csr_matrix, list[tuple[int, int]]]:
    """Sparse ``G`` with ``(G u)[c n_e + e] = ε_ab`` at the centroid of element ``e``.

    Parameters
    ----------
    basis : scikit-fem ``Basis`` of an ``ElementVector`` (displacement, m).

    Returns
    -------
    G : ``(n_pairs n_e, basis.N)`` (1/m × m: dimensionless strain).
    pairs : the pairs ``(a, b)``, ``a ≤ b``, of the row blocks ``c``.
    """
    dim = basis.mesh.p.shape[0]
    pairs = [(a, b) for a in range(dim) for b in range(a, dim)]
    n_e = basis.element_dofs.shape[1]
    rows, cols, vals = [], [], []
    for i, phi in enumerate(basis.basis):
        g = phi[0].grad.mean(axis=-1)  # (dim, dim, n_e): ∂_b φ_a at the centroid
        for c, (a, b) in enumerate(pairs):
            v = 0.5 * (g[a, b] + g[b, a])
            keep = v != 0.0
            if keep.any():
                rows.append(c * n_e + np.flatnonzero(keep))
                cols.append(basis.element_dofs[i, keep])
                vals.append(v[keep])
    G = sp.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(len(pairs) * n_e, basis.N),
    ).tocsr()
    return G, pairs
