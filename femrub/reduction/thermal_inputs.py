"""Thermal basis built on the heat inputs of a model (one distribution per input).

The frictional heat of contact ``j`` enters the heat equation through one fixed spatial
distribution ``q_j`` (the heat rows of :class:`~femrub.contact.points.ContactPoints`, the
columns of ``Ht``) times a scalar magnitude per step; a heat load enters through its vector
``f_j``. With ``Q = [q_1 … q_m]`` the heat equation is::

    C θ̇ = −K θ − C^θu v + Q w(t),        y = Qᵀ θ   (contact temperatures)

and the basis of :func:`input_basis` holds, C-orthogonalised in this order,

* ``1``: the constant field on the free temperature dofs, so that the reduced heat equation
  tested with the basis contains the global heat balance ``d/dt (1ᵀ C θ) = 1ᵀ(Q w − K θ −
  C^θu v)`` exactly (a Galerkin projection on a space containing ``1``);
* ``C⁻¹ Q``: the instantaneous response to each input (``s → ∞`` of ``(sC + K)⁻¹ Q``): a
  heat pulse ``Q ΔE`` raises the contact temperatures by ``Qᵀ C⁻¹ Q ΔE`` as in the full
  model (the heat stays where it entered while diffusion has no time to act);
* ``K⁻¹ Q``: the static response to each input (``s = 0``);
* the thermal shapes a sub-basis truncates, in this order: the block Krylov sequence at
  ``s → ∞``, ``(C⁻¹K)^j C⁻¹ Q`` for ``j = 1 … KRYLOV_DEPTH`` (the short-time Taylor terms of
  ``exp(−t C⁻¹K) C⁻¹ Q``: the heat of a pulse spreading to the neighbouring nodes), then the
  lowest thermal modes ``K χ = μ C χ`` of the whole blade (contact dofs free).

With the Galerkin projection ``Tᵀ C T θ̄̇ = −Tᵀ K T θ̄ + Tᵀ Q w`` and the output ``Qᵀ T θ̄``
(input and output distributions coincide), the reduced contact-temperature transfer
function ``H(s) = Qᵀ(sC + K)⁻¹Q`` matches the full one at ``s = 0`` and at ``s → ∞`` (value
and first derivative, two-sided since the system is symmetric), the reduced conduction
operator stays symmetric positive definite (no energy created by the thermal part) and the
number of thermal boundary coordinates is ``2 m + 1``, not the number of heated dofs.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..fem.eigen import lowest_modes
from ..fem.linalg import sparse_lu

__all__ = ["input_basis", "input_distributions"]

#: Krylov blocks ``(C⁻¹K)^j C⁻¹Q`` placed before the blade's thermal modes.
KRYLOV_DEPTH = 4
#: Relative C-norm below which a shape is in the span of the previous ones (dropped).
DEFLATION = 1e-9


def input_distributions(model) -> np.ndarray:
    """(n_θ, m) heat input distributions of a full model: contact heat rows and heat loads."""
    L = model.layout
    cols = []
    if model.contact is not None:
        Ht = np.asarray(model.contact.Ht[L.t])
        cols += [Ht[:, j] for j in range(Ht.shape[1]) if np.any(Ht[:, j])]
    cols += [t.vector[L.t] for t in model.loads if np.any(t.vector[L.t])]
    return np.column_stack(cols) if cols else np.zeros((L.n_t, 0))


def _capacity_solve(C):
    C = sp.csr_matrix(C)
    d = C.diagonal()
    if C.count_nonzero() == np.count_nonzero(d):  # lumped (diagonal) heat capacity
        return lambda r: r / (d[:, None] if r.ndim == 2 else d)
    lu = sparse_lu(sp.csc_matrix(C), symmetric=True, what="heat capacity C^θθ")
    return lu.solve


def _c_orthogonalise(V, C, keep_all=False):
    """Sequential C-orthogonalisation (twice, modified Gram–Schmidt) of the columns of ``V``.

    Returns the kept columns scaled to a unit largest entry (positive) and their indices; a
    column whose C-norm falls below :data:`DEFLATION` of its own is dropped (it lies in the
    span of the previous ones) unless ``keep_all``.
    """
    out, norms2, kept = [], [], []
    for j in range(V.shape[1]):
        x = V[:, j].astype(float)
        n0 = np.sqrt(max(x @ (C @ x), 0.0))
        if n0 == 0.0:
            continue
        for _ in range(2):
            for y, yy in zip(out, norms2):
                x = x - ((y @ (C @ x)) / yy) * y
        n1 = np.sqrt(max(x @ (C @ x), 0.0))
        if n1 <= DEFLATION * n0 and not keep_all:
            continue
        k = int(np.argmax(np.abs(x)))
        x = x / x[k]
        out.append(x)
        norms2.append(float(x @ (C @ x)))
        kept.append(j)
    V = np.column_stack(out) if out else np.zeros((V.shape[0], 0))
    return V, kept


def input_basis(Ctt, Ktt, solve_K, Q, n_modes: int) -> tuple[np.ndarray, int, np.ndarray]:
    """C-orthogonal thermal basis ``[1, C⁻¹Q, K⁻¹Q, χ_1 … χ_k]`` (module docstring).

    Parameters
    ----------
    Ctt, Ktt : heat capacity and conductivity on the free temperature dofs.
    solve_K : ``r ↦ Ktt⁻¹ r`` (an existing factorisation).
    Q : (n_θ, m) input distributions (:func:`input_distributions`).
    n_modes : thermal modes wanted after the input shapes.

    Returns
    -------
    T : (n_θ, n_in + k) basis, columns scaled to a unit largest entry (K).
    n_in : number of input shapes (the thermal boundary coordinates, always kept).
    mu : (k,) eigenvalues (1/s) of the shapes kept (NaN for the Krylov shapes).
    """
    C = sp.csr_matrix(Ctt)
    nt = C.shape[0]
    shapes = [np.ones((nt, 1))]
    if Q.shape[1]:
        shapes += [_capacity_solve(C)(Q), np.asarray(solve_K(Q)).reshape(nt, -1)]
    T_in, _ = _c_orthogonalise(np.hstack(shapes), C)
    n_in = T_in.shape[1]
    k = int(min(n_modes, nt - n_in))
    if k <= 0:
        return T_in, n_in, np.zeros(0)
    solve_C, K = _capacity_solve(C), sp.csr_matrix(Ktt)
    Z, blocks = solve_C(Q), []
    for _ in range(KRYLOV_DEPTH if Q.shape[1] else 0):
        Z = solve_C(K @ Z)
        Z = Z / np.maximum(np.abs(Z).max(axis=0), 1e-300)
        blocks.append(Z)
    kry = np.hstack(blocks) if blocks else np.zeros((nt, 0))
    kry = kry[:, :k]
    mu, chi = lowest_modes(Ktt, Ctt, min(k - kry.shape[1], nt - 1), solve_K)
    T, kept = _c_orthogonalise(np.hstack([T_in, kry, chi]), C)
    T = T[:, : n_in + k]
    mu_all = np.r_[np.full(kry.shape[1], np.nan), mu]  # NaN: a Krylov shape, no eigenvalue
    idx = [j - n_in for j in kept if j >= n_in][:k]
    return T, n_in, mu_all[idx]
