"""Weak forms of a blade spinning at Ω about an axis through the origin (rotating frame).

Total-Lagrangian form, Saint Venant–Kirchhoff material, displacement ``u`` from the
reference position ``X``, unit rotation axis ``a`` and radial projector ``P = I − a aᵀ``::

    F = I + ∇u,   E = ½ (Fᵀ F − I),   S = λ tr(E) I + 2 μ E
    r(u; v) = ∫ F S : ∇v dX − ∫ ρ Ω² P (X + u) · v dX = 0                (static prestress)

the centrifugal body force acting on the deformed position ``X + u`` (mass is conserved, so
``ρ dX`` is the mass element whatever the deformation). Its tangent at ``u``::

    K_T(u) = ∫ (F S'[δu] + ∇δu S) : ∇v dX − Ω² ∫ ρ P δu · v dX,
    S'[δu] = λ tr(Ė) I + 2 μ Ė,   Ė = sym(Fᵀ ∇δu)

is the stiffness of small vibrations about the spinning equilibrium: material stiffness at
the deformed state, geometric (stress) stiffness ``∫ ∇δu S : ∇v`` and spin softening
``−Ω² M_P``. Coriolis (gyroscopic) terms are left out (see docs/theory.md).

With ``linear=True`` the same forms give the small-displacement model: ``F = I``,
``E = ε(u)``, so ``r`` is linear in ``u`` and ``K_T = K + K_σ(σ(u)) − Ω² M_P``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import BilinearForm, LinearForm
from skfem.helpers import ddot, dot, grad, mul, transpose

__all__ = [
    "centrifugal_force",
    "internal_force",
    "axis_params",
    "kinematics",
    "spin_mass",
    "tangent_stiffness",
]


def axis_params(axis) -> dict:
    """Form parameters ``a0, a1, a2`` of the unit rotation axis (normalised here)."""
    a = np.asarray(axis, dtype=float).reshape(3)
    a = a / np.linalg.norm(a)
    return {"a0": float(a[0]), "a1": float(a[1]), "a2": float(a[2])}


def _radial(a, x):
    """``P x = x − a (a · x)`` for a field ``x`` (3, ...); ``a`` from :func:`axis_params`."""
    a = (a["a0"], a["a1"], a["a2"])
    ax = a[0] * x[0] + a[1] * x[1] + a[2] * x[2]
    return np.array([x[i] - a[i] * ax for i in range(3)])


def kinematics(basis, u, lam: float, mu: float, linear: bool = False):
    """``F`` and ``S`` (3, 3, n_elements, n_points) at the quadrature points of ``basis``.

    ``linear``: ``F = I``, ``E = ε(u)`` (small displacements).
    """
    G = basis.interpolate(u).grad
    eye = np.zeros_like(G)
    for i in range(3):
        eye[i, i] = 1.0
    if linear:
        F, E = eye, 0.5 * (G + transpose(G))
    else:
        F, E = eye + G, 0.5 * (G + transpose(G) + mul(transpose(G), G))
    S = lam * (E[0, 0] + E[1, 1] + E[2, 2]) * eye + 2.0 * mu * E
    return F, S


def centrifugal_force(basis, u, rho_w2: float, axis):
    """``∫ ρ Ω² P (X + u) · v dX`` (vector on the dofs of ``basis``); ``rho_w2`` = ρΩ²."""
    a = axis_params(axis)

    @LinearForm
    def form(v, w):
        return rho_w2 * dot(_radial(a, w.x + w["u0"]), v)

    return form.assemble(basis, u0=u)


def internal_force(basis, u, lam: float, mu: float, linear: bool = False):
    """``∫ F S : ∇v dX`` at ``u`` (vector on the dofs of ``basis``)."""
    F, S = kinematics(basis, u, lam, mu, linear)
    FS = mul(F, S)

    @LinearForm
    def form(v, w):
        return ddot(FS, grad(v))

    return form.assemble(basis)


def tangent_stiffness(basis, u, lam: float, mu: float, linear: bool = False, chunk=1500):
    """Material + geometric stiffness at ``u`` (module docstring), without spin softening.

    Assembled element by element in vectorised form (every pair of local shape functions at
    once, ``chunk`` elements at a time): with ``H_a = sym(Fᵀ ∇φ_a)`` the element matrix is
    ``∫ λ tr(H_a) tr(H_b) + 2 μ H_a : H_b + ∇φ_a : (∇φ_b S)``. A scikit-fem form would be
    evaluated once per pair of local dofs, recomputing the products each time.
    """
    F, S = kinematics(basis, u, lam, mu, linear)
    nb = basis.Nbfun
    dofs = basis.element_dofs  # (nb, n_elements)
    data = []
    for lo in range(0, basis.nelems, chunk):
        e = slice(lo, min(lo + chunk, basis.nelems))
        G = np.stack([basis.basis[i][0].grad[:, :, e] for i in range(nb)])  # (nb,3,3,ne,nq)
        H = np.einsum("kiEq,akjEq->aijEq", F[:, :, e], G)
        H = 0.5 * (H + H.transpose(0, 2, 1, 3, 4))
        tr = H[:, 0, 0] + H[:, 1, 1] + H[:, 2, 2]
        GS = np.einsum("aikEq,kjEq->aijEq", G, S[:, :, e])
        dx = basis.dx[e]
        Ke = lam * np.einsum("aEq,bEq,Eq->Eab", tr, tr, dx, optimize=True)
        Ke += np.einsum("aijEq,bijEq,Eq->Eab", 2.0 * mu * H, H, dx, optimize=True)
        Ke += np.einsum("aijEq,bijEq,Eq->Eab", G, GS, dx, optimize=True)
        data.append(Ke)
    Ke = np.concatenate(data)  # (n_elements, nb, nb): rows a (test), columns b (trial)
    del data
    idx = dofs.T.astype(np.int32)
    rows = np.broadcast_to(idx[:, :, None], Ke.shape).ravel()
    cols = np.broadcast_to(idx[:, None, :], Ke.shape).ravel()
    return sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(basis.N, basis.N))


def spin_mass(basis, rho: float, axis):
    """``M_P = ∫ ρ P δu · v dX`` (spin softening ``−Ω² M_P``), CSR.

    With scikit-fem's vector numbering (the components of each scalar dof ``k`` at
    ``3k, 3k + 1, 3k + 2``) ``M_P = m ⊗ P``, ``m = ∫ ρ φ_a φ_b`` the scalar mass of the
    element: assembled on the scalar basis (nine times fewer element entries than the
    vector form, which other numberings use)."""
    a = axis_params(axis)
    scalar = _scalar_basis(basis)
    if scalar is not None:
        unit = np.array([a["a0"], a["a1"], a["a2"]])
        m = _scalar_mass.assemble(scalar, rho=rho)
        return sp.kron(m, np.eye(3) - np.outer(unit, unit), format="csr")

    @BilinearForm
    def form(du, v, w):
        return rho * dot(_radial(a, du), v)

    return form.assemble(basis).tocsr()


@BilinearForm
def _scalar_mass(u, v, w):
    return w.rho * u * v


def _scalar_basis(basis):
    """The scalar basis of a 3D vector ``basis`` whose dofs are numbered ``3k + i``, or
    ``None`` (another element or numbering)."""
    elem = getattr(basis.elem, "elem", None)
    if elem is None or not hasattr(basis, "with_element") or basis.elem.dim != 3:
        return None
    scalar = basis.with_element(elem)
    local = np.arange(basis.Nbfun)
    expected = 3 * scalar.element_dofs[local // 3] + (local % 3)[:, None]
    same = scalar.Nbfun * 3 == basis.Nbfun and np.array_equal(basis.element_dofs, expected)
    return scalar if same else None
