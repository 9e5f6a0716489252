"""Finite-element spaces of a blade: displacement and temperature bases, clamped root dofs.

:func:`discretise` turns a :class:`~femrub.geometry.BladeMesh` into a
:class:`Discretisation`: vector Lagrange displacement (P2 on tetrahedra by default: P1
tetrahedra lock in bending; P1 on the paper's bar) and scalar P1 temperature on the same
cells, with the ``root`` faces clamped and held at ambient temperature (Dirichlet dofs).
:func:`assemble` then assembles the paper's Eq. (2) blocks on it
(:func:`~femrub.fem.assembly.assemble_thermoelastic`) with the mass lumping the element
needs: row-sum for linear elements, HRZ for quadratic ones (row-sum lumping of P2 goes
negative); the P1 heat capacity is row-sum lumped beside an HRZ mass.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import skfem as fem

from .assembly import ThermoelasticMatrices, assemble_thermoelastic
from .damping import rayleigh_coefficients
from .eigen import angular_frequencies
from .material import Material

__all__ = ["Discretisation", "Spaces", "assemble", "discretise"]

_ELEMENTS = {
    (1, 1): fem.ElementLineP1,
    (3, 1): fem.ElementTetP1,
    (3, 2): fem.ElementTetP2,
}


class Spaces:
    """The finite-element spaces of a mesh, each built when first asked for.

    ``basis_u`` (vector displacement) and ``basis_t`` (scalar temperature, the same
    quadrature) carry the shape functions at every quadrature point of every cell, for the
    assembly (on Rotor 37's quadratic tetrahedra about 2 s); ``dofs_u`` and ``dofs_t`` are the
    same spaces on one point per cell (the centroid): their dof numbering and positions are
    the bases', built in a tenth of the time, for what a model built from stored matrices
    needs (dof numbers, contact points, probes, the strain at the centroids).
    """

    def __init__(self, mesh, element_u, element_t, mapping=None):
        self.mesh, self.element_u, self.element_t = mesh, element_u, element_t
        self.mapping = mapping

    @cached_property
    def basis_u(self) -> fem.Basis:
        return fem.Basis(self.mesh, self.element_u, mapping=self.mapping)

    @cached_property
    def basis_t(self) -> fem.Basis:
        return self.basis_u.with_element(self.element_t)  # same quadrature as basis_u

    @cached_property
    def dofs_u(self) -> fem.Basis:
        return fem.Basis(self.mesh, self.element_u, mapping=self.mapping, intorder=1)

    @cached_property
    def dofs_t(self) -> fem.Basis:
        return self.dofs_u.with_element(self.element_t)


@dataclass(frozen=True)
class Discretisation:
    """Spaces of a blade and its Dirichlet dofs (full numbering of each space).

    Attributes
    ----------
    blade : the :class:`~femrub.geometry.BladeMesh` (named node sets, contact points).
    spaces : the :class:`Spaces` (``basis_u``, ``basis_t``, ``dofs_u``, ``dofs_t``, each
        built on first use).
    fixed_u, fixed_t : clamped displacement dofs and temperature dofs held at ambient.
    order : displacement element order.
    """

    blade: object
    spaces: Spaces
    fixed_u: np.ndarray
    fixed_t: np.ndarray
    order: int

    @property
    def basis_u(self) -> fem.Basis:
        """Vector displacement basis (quadrature of the assembly)."""
        return self.spaces.basis_u

    @property
    def basis_t(self) -> fem.Basis:
        """Scalar temperature basis (``basis_u``'s quadrature)."""
        return self.spaces.basis_t

    @property
    def dofs_u(self) -> fem.Basis:
        """``basis_u``'s space on one point per cell: its dofs, doflocs and numbering."""
        return self.spaces.dofs_u

    @property
    def dofs_t(self) -> fem.Basis:
        """``basis_t``'s space on one point per cell."""
        return self.spaces.dofs_t

    @property
    def mesh(self):
        return self.blade.mesh

    @property
    def dim(self) -> int:
        return self.blade.dim

    def facets_of(self, name: str) -> np.ndarray:
        """Boundary facets whose vertices all belong to node set ``name``."""
        mesh = self.mesh
        bf = mesh.boundary_facets()
        return bf[np.all(np.isin(mesh.facets[:, bf], self.blade.require(name)), axis=0)]


def curved_mapping(blade, order: int):
    """Isoparametric P2 mapping of a mesh read with quadratic geometry, else ``None``.

    Readers of quadratic elements (C3D10, C3D15, C3D20) keep, in
    ``blade.info["edge_midpoints"]``, the curved position of every tetrahedral edge's
    midpoint (in ``mesh.edges`` order); with quadratic displacement the cells are then
    curved P2 tetrahedra (``skfem.MeshTet2``), with linear displacement they stay straight.
    """
    mid = getattr(blade, "info", {}).get("edge_midpoints")
    if order != 2 or mid is None or blade.dim != 3:
        return None
    mesh = blade.mesh
    return fem.MeshTet2(np.hstack([mesh.p, mid]), mesh.t)._mapping()


def discretise(blade, order: int = 2, *, clamped: bool = True) -> Discretisation:
    """Bases of ``blade`` with displacement ``order`` (1 or 2; the bar is linear).

    Quadratic geometry read from the mesh file is kept for ``order = 2``
    (:func:`curved_mapping`).
    """
    dim = blade.dim
    if (dim, order) not in _ELEMENTS:
        allowed = sorted(o for d, o in _ELEMENTS if d == dim)
        raise ValueError(f"displacement order {order!r} on a {dim}D mesh: use one of {allowed}")
    spaces = Spaces(
        blade.mesh,
        fem.ElementVector(_ELEMENTS[dim, order]()),
        _ELEMENTS[dim, 1](),
        curved_mapping(blade, order),
    )
    empty = np.zeros(0, dtype=int)
    disc = Discretisation(blade, spaces, empty, empty, order)
    if not clamped:
        return disc
    facets = disc.facets_of("root")
    if facets.size == 0:
        raise ValueError(
            f"the 'root' node set of {blade.source} covers no boundary face; clamp a face"
        )
    fixed_u = disc.dofs_u.get_dofs(facets).all()
    fixed_t = disc.dofs_t.get_dofs(facets).all()
    return replace(disc, fixed_u=fixed_u, fixed_t=fixed_t)


def default_lumping(order: int) -> str:
    """Mass lumping an element order needs: row-sum (P1) or HRZ (P2)."""
    return "hrz" if order == 2 else "row-sum"


def assemble(
    disc: Discretisation,
    material: Material,
    *,
    area: float = 1.0,
    lumping: str = "auto",
    conduction: str = "galerkin",
    coupling: str = "physical",
    beta: float | None = None,
    strain_heating: bool = False,
    rayleigh: tuple[float, float] = (0.0, 0.0),
    damping_ratio: float | None = None,
    damping_modes: tuple[int, int] = (1, 5),
    prestress=None,
) -> ThermoelasticMatrices:
    """Eq. (2) blocks of ``disc`` (see :func:`~femrub.fem.assembly.assemble_thermoelastic`).

    ``damping_ratio`` ζ replaces ``rayleigh``: ``C = a M + b K`` with ``ζ(ω_i) = ζ(ω_j) = ζ``
    at the clamped modes ``damping_modes = (i, j)`` (1-based); ``info["rayleigh"]`` holds
    the ``(a, b)`` used. ``prestress`` (a :class:`~femrub.fem.prestress.Prestress` of
    ``disc``) replaces ``K^uu`` by its prestressed tangent (material + geometric stiffness −
    spin softening) before the damping is set, so the blade vibrates about its spinning
    equilibrium; ``info["prestress_speed"]`` holds its Ω. ``conduction``: ``"galerkin"``
    or ``"monotone"`` (:mod:`femrub.fem.monotone`).
    """
    lumping = default_lumping(disc.order) if lumping == "auto" else lumping
    mats = assemble_thermoelastic(
        disc.basis_u,
        disc.basis_t,
        material,
        area=area,
        lumping=lumping,
        heat_lumping="row-sum" if lumping == "hrz" else lumping,
        conduction=conduction,
        coupling=coupling,
        beta=beta,
        strain_heating=strain_heating,
        rayleigh=rayleigh,
        fixed_u=disc.fixed_u,
        fixed_t=disc.fixed_t,
    )
    if prestress is not None:
        if not np.array_equal(prestress.free_u, mats.free_u):
            raise ValueError("the prestress was computed on another discretisation")
        a, b = rayleigh
        C = (a * mats.M + b * prestress.K).tocsr() if a or b else mats.C  # (empty when 0)
        mats = replace(mats, K=prestress.K, C=C)
        mats.info["prestress_speed"] = prestress.omega
    if damping_ratio:
        i, j = damping_modes
        w = angular_frequencies(mats.K, mats.M, max(i, j))
        rayleigh = rayleigh_coefficients(float(damping_ratio), w[i - 1], w[j - 1])
        mats = replace(mats, C=(rayleigh[0] * mats.M + rayleigh[1] * mats.K).tocsr())
    mats.info["rayleigh"] = tuple(float(x) for x in rayleigh)
    return mats
