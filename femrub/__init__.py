"""femrub: finite elements for nonsmooth thermomechanical blade–casing rub.

SI units throughout (m, kg, s, K, N, W, J, Pa).
"""

from .cases.bar import PAPER, BarCase, bar_matrices, bar_model, rpm
from .fem.assembly import ThermoelasticMatrices, assemble_thermoelastic
from .fem.material import Material
from .model.build import ContactSpec, Load, first_order_model
from .model.first_order import Contact, EnergyForms, FirstOrderModel, Layout, LoadTerm
from .output.results import Results
from .steppers import Carpenter, ExponentialMoreau, Penalty, ThetaMethod, make_stepper

__version__ = "0.1.0"

__all__ = [
    "PAPER",
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
