"""femrub: finite elements for nonsmooth thermomechanical blade–casing rub.

SI units throughout (m, kg, s, K, N, W, J, Pa).
"""

from .bar import PAPER, BarCase, bar_matrices, bar_model, rpm
from .first_order import ContactSpec, Load, first_order_model
from .material import Material
from .model import Contact, EnergyForms, FirstOrderModel, Layout, LoadTerm
from .results import Results
from .steppers import Carpenter, Penalty, ThetaMethod, make_stepper
from .thermoelastic import ThermoelasticMatrices, assemble_thermoelastic

__version__ = "0.1.0"

__all__ = [
    "PAPER",
    "BarCase",
    "Carpenter",
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
