"""The integrator protocol every time stepper follows: ``advance()``, ``step()``, ``iterate()``.

A stepper is a pure integrator on any :class:`~femrub.model.first_order.FirstOrderModel`: it
advances ``t_{k+1} = t0 + (k + 1) h`` and knows nothing of scenes, files, stop limits,
verdicts or estimates. Subclasses implement ``_step()`` (advance one step from
``(self.t, self.X)``; return ``(X_new, impulse)`` or, with friction,
``(X_new, impulse, friction)``, a :class:`~femrub.steppers.record.Friction`). The public
methods:

* :meth:`Stepper.advance`: one step, its typed :class:`~femrub.steppers.record.StepRecord`;
* :meth:`Stepper.step`: one step, the new :class:`~femrub.steppers.record.State`;
* :meth:`Stepper.iterate`: the initial state, then the state after every step to ``t_end``;
* :meth:`Stepper.block_writer`: a compiled writer of whole blocks of steps into given rows
  (the fast path of the θ-method), or ``None``;
* :meth:`Stepper.measure_works`: ask for the exact works of each step in its record (steppers
  that can integrate them).

Recording, stop limits and the verdict live in the analysis layer above
(:mod:`femrub.analysis`, whose runnable subclasses add ``run()``). Every stepper refuses a
model that starts inside the casing (initial penetration).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ..blas import SERIAL_SETUP_DOFS, one_blas_thread
from ..model.first_order import FirstOrderModel
from .record import Friction, State, StepRecord

__all__ = ["Friction", "PENETRATION_TOLERANCE", "State", "StepRecord", "Stepper", "check_step"]

#: identifies the stepper that owns a contact's state (:meth:`Stepper._check_owner`)
_TOKENS = itertools.count(1)
#: initial gaps below minus this (m) are an initial penetration
PENETRATION_TOLERANCE = 1e-12


def check_step(h, t_end=None) -> float:
    """Validate the step ``h`` (s) and the end time; return ``float(h)``."""
    try:
        h = float(h)
    except (TypeError, ValueError):
        raise ValueError(f"time step h must be a number, got {h!r}") from None
    if not math.isfinite(h) or h <= 0.0:
        raise ValueError(f"time step h must be finite and > 0 (seconds), got {h!r}")
    if t_end is not None:
        t_end = float(t_end)
        if not math.isfinite(t_end) or t_end < 0.0:
            raise ValueError(f"end time t_end must be finite and >= 0 (seconds), got {t_end!r}")
    return h


class Stepper:
    """Base class; see the module docstring. ``h`` is the time step (s)."""

    name = "stepper"
    #: a recorder may stop a run whose energy balance opens (numerical blow-up)
    blowup_check = True
    #: the step locates contact events inside itself (no contact-resolution check needed)
    locates_events = False
    #: bounds its impulses by ``Contact.impulse_cap`` (abradable coatings)
    supports_wear = False

    def __init__(self, model: FirstOrderModel, h: float, *, t0: float = 0.0):
        if not isinstance(model, FirstOrderModel):
            raise TypeError("a stepper needs a femrub.FirstOrderModel")
        self.model = model
        self.h = check_step(h)
        self.k = 0
        self.t0 = self.t = float(t0)
        self.X = model.x0.copy()
        self.impulse = np.zeros(model.n_contacts)
        #: the frictional quantities of the last step (:class:`Friction`), or ``None``
        self.friction = None
        self._h_lim = None
        self._refuse_wear()
        self._token = next(_TOKENS)
        self._owned_states = bool(self._contact_states())
        self._claim_contact_state()
        self._check_initial_gap()
        if model.n_dofs <= SERIAL_SETUP_DOFS:  # no BLAS worker left spinning into the steps
            with one_blas_thread:
                self._setup()
        else:
            self._setup()

    def _refuse_wear(self) -> None:
        """An abradable coating needs a stepper that bounds its impulses."""
        c = self.model.contact
        if c is not None and c.wear is not None and not self.supports_wear:
            raise ValueError(
                f"an abradable coating needs scheme.name = 'theta' (the {self.name} "
                "scheme does not bound its contact impulses)"
            )

    def _contact_states(self) -> list:
        """:attr:`~femrub.contact.gap.Contact.carried_state` of the model's contact."""
        c = self.model.contact
        return [] if c is None else c.carried_state

    def _claim_contact_state(self) -> None:
        """Start the contact's states afresh for this stepper (a fresh coating, a cold
        casing) and mark them as its own."""
        for state in self._contact_states():
            if state is self.model.contact.wear:
                state.reset(self.h)
            else:
                state.reset()
            state.owner = self._token

    def _check_owner(self) -> None:
        """Before stepping: the contact's states are this stepper's. Another stepper of the
        same model built or run since this one was built has reset or worn them: before the
        first step they are started afresh again, after it the run cannot go on."""
        for state in self._contact_states():
            if getattr(state, "owner", None) != self._token:
                if self.k:
                    raise RuntimeError(
                        "another stepper of this model has used its contact's state (wear "
                        "map, casing heat) since this run started; run the steppers of one "
                        "model one after the other"
                    )
                self._claim_contact_state()
                return

    def _check_initial_gap(self) -> None:
        """Refuse a model that starts inside the casing (no scheme can undo it honestly)."""
        c = self.model.contact
        if c is None:
            return
        g = np.asarray(c.gap(self.t, self.X), dtype=float)
        if g.size and g.min() < -PENETRATION_TOLERANCE:
            i = int(np.argmin(g))
            raise ValueError(
                f"initial penetration: contact {i} starts {-g[i]:.3g} m inside the casing at "
                f"t = {self.t:g} s ({int(np.sum(g < -PENETRATION_TOLERANCE))} contact(s)); "
                "increase the clearance or move the casing (contact.casing.phase)"
            )

    def _refuse_restitution(self) -> None:
        """For schemes that model a perfectly plastic impact only (e = 0)."""
        c = self.model.contact
        e = float(getattr(c, "restitution", 0.0) or 0.0) if c is not None else 0.0
        if e > 0.0:
            raise ValueError(
                f"{self.name} does not model Newton's restitution (contact.restitution = "
                f"{e:g}); use scheme.name = 'theta' or contact.restitution = 0"
            )

    # -- to be implemented by subclasses ---------------------------------------------------
    def _setup(self) -> None:
        """Factorise constant matrices, precompute operators."""

    def _step(self) -> tuple:
        """Advance from ``(self.t, self.X)`` by ``h``; return ``(X_new, impulse)`` or, with
        friction, ``(X_new, impulse, friction)`` (:class:`Friction`)."""
        raise NotImplementedError

    def _stability_limit(self) -> float:
        """Largest stable step (s); ``inf`` for unconditionally stable schemes."""
        return math.inf

    # -- public API ------------------------------------------------------------------------
    def stability_limit(self) -> float:
        """Largest stable step (s), computed once per stepper (an eigen-solve for Carpenter)."""
        if self._h_lim is None:
            self._h_lim = self._stability_limit()
        return self._h_lim

    def block_writer(self):
        """A writer of whole blocks of steps, or ``None`` (then steps go one by one).

        ``block(m, X, t, P, Pt, heat, state) -> (steps done, friction rows written, error)``
        advances ``m`` steps and writes them into the given rows (states ``X`` (m, N), times,
        impulses and the frictional rows of :class:`Friction`); ``error``, an exception or
        ``None``, is what :meth:`advance` would have raised after the steps done.
        """
        return None

    def measure_works(self, on: bool) -> None:
        """Fill the records' ``works`` with the exact energy-balance integrals of each step
        when the stepper can integrate them (``on``); the others ignore it."""

    def start_run(self) -> None:
        """Before a run from the current state: the contact's history is this stepper's."""
        self._check_owner()

    @property
    def state(self) -> State:
        c, t, X = self.model.contact, self.t, self.X
        if c is None:
            return State(self.k, t, X, self.impulse, np.zeros(0), np.zeros(0))
        return State(self.k, t, X, self.impulse, c.gap(t, X), c.gap_velocity(t, X))

    def advance(self) -> StepRecord:
        """One step of size ``h``; its :class:`StepRecord`."""
        if self._owned_states:
            self._check_owner()
        X, impulse, *friction = self._step()
        self.friction = friction[0] if friction else None
        self.k += 1
        self.t = self.t0 + self.k * self.h
        if self.model.contact is not None:
            Pt = None if self.friction is None else self.friction.impulse
            self.model.contact.after_step(self.t, X, impulse, self.h, Pt)
        self.X, self.impulse = X, impulse
        return StepRecord(self.t, X, impulse, self.friction)

    def step(self) -> State:
        """Advance one step of size ``h`` and return the new :class:`State`."""
        self.advance()
        return self.state

    def steps_to(self, t_end: float) -> int:
        """Number of steps from the current time to ``t_end`` (validated)."""
        check_step(self.h, t_end)
        return int(round((t_end - self.t) / self.h))

    def iterate(self, t_end: float):
        """Yield the initial state, then the state after every step until ``t_end``."""
        n = self.steps_to(t_end)
        yield self.state
        for _ in range(n):
            yield self.step()
