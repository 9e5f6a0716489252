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

With ``linear = 1`` the same forms give the small-displacement model: ``F = I``,
``E = ε(u)``, so ``r`` is linear in ``u`` and ``K_T = K + K_σ(σ(u)) − Ω² M_P``.
"""

from __future__ import annotations

import numpy as np
from skfem import BilinearForm, LinearForm
from skfem.helpers import ddot, dot, grad, mul, transpose

__all__ = [
    "centrifugal_force",
    "internal_force",
    "axis_params",
    "spin_mass",
    "tangent_stiffness",
]


def axis_params(axis) -> dict:
    """Form parameters ``a0, a1, a2`` of the unit rotation axis (normalised here)."""
    a = np.asarray(axis, dtype=float).reshape(3)
    a = a / np.linalg.norm(a)
    return {"a0": float(a[0]), "a1": float(a[1]), "a2": float(a[2])}


def _radial(w, x):
    """``P x = x − a (a · x)`` for a field ``x`` of shape (3, ...); axis ``(w.a0, w.a1, w.a2)``."""
    a = (w.a0, w.a1, w.a2)
    ax = a[0] * x[0] + a[1] * x[1] + a[2] * x[2]
    return np.array([x[i] - a[i] * ax for i in range(3)])


def _kinematics(w):
    """``F`` and ``S`` at the quadrature points from the displacement field ``w['u0']``."""
    G = grad(w["u0"])
    nl = 1.0 - w.linear
    eye = np.zeros_like(G)
    for i in range(3):
        eye[i, i] = 1.0
    F = eye + nl * G
    E = 0.5 * (G + transpose(G)) + 0.5 * nl * mul(transpose(G), G)
    trE = E[0, 0] + E[1, 1] + E[2, 2]
    S = w.lam * trE * eye + 2.0 * w.mu * E
    return F, S, eye


@LinearForm
def centrifugal_force(v, w):
    """``∫ ρ Ω² P (X + u0) · v dX``; parameters ``rho_w2`` = ρΩ², axis ``a0, a1, a2``, ``u0``."""
    return w.rho_w2 * dot(_radial(w, w.x + w["u0"]), v)


@LinearForm
def internal_force(v, w):
    """``∫ F S : ∇v dX`` at ``u0``; parameters ``lam``, ``mu``, ``linear`` (0 or 1), ``u0``."""
    F, S, _ = _kinematics(w)
    return ddot(mul(F, S), grad(v))


@BilinearForm
def tangent_stiffness(du, v, w):
    """Material + geometric stiffness at ``u0`` (module docstring), without spin softening."""
    F, S, eye = _kinematics(w)
    Ed = mul(transpose(F), grad(du))
    Ed = 0.5 * (Ed + transpose(Ed))
    Sd = w.lam * (Ed[0, 0] + Ed[1, 1] + Ed[2, 2]) * eye + 2.0 * w.mu * Ed
    return ddot(mul(F, Sd) + mul(grad(du), S), grad(v))


@BilinearForm
def spin_mass(du, v, w):
    """``M_P = ∫ ρ P δu · v dX`` (spin softening ``−Ω² M_P``); ``rho``, axis ``a0, a1, a2``."""
    return w.rho * dot(_radial(w, du), v)
