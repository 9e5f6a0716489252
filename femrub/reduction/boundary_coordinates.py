"""Boundary coordinates of a Craig–Bampton reduction that are patch means, not dofs.

When a model's contacts act on the mean displacements of tip patches, ``ū = P u``
(``model.boundary["u_rows"]``, one row per contact and component,
:mod:`femrub.contact.patches`), the reduction keeps those means as its boundary
coordinates. One dof per row, its master ``m`` (``model.boundary["u"]``), is exchanged for
the row's mean::

    u' = T⁻¹ u :   u'_m = P u,                        u'_o = u_o    (o: every other dof)
    u  = T u'  :   u_m = P_mm⁻¹ (u'_m − P_mo u'_o),   u_o = u'_o

In ``u'`` the contacts act on the dofs ``u'_m`` alone, so the reduction of Eqs. (10)–(15)
applies unchanged with ``m`` as its boundary dofs: the static shape of a boundary coordinate
(Eq. 11) is the least-energy deformation with that patch mean and the others zero (an
RBE3-like constraint mode), and the clamped modes keep every patch mean at zero. The
first-order operators of Eq. (9) become::

    A' = L̃ᵀ A T̃,   B' = L̃ᵀ B T̃,   T̃ = diag(T, T, I),   L̃ = diag(T⁻ᵀ, T, I)

(the kinematic rows ``u̇ = v`` multiplied by ``T⁻¹`` stay ``u̇' = v'``, the momentum rows by
``Tᵀ``: ``K' = Tᵀ K T``, ``M' = Tᵀ M T``, ``K^uθ' = Tᵀ K^uθ``, ``C^θu' = C^θu T``). A right
basis ``R'`` and a left basis ``R̃'`` computed in these coordinates are those of the physical
model ``R = T̃ R'`` and ``R̃ = L̃ R̃'``: ``R̃ᵀ A R = R̃'ᵀ A' R'``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

__all__ = ["BoundaryCoordinates", "boundary_coordinates", "boundary_dofs"]

#: Largest condition number of ``P_mm`` accepted (the masters carry their rows' weights).
MAX_CONDITION = 1e8


@dataclass(frozen=True)
class BoundaryCoordinates:
    """The change of coordinates ``u = T u'`` of the module docstring.

    Attributes
    ----------
    T, T_inv : (n_u, n_u) sparse ``T`` and ``T⁻¹`` (identity outside the master rows).
    """

    T: sp.csr_matrix
    T_inv: sp.csr_matrix

    def blocks(self, b):
        """The Eq. (2) blocks ``b`` (a ``ThermoelasticMatrices``) in the coordinates ``u'``."""
        T, Tt, congruent = self.T, sp.csr_matrix(self.T.T), self.congruent
        return replace(
            b,
            K=congruent(b.K),
            M=congruent(b.M),
            C=congruent(b.C),
            Kut=sp.csr_matrix(Tt @ b.Kut),
            Ctu=sp.csr_matrix(sp.csr_matrix(b.Ctu) @ T),
        )

    def congruent(self, X) -> sp.csr_matrix:
        """``Tᵀ X T`` of a u-block matrix (``K' = Tᵀ K T``)."""
        return sp.csr_matrix(sp.csr_matrix(self.T.T) @ sp.csr_matrix(X) @ self.T)

    def _diag(self, layout, u, v) -> sp.csr_matrix:
        return sp.block_diag([u, v] + ([sp.identity(layout.n_t)] if layout.n_t else []), "csr")

    def operator(self, X, layout) -> sp.csr_matrix:
        """``L̃ᵀ X T̃`` of a full first-order operator ``X`` (``A`` or ``B``) of ``layout``."""
        right = self._diag(layout, self.T, self.T)
        left_t = self._diag(layout, self.T_inv, sp.csr_matrix(self.T.T))
        return sp.csr_matrix(left_t @ sp.csr_matrix(X) @ right)

    def right(self, V: np.ndarray, layout) -> np.ndarray:
        """``T̃ V``: a right basis computed in ``u'`` (rows ``[u' | v' | θ]``), in place."""
        return _in_place(V, [(layout.u, self.T), (layout.v, self.T)])

    def left(self, V: np.ndarray, layout) -> np.ndarray:
        """``L̃ V``: a left basis computed in ``u'``, in place."""
        return _in_place(V, [(layout.u, self.T_inv.T), (layout.v, self.T)])

    def solve(self, solve_prime):
        """``f ↦ K⁻¹ f = T K'⁻¹ Tᵀ f`` from a solve ``solve_prime`` with ``K' = Tᵀ K T``."""
        return lambda f: self.T @ solve_prime(self.T.T @ f)


#: columns of a basis changed of coordinates at once (bounds the temporaries: a Rotor 37 basis
#: is 0.6 GB)
COLUMN_BLOCK = 64


def _in_place(V: np.ndarray, blocks) -> np.ndarray:
    """``V[rows] = M @ V[rows]`` for each ``(rows, M)`` of ``blocks``, in place,
    :data:`COLUMN_BLOCK` columns at a time (the same products column by column)."""
    for rows, M in blocks:
        for j in range(0, V.shape[1], COLUMN_BLOCK):
            V[rows, j : j + COLUMN_BLOCK] = M @ V[rows, j : j + COLUMN_BLOCK]
    return V


def boundary_coordinates(boundary: dict, n_u: int) -> BoundaryCoordinates | None:
    """The change of coordinates of ``boundary["u_rows"]`` and its masters ``boundary["u"]``,
    or ``None`` when the boundary is made of dofs (no rows, or rows that select them)."""
    P = boundary.get("u_rows")
    if P is None:
        return None
    P = sp.csr_matrix(P)
    m = np.asarray(boundary["u"], dtype=int)
    nb = m.size
    if P.shape != (nb, n_u):
        raise ValueError(f"boundary u_rows must be ({nb}, {n_u}), got {P.shape}")
    E = sp.csr_matrix((np.ones(nb), (np.arange(nb), m)), shape=(nb, n_u))
    if (P - E).count_nonzero() == 0:
        return None  # the rows are the masters themselves
    Pmm = P[:, m].toarray()
    cond = np.linalg.cond(Pmm)
    if not cond < MAX_CONDITION:
        raise ValueError(
            f"contact patches: the master weights are singular (condition {cond:.3g}); "
            "use contact.spread = 'node'"
        )
    keep = sp.diags(1.0 - np.asarray(E.sum(axis=0)).ravel())  # zero on the masters
    rows_m = sp.csr_matrix(np.linalg.inv(Pmm)) @ (E - P @ keep)
    T = sp.csr_matrix(keep + E.T @ rows_m)
    T_inv = sp.csr_matrix(keep + E.T @ P)
    T.eliminate_zeros()
    return BoundaryCoordinates(T, T_inv)


def boundary_dofs(boundary: dict, n_u: int, n_t: int) -> tuple[np.ndarray, np.ndarray]:
    """The boundary dofs (Eq. 10) ``boundary["u"]`` and ``["theta"]``, sorted and checked
    against the sizes of the u- and θ-blocks."""
    mb = np.unique(np.asarray(boundary.get("u", []), dtype=int))
    tb = np.unique(np.asarray(boundary.get("theta", []), dtype=int))
    out_u = mb.size and (mb.min() < 0 or mb.max() >= n_u)
    if out_u or tb.size and (tb.min() < 0 or tb.max() >= n_t):
        raise ValueError("boundary dofs out of range of the u- or θ-block")
    return mb, tb
