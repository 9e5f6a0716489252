"""Time steppers for first-order models with unilateral contact."""

from .base import State, Stepper, check_step
from .carpenter import Carpenter
from .exponential import ExponentialMoreau
from .penalty import Penalty
from .theta import ACTIVATION_RULES, ThetaMethod

SCHEMES = {
    "theta": ThetaMethod,
    "carpenter": Carpenter,
    "penalty": Penalty,
    "exponential": ExponentialMoreau,
}


def make_stepper(scheme: str, model, h, **options) -> Stepper:
    """Stepper by name: ``"theta"`` (paper Sec. 3), ``"carpenter"``, ``"penalty"`` or
    ``"exponential"`` (exact flight between contact events)."""
    try:
        cls = SCHEMES[scheme]
    except KeyError:
        raise ValueError(f"unknown scheme {scheme!r}; use one of {', '.join(SCHEMES)}") from None
    return cls(model, h, **options)


__all__ = [
    "ACTIVATION_RULES",
    "Carpenter",
    "ExponentialMoreau",
    "Penalty",
    "SCHEMES",
    "State",
    "Stepper",
    "ThetaMethod",
    "check_step",
    "make_stepper",
]
