"""The temperature field of a cyclic structure's sector and its coupling to the displacement.

A sector's temperature ``θ`` (P1, the ``root`` held at ambient, :mod:`femrub.fem.assembly`)
obeys, sector by sector, the heat equation of Eq. (2) of the paper::

    C^θθ θ̇ + K^θθ θ + C^θu u̇ = q                                              (1)

and the displacement feels it through the thermal stresses ``−K^uθ θ``. Temperature is a
scalar: a wave of ``k`` nodal diameters repeats on the right face as the left face's value
times ``e^{i k α}`` (Eq. 1 of :mod:`femrub.model.cyclic` with ``R = 1``), so the sector's
temperature is a :class:`~femrub.model.cyclic.CyclicStructure` of one component with
``K = K^θθ`` (W/K) and ``M = C^θθ`` (J/K): its "modes" ``K^θθ φ = μ C^θθ φ`` are the
sector's thermal modes, ``μ = 1/τ`` (1/s), and the harmonic bases of
:mod:`femrub.reduction.cyclic_ritz` reduce it as they reduce the displacement.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..fem.discretisation import assemble
from .cyclic import CyclicStructure, face_dof_map

__all__ = ["ThermalSector", "expansion_rows", "heat_rows_with_content", "thermal_sector"]


@dataclass(frozen=True)
class ThermalSector:
    """A sector's temperature as a cyclic structure, and its coupling to the displacement.

    Attributes
    ----------
    structure : CyclicStructure
        The temperature's: ``K`` = ``K^θθ`` (W/K), ``M`` = ``C^θθ`` (J/K), ``free`` the free
        temperature dofs, ``left``/``right`` ``(n, 1)``.
    Kut : scipy.sparse.csr_matrix
        ``K^uθ`` (N/K) on the free displacement dofs × the free temperature dofs.
    Ctu : scipy.sparse.csr_matrix
        ``C^θu`` (J/m) on the free temperature dofs × the free displacement dofs.
    coupling : str
        The coupling ``Kut`` and ``Ctu`` were assembled with (``"physical"`` or ``"none"``).
    """

    structure: CyclicStructure
    Kut: sp.csr_matrix = field(repr=False)
    Ctu: sp.csr_matrix = field(repr=False)
    coupling: str = "physical"


def thermal_sector(structure: CyclicStructure, material, coupling: str = "physical"):
    """The temperature of ``structure``'s sector (its mesh and displacement dofs) with
    ``material``'s heat capacity ``ρc`` (J/m³/K), conductivity (W/m/K) and expansion (1/K).

    ``coupling``: ``"physical"`` (thermal stresses and thermoelastic heating at the
    material's reference temperature) or ``"none"`` (``K^uθ = C^θu = 0``).
    """
    disc = structure.disc
    mats = assemble(disc, material, coupling=coupling)
    if not np.array_equal(mats.free_u, structure.free):
        raise ValueError("the thermal assembly's displacement dofs differ from the structure's")
    free = np.asarray(mats.free_t)
    left, right = face_dof_map(disc.basis_t, structure.sector, free, n_components=1)
    temperature = CyclicStructure(
        structure.sector,
        sp.csr_matrix(mats.Ktt),
        sp.csr_matrix(mats.Ctt),
        free,
        left,
        right,
        structure.omega,
        "off",
        np.zeros(disc.basis_t.N),
        disc.basis_t,
        disc,
    )
    return ThermalSector(temperature, sp.csr_matrix(mats.Kut), sp.csr_matrix(mats.Ctu), coupling)


def expansion_rows(thermal: ThermalSector, basis):
    """``k -> (m_k, n_free_u)`` rows whose transposes are the thermal-stress loads
    ``K^uθ θ`` of the temperature shapes of nodal diameter ``k`` of ``basis`` (a
    :class:`~femrub.reduction.cyclic_ritz.CyclicBasis` of the temperature): the loads whose
    static responses a displacement basis needs so that the thermal expansion of any
    temperature of ``basis`` is exact (:func:`~femrub.reduction.cyclic_ritz.cyclic_bases`
    takes such a function as its ``load_rows``)."""
    shapes = {h.k: h.shapes for h in basis.harmonics}

    def rows(k: int) -> sp.csr_matrix:
        loads = thermal.Kut @ shapes[int(k)]  # (n_free_u, m_k), complex
        return sp.csr_matrix(np.asarray(loads).T)

    return rows


def heat_rows_with_content(thermal: ThermalSector, heat_rows):
    """``k -> rows`` of the temperature's residual shapes: the tip contacts' heat inputs
    ``heat_rows`` (``(n_c, n_free_θ)``) and, for ``k = 0``, the load ``K^θθ 1`` whose static
    response is the uniform temperature ``1`` on the free dofs.

    With ``1`` in the span of the basis ``Θ`` (``C^θθ``-orthonormal), the reduced model
    conserves heat exactly: the whole wheel's heat content ``1ᵀ C^θθ Θ η`` changes by the
    heat put in ``1ᵀ f`` less the outflow ``1ᵀ K^θθ Θ η`` (its Galerkin equation tested
    with ``Θᵀ C^θθ 1``, whose field ``Θ Θᵀ C^θθ 1`` is ``1``); without it the heat
    balance errs by ``(1 − Θ Θᵀ C^θθ 1)`` at the contacts (tens of per cent with a few
    modes).
    """
    rows = sp.csr_matrix(heat_rows)
    t = thermal.structure
    uniform = sp.csr_matrix(t.K @ np.ones(t.free.size))  # (1, n_free_θ)

    def of(k: int) -> sp.csr_matrix:
        return sp.vstack([rows, uniform]).tocsr() if int(k) == 0 else rows

    return of
