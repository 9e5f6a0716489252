"""Finite elements: material, weak forms, lumping, linear algebra, damping, Eq. 2 blocks."""

from .assembly import ThermoelasticMatrices, assemble_thermoelastic
from .material import Material

__all__ = ["Material", "ThermoelasticMatrices", "assemble_thermoelastic"]
