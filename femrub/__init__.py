"""femrub: finite elements for nonsmooth thermomechanical blade–casing rub.

SI units throughout (m, kg, s, K, N, W, J, Pa).
"""

from importlib import import_module as _import

__version__ = "0.1.0"

# imported on first use (PEP 562): `femrub --help` and `femrub scenes` stay fast
_LAZY = {
    "PAPER": ".cases.bar",
    "BarCase": ".cases.bar",
    "bar_matrices": ".cases.bar",
    "bar_model": ".cases.bar",
    "rpm": ".cases.bar",
    "ThermoelasticMatrices": ".fem.assembly",
    "assemble_thermoelastic": ".fem.assembly",
    "Material": ".fem.material",
    "ContactSpec": ".model.build",
    "Load": ".model.build",
    "first_order_model": ".model.build",
    "Contact": ".model.first_order",
    "EnergyForms": ".model.first_order",
    "FirstOrderModel": ".model.first_order",
    "Layout": ".model.first_order",
    "LoadTerm": ".model.first_order",
    "Results": ".output.results",
    "Carpenter": ".steppers",
    "Penalty": ".steppers",
    "ExponentialMoreau": ".steppers",
    "ThetaMethod": ".steppers",
    "make_stepper": ".steppers",
}

__all__ = [
    "BarCase",
    "Carpenter",
    "ExponentialMoreau",
    "Contact",
    "ContactSpec",
    "EnergyForms",
    "FirstOrderModel",
    "Layout",
    "Load",
    "LoadTerm",
    "Material",
    "PAPER",
    "Penalty",
    "Results",
    "ThermoelasticMatrices",
    "ThetaMethod",
    "assemble_thermoelastic",
    "bar_matrices",
    "bar_model",
    "first_order_model",
    "make_stepper",
    "rpm",
]


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
