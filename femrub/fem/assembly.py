"""Assembly of the coupled thermoelastic matrices of the paper's Eq. (2), for any mesh.

:func:`assemble_thermoelastic` takes a displacement basis (vector element) and a temperature
basis (scalar element) on the same mesh and returns :class:`ThermoelasticMatrices`::

    M ü + C^uu u̇ + K^uu u + K^uθ θ = f^u + f_contact          (2a)
    C^θθ θ̇ + C^θu u̇ + K^θθ θ     = f^θ + f_tip                (2b)

with Dirichlet dofs (clamped root, root held at ambient temperature) removed. The 1D bar of
the paper and a 3D blade go through this same function; only the bases differ.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementVector

from .. import progress
from . import forms
from .elasticity import isotropic_stiffness
from .lumping import hrz_of, lump
from .material import Material, check_finite_positive
from .monotone import conduction_operator

__all__ = ["ThermoelasticMatrices", "assemble_thermoelastic", "COUPLINGS"]

COUPLINGS = ("none", "physical", "paper")


@dataclass
class ThermoelasticMatrices:
    """Matrices of Eq. (2) on the free dofs, plus what is needed to map back to the mesh.

    ``free_u`` / ``free_t`` index the free dofs in the bases' full numbering; ``n_u_all`` /
    ``n_t_all`` are the full sizes. ``Kut`` is ``K^uθ`` (n_u × n_θ), ``Ctu`` is ``C^θu``
    (n_θ × n_u).

    Attributes
    ----------
    M, C, K : scipy.sparse.csr_matrix
        Mass (kg), damping (N s/m) and stiffness (N/m) of the displacement dofs.
    Kut : scipy.sparse.csr_matrix
        Thermal stresses' coupling ``K^uθ`` (N/K).
    Ctu : scipy.sparse.csr_matrix
        Thermoelastic heating ``C^θu`` (J/m, acting on the velocity).
    Ctt, Ktt : scipy.sparse.csr_matrix
        Heat capacity ``C^θθ`` (J/K) and conductivity ``K^θθ`` (W/K).
    free_u, free_t : ndarray of int
        Free dofs in the bases' numbering (Dirichlet dofs removed).
    n_u_all, n_t_all : int
        Sizes before the Dirichlet dofs are removed.
    info : dict
        What the assembly reports (sizes, timings).
    """

    M: sp.csr_matrix
    C: sp.csr_matrix
    K: sp.csr_matrix
    Kut: sp.csr_matrix
    Ctu: sp.csr_matrix
    Ctt: sp.csr_matrix
    Ktt: sp.csr_matrix
    free_u: np.ndarray
    free_t: np.ndarray
    n_u_all: int
    n_t_all: int
    info: dict = field(default_factory=dict)

    @property
    def n_u(self) -> int:
        return self.M.shape[0]

    @property
    def n_t(self) -> int:
        return self.Ctt.shape[0]

    def u_index(self, full_dofs) -> np.ndarray:
        """Positions in the free numbering of displacement dofs given in full numbering."""
        return _positions(self.free_u, self.n_u_all, full_dofs, "displacement")

    def t_index(self, full_dofs) -> np.ndarray:
        """Positions in the free numbering of temperature dofs given in full numbering."""
        return _positions(self.free_t, self.n_t_all, full_dofs, "temperature")

    def mechanical(self) -> ThermoelasticMatrices:
        """The same blocks without the thermal part (``n_θ = 0``)."""
        z = sp.csr_matrix
        return replace(
            self,
            Kut=z((self.n_u, 0)),
            Ctu=z((0, self.n_u)),
            Ctt=z((0, 0)),
            Ktt=z((0, 0)),
            free_t=np.zeros(0, dtype=int),
        )

    def prolongation_u(self) -> sp.csr_matrix:
        """Sparse map from free displacement dofs to all dofs (zeros on Dirichlet dofs)."""
        return _prolongation(self.free_u, self.n_u_all)

    def prolongation_t(self) -> sp.csr_matrix:
        """Sparse map from free temperature dofs to all dofs."""
        return _prolongation(self.free_t, self.n_t_all)


def _positions(free: np.ndarray, n_all: int, full_dofs, what: str) -> np.ndarray:
    lookup = np.full(n_all, -1)
    lookup[free] = np.arange(free.size)
    pos = lookup[np.atleast_1d(np.asarray(full_dofs, dtype=int))]
    if np.any(pos < 0):
        raise ValueError(f"a {what} dof asked for is fixed by a Dirichlet condition")
    return pos


def _prolongation(free: np.ndarray, n_all: int) -> sp.csr_matrix:
    ones = np.ones(free.size)
    return sp.csr_matrix((ones, (free, np.arange(free.size))), shape=(n_all, free.size))


def _stiffness_bases(basis_u: Basis, basis_t: Basis) -> tuple[Basis, Basis]:
    """Bases with the lowest quadrature exact for ``∫ ε(u):ε(v)`` and ``∫ θ div v``."""
    p_u = int(getattr(basis_u.elem, "maxdeg", 1))
    p_t = int(getattr(basis_t.elem, "maxdeg", 1))
    order = max(2 * (p_u - 1), p_t + p_u - 1, 1)
    bu = Basis(basis_u.mesh, basis_u.elem, mapping=basis_u.mapping, intorder=order)
    return bu, bu.with_element(basis_t.elem)


def _lumped_mass(basis_u: Basis, rho: float, area: float, lumping: str, n_comp: int):
    """The mass lumped by ``lumping``; row-sum and HRZ lumping need only the consistent
    matrix's row sums and diagonal (two vectors: :func:`~.forms.mass_row_sums`,
    :func:`~.forms.mass_diagonal`), so it is assembled only when kept consistent."""
    if lumping not in ("row-sum", "hrz"):
        return lump(forms.mass.assemble(basis_u, rho=rho, area=area), lumping, n_comp)
    rows = forms.mass_row_sums.assemble(basis_u, rho=rho, area=area)
    if lumping == "row-sum":
        return sp.diags(rows).tocsr()
    return hrz_of(forms.mass_diagonal.assemble(basis_u, rho=rho, area=area), rows, n_comp)


def _free(n: int, fixed) -> np.ndarray:
    mask = np.ones(n, dtype=bool)
    if fixed is not None:
        mask[np.asarray(fixed, dtype=int)] = False
    return np.flatnonzero(mask)


def assemble_thermoelastic(  # noqa: PLR0913 (keyword-only options, one per scene key)
    basis_u: Basis,
    basis_t: Basis,
    material: Material,
    *,
    area: float = 1.0,
    lumping: str = "row-sum",
    heat_lumping: str | None = None,
    conduction: str = "galerkin",
    coupling: str = "physical",
    beta: float | None = None,
    strain_heating: bool = False,
    rayleigh: tuple[float, float] = (0.0, 0.0),
    fixed_u=None,
    fixed_t=None,
) -> ThermoelasticMatrices:
    """Assemble M, C^uu, K^uu, K^uθ, C^θu, C^θθ, K^θθ (paper Eq. 2) and apply Dirichlet dofs.

    Parameters
    ----------
    basis_u, basis_t
        Displacement basis (``ElementVector`` of a Lagrange element) and temperature basis
        (scalar Lagrange element) on the same mesh.
    material
        :class:`~femrub.fem.material.Material`.
    area
        Cross-section (m²) for a 1D bar; 1 for 2D/3D solids.
    lumping
        Mass lumping: ``"consistent"``, ``"row-sum"`` (P1) or ``"hrz"`` (P2, required to keep
        masses positive); ``heat_lumping`` defaults to ``lumping`` (scalar field).
    conduction
        ``"galerkin"`` (the P1 matrix ``K^θθ = ∫ k ∇θ·∇w``) or ``"monotone"`` (the same made
        an M-matrix by discrete upwinding, :mod:`femrub.fem.monotone`: no temperature below
        ambient without a sink on meshes with obtuse tetrahedra).
    coupling
        ``"none"`` (K^uθ = 0), ``"physical"`` (K^uθ = −∫ b θ div v, b = (dλ + 2μ) α_th) or
        ``"paper"`` (K^uθ = β K^uu, the paper's Sec. 4.1 model, which needs u and θ on the
        same scalar dofs).
    beta
        Paper coupling coefficient β (m/K); required with ``coupling="paper"``.
    strain_heating
        Include C^θu = −T0 (K^uθ)^T (thermoelastic heating); the paper omits it.
    rayleigh
        ``(a, b)`` Rayleigh damping ``C^uu = a M + b K^uu``.
    fixed_u, fixed_t
        Dirichlet dofs (full numbering of each basis), held at zero.
    """
    if coupling not in COUPLINGS:
        raise ValueError(f"unknown coupling {coupling!r}; use one of {', '.join(COUPLINGS)}")
    area = check_finite_positive("area", area)
    dim = basis_u.mesh.dim()
    lam, mu = forms.lame_parameters(material.young, material.poisson, dim)
    n_comp = basis_u.elem.dim if hasattr(basis_u.elem, "dim") else 1

    with progress.phase(f"mass matrix ({basis_u.N} dofs)", start=False):
        M = _lumped_mass(basis_u, material.rho, area, lumping, n_comp)
    # stiffness and coupling integrate gradients: the lowest exact quadrature is enough
    # (order 2 for P2 on straight elements), several times cheaper than the mass's
    with progress.phase(f"stiffness matrix ({basis_u.N} dofs)", start=False):
        bu_k, bt_k = _stiffness_bases(basis_u, basis_t)
        if isinstance(bu_k.elem, ElementVector):  # batched element products
            K = isotropic_stiffness(bu_k, lam, mu, area)
        else:
            K = forms.stiffness.assemble(bu_k, lam=lam, mu=mu, area=area)
    with progress.phase(f"heat matrices ({basis_t.N} dofs)", start=False):
        Ctt = forms.heat_capacity.assemble(basis_t, rho_c=material.rho_c, area=area)
        Ctt = lump(Ctt, heat_lumping or lumping, 1)
        Ktt = forms.conductivity.assemble(basis_t, k=material.conductivity, area=area)
        Ktt = conduction_operator(Ktt, conduction)

    b = (dim * lam + 2.0 * mu) * material.expansion
    if coupling == "physical":
        Kut = forms.thermal_stress.assemble(bt_k, bu_k, b=b, area=area)
    elif coupling == "paper":
        if beta is None or not np.isfinite(beta):
            raise ValueError("coupling='paper' needs a finite beta (m/K), e.g. beta=-4.5e-7")
        if K.shape[0] != Ktt.shape[0]:
            raise ValueError("coupling='paper' needs u and θ on the same dofs; use 'physical'")
        Kut = beta * K
    else:
        Kut = sp.csr_matrix((basis_u.N, basis_t.N))
    if strain_heating:
        if coupling == "paper":
            Ctu = -material.reference_temperature * Kut.T
        else:
            Ctu = forms.strain_heating.assemble(
                bu_k, bt_k, T0=material.reference_temperature, b=b, area=area
            )
    else:
        Ctu = sp.csr_matrix((basis_t.N, basis_u.N))
    a_r, b_r = (float(x) for x in rayleigh)
    # no damping: an empty C, not a copy of K's pattern holding zeros (the modal damping of
    # the pipeline sets C later, these undamped blocks stay alive beside the model)
    C = a_r * M + b_r * K if a_r or b_r else sp.csr_matrix(M.shape)

    fu, ft = _free(basis_u.N, fixed_u), _free(basis_t.N, fixed_t)

    def sub(A, rows, cols):
        return sp.csr_matrix(A)[rows][:, cols].tocsr()

    return ThermoelasticMatrices(
        M=sub(M, fu, fu),
        C=sub(sp.csr_matrix(C), fu, fu),
        K=sub(K, fu, fu),
        Kut=sub(Kut, fu, ft),
        Ctu=sub(Ctu, ft, fu),
        Ctt=sub(Ctt, ft, ft),
        Ktt=sub(Ktt, ft, ft),
        free_u=fu,
        free_t=ft,
        n_u_all=basis_u.N,
        n_t_all=basis_t.N,
        info={
            "dim": dim,
            "lumping": lumping,
            "coupling": coupling,
            "area": area,
            "beta": beta,
            "conduction": conduction,
        },
    )
