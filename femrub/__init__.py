"""femrub: finite elements for nonsmooth thermomechanical blade–casing rub.

SI units throughout (m, kg, s, K, N, W, J, Pa).
"""

from ._lazy import lazy_attributes

__version__ = "0.1.0"

# imported on first use (PEP 562): `femrub --help` and `femrub scenes` stay fast
_LAZY = {
    "PAPER": ".cases.bar",
    "BarCase": ".cases.bar",
    "bar_matrices": ".cases.bar",
    "bar_model": ".cases.bar",
    "rpm": ".scene.units",
    "ContactConfig": ".model.config",
    "RubConfig": ".model.config",
    "build_rub": ".model.builder",
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
    "Carpenter": ".analysis.steppers",
    "Penalty": ".analysis.steppers",
    "ExponentialMoreau": ".analysis.steppers",
    "ThetaMethod": ".analysis.steppers",
    "make_stepper": ".analysis.steppers",
    "RunOptions": ".analysis.options",
}

__all__ = [
    "BarCase",
    "Carpenter",
    "ExponentialMoreau",
    "Contact",
    "ContactConfig",
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
    "RubConfig",
    "RunOptions",
    "ThermoelasticMatrices",
    "ThetaMethod",
    "assemble_thermoelastic",
    "bar_matrices",
    "bar_model",
    "build_rub",
    "first_order_model",
    "make_stepper",
    "rpm",
]


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, __all__)
