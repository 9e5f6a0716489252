"""What a stepper hands back: the typed record of one step and the state after it.

A stepper is a pure integrator: :meth:`~femrub.steppers.base.Stepper.advance` moves its
state by one step ``h`` and returns a :class:`StepRecord`,

* ``t`` (s), ``X`` (the state after the step) and ``impulse`` (N s, the normal contact
  impulses ``P`` of the step, one per contact);
* with Coulomb friction, ``friction`` (:class:`Friction`): the tangential impulses
  ``P_t`` (n_c, 2) (N s), the heat each contact put into the blade (n_c,) (J) and the
  contact states (open, stick, slip) of the step;
* ``works``: the increments over the step of energy-balance integrals (J, names in
  :data:`WORK_KEYS`) that the stepper computed itself, exactly (impulses inside the step, an
  exact flight); the energy meter then uses them instead of its quadratures (paper Eq. 8
  energy balance). Any stepper may fill it; none has to.

:class:`State` is what ``step()`` / ``iterate()`` yield and what output sinks are fed: the
record's time, state and impulses with the gaps and gap velocities of ``X``.
:class:`StepRefused` is raised by a stepper whose contact model no longer applies.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

__all__ = ["Friction", "State", "StepRecord", "StepRefused", "WORK_KEYS"]

#: energy-balance integrals over a step a stepper may compute itself (J)
WORK_KEYS = (
    "contact_work",
    "external_work",
    "thermal_work",
    "damping_work",
    "heat_load",
    "heat_outflow",
    "tangential_work",
)


class StepRefused(ValueError):
    """A stepper cannot go on (its contact model no longer applies): status ``failed``."""


class Friction(NamedTuple):
    """Frictional quantities of one step, per contact."""

    #: tangential impulses ``P_t`` (n_c, 2) (N s)
    impulse: np.ndarray
    #: heat put into the blade (n_c,) (J)
    heat: np.ndarray
    #: contact state (n_c,) int8: open, stick, slip (:mod:`femrub.contact.friction`)
    state: np.ndarray


class StepRecord(NamedTuple):
    """One step of a stepper (see the module docstring)."""

    t: float
    X: np.ndarray
    impulse: np.ndarray
    friction: Friction | None = None
    works: Mapping[str, float] | None = None


@dataclass
class State:
    """The state after step ``k``: time, state vector and contact quantities of the step."""

    k: int
    t: float
    X: np.ndarray
    impulse: np.ndarray
    gap: np.ndarray
    gap_velocity: np.ndarray
    friction_impulse: np.ndarray | None = None
