"""Weak forms of linear thermoelasticity, written once for 1D, 2D and 3D.

Every form is a plain scikit-fem form: assemble it with ``form.assemble(basis, **params)``
(or ``asm(form, basis)``), which returns a scipy sparse matrix. Parameters are passed as
keyword arguments and read from ``w``; each form multiplies by ``w.area`` so that a 1D
bar of cross-section ``A`` uses the same code as a 3D solid (where ``area = 1``).

Constitutive law (isotropic, small strain, temperature rise ``θ`` from ``T0``)::

    σ = 2 μ ε + λ tr(ε) I − b θ I,      b = (d λ + 2 μ) α_th

with ``d`` the space dimension. For the 1D bar the uniaxial-stress law ``σ = E (ε − α_th θ)``
is the special case ``λ = 0``, ``μ = E / 2`` (see :func:`lame_parameters`).

The semi-discrete equations are the paper's Eq. (2)::

    M ü + C^uu u̇ + K^uu u + K^uθ θ = f^u + f_contact          (2a)
    C^θθ θ̇ + C^θu u̇ + K^θθ θ     = f^θ + f_tip                (2b)

Units: SI throughout (m, kg, s, K, N, W).
"""

from __future__ import annotations

import numpy as np
from skfem import BilinearForm, LinearForm
from skfem.helpers import ddot, dot, eye, grad, sym_grad, trace

__all__ = [
    "lame_parameters",
    "mass",
    "mass_diagonal",
    "mass_row_sums",
    "stiffness",
    "thermal_stress",
    "heat_capacity",
    "conductivity",
    "strain_heating",
]


def lame_parameters(young: float, poisson: float, dim: int) -> tuple[float, float]:
    """Lamé parameters ``(λ, μ)`` for the space dimension ``dim``.

    In 1D the bar is in uniaxial stress, so ``λ = 0`` and ``2 μ = E``; in 2D plane strain
    and in 3D the usual ``λ = E ν / ((1 + ν)(1 − 2ν))``, ``μ = E / (2 (1 + ν))``.
    """
    if dim == 1:
        return 0.0, 0.5 * young
    lam = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))
    mu = young / (2.0 * (1.0 + poisson))
    return lam, mu


@BilinearForm
def mass(u, v, w):
    """Mass ``M_ij = ∫ ρ A N_i · N_j dx`` (paper Eq. 2a); parameters ``rho``, ``area``."""
    return w.rho * w.area * dot(u, v)


@LinearForm
def mass_row_sums(v, w):
    """Row sums of the mass, ``Σ_j M_ij = ∫ ρ A N_i · Σ_j N_j dx``: the sum of a shape's
    components (the shapes of each component sum to one); parameters ``rho``, ``area``."""
    return w.rho * w.area * dot(v, np.ones_like(np.asarray(v)))


@LinearForm
def mass_diagonal(v, w):
    """Diagonal of the mass, ``M_ii = ∫ ρ A N_i · N_i dx`` (not a linear form in ``v``: each
    test function is integrated against itself); parameters ``rho``, ``area``."""
    return w.rho * w.area * dot(v, v)


@BilinearForm
def stiffness(u, v, w):
    """Stiffness ``K^uu = ∫ A σ(u) : ε(v) dx`` with ``σ = 2 μ ε + λ tr(ε) I`` (Eq. 2a)."""
    eps = sym_grad(u)
    sig = 2.0 * w.mu * eps + w.lam * eye(trace(eps), eps.shape[0])
    return w.area * ddot(sig, sym_grad(v))


@BilinearForm
def thermal_stress(theta, v, w):
    """Physical coupling ``K^uθ = −∫ A b θ div(v) dx``, ``b = (d λ + 2 μ) α_th`` (Eq. 2a).

    Trial space: temperature (scalar); test space: displacement (vector). With ``θ > 0`` the
    force ``−K^uθ θ`` expands the body. Parameter ``b`` (Pa/K), ``area``.
    """
    return -w.area * w.b * theta * trace(sym_grad(v))


@BilinearForm
def heat_capacity(theta, eta, w):
    """Heat capacity ``C^θθ = ∫ ρ c A θ η dx`` (Eq. 2b); parameters ``rho_c``, ``area``."""
    return w.rho_c * w.area * theta * eta


@BilinearForm
def conductivity(theta, eta, w):
    """Conductivity ``K^θθ = ∫ A k ∇θ · ∇η dx`` (Eq. 2b); parameters ``k`` (W/(m K)), ``area``."""
    return w.k * w.area * dot(grad(theta), grad(eta))


@BilinearForm
def strain_heating(u, eta, w):
    """Thermoelastic heating ``C^θu = ∫ A T0 b div(u) η dx`` = ``−T0 (K^uθ)^T`` (Eq. 2b).

    Trial space: displacement; test space: temperature. Parameters ``T0`` (K), ``b``, ``area``.
    """
    return w.area * w.T0 * w.b * trace(sym_grad(u)) * eta
