"""Finite elements: material, weak forms, lumping, linear algebra, damping, Eq. 2 blocks."""

from .._lazy import lazy_attributes

# imported on first use (PEP 562): `femrub --help` and `femrub scenes` stay fast
_LAZY = {
    "ThermoelasticMatrices": ".assembly",
    "assemble_thermoelastic": ".assembly",
    "Material": ".material",
}

__all__ = ["Material", "ThermoelasticMatrices", "assemble_thermoelastic"]


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, __all__)
