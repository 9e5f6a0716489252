"""The first-order model ``A Ẋ = B X + F + H λ`` (paper Eqs. 8-9) and its one constructor."""

from .build import ContactSpec, Load, first_order_model
from .first_order import Contact, EnergyForms, FirstOrderModel, Layout, LoadTerm

__all__ = [
    "Contact",
    "ContactSpec",
    "EnergyForms",
    "FirstOrderModel",
    "Layout",
    "Load",
    "LoadTerm",
    "first_order_model",
]
