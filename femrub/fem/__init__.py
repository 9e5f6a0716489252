"""Finite elements: material, weak forms, lumping, linear algebra, damping, Eq. 2 blocks."""

from importlib import import_module as _import

# imported on first use (PEP 562): `femrub --help` and `femrub scenes` stay fast
_LAZY = {
    "ThermoelasticMatrices": ".assembly",
    "assemble_thermoelastic": ".assembly",
    "Material": ".material",
}

__all__ = ["Material", "ThermoelasticMatrices", "assemble_thermoelastic"]


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
