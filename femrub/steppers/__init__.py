"""Time steppers for first-order models with unilateral contact: pure integrators.

Each stepper advances a state and returns typed step records (:mod:`.record`); the runnable
classes with ``run()`` (recording, stop limits, verdict) are in :mod:`femrub.analysis`.
"""

from .base import Stepper, check_step
from .carpenter import Carpenter
from .exponential import ExponentialMoreau
from .penalty import Penalty
from .record import Friction, State, StepRecord, StepRefused
from .theta import ACTIVATION_RULES, ThetaMethod

SCHEMES = {
    "theta": ThetaMethod,
    "carpenter": Carpenter,
    "penalty": Penalty,
    "exponential": ExponentialMoreau,
}


def make_stepper(scheme: str, model, h, *, schemes=None, **options) -> Stepper:
    """Stepper by name: ``"theta"`` (paper Sec. 3), ``"carpenter"``, ``"penalty"`` or
    ``"exponential"`` (exact flight between contact events), from ``schemes`` (default
    :data:`SCHEMES`, the pure integrators)."""
    schemes = SCHEMES if schemes is None else schemes
    try:
        cls = schemes[scheme]
    except KeyError:
        raise ValueError(f"unknown scheme {scheme!r}; use one of {', '.join(schemes)}") from None
    return cls(model, h, **options)


__all__ = [
    "ACTIVATION_RULES",
    "Carpenter",
    "ExponentialMoreau",
    "Friction",
    "Penalty",
    "SCHEMES",
    "State",
    "StepRecord",
    "StepRefused",
    "Stepper",
    "ThetaMethod",
    "check_step",
    "make_stepper",
]
