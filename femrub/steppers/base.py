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
  that can integrate them);
* :meth:`Stepper.restart`: start again from a given state and time, the factorised operators
  kept (steppers whose ``restartable`` is true: the period map of :mod:`femrub.periodic`).

Recording, stop limits and the verdict live in the analysis layer above
(:mod:`femrub.analysis`, whose runnable subclasses add ``run()``). Every stepper refuses a
model that starts inside the casing (initial penetration).

A contact's history outside ``X`` (an abradable coating's wear map, the casing's heat) is the
run's state: a stepper runs ``model.with_(contact=contact.with_fresh_history(h))``, its own
copy started afresh, as ``stepper.model`` (read the wear of a run from
``stepper.model.contact.wear``); the model it was given is never changed, and steppers of
one model may step in any order.
"""

from __future__ import annotations

import math

import numpy as np

from ..blas import SERIAL_SETUP_DOFS, one_blas_thread
from ..model.first_order import FirstOrderModel
from .record import Friction, State, StepRecord

__all__ = ["Friction", "PENETRATION_TOLERANCE", "State", "StepRecord", "Stepper", "check_step"]

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
    #: :meth:`restart` resets every state the step carries (``_restart``)
    restartable = False

    def __init__(self, model: FirstOrderModel, h: float, *, t0: float = 0.0):
        if not isinstance(model, FirstOrderModel):
            raise TypeError("a stepper needs a femrub.FirstOrderModel")
        self.h = check_step(h)
        if model.contact is not None and model.contact.carried_state:
            # the contact's history (wear map, casing heat) is this run's own state
            model = model.with_(contact=model.contact.with_fresh_history(self.h))
        self.model = model
        self.k = 0
        self.t0 = self.t = float(t0)
        self.X = model.x0.copy()
        self.impulse = np.zeros(model.n_contacts)
        #: the frictional quantities of the last step (:class:`Friction`), or ``None``
        self.friction = None
        self._h_lim = None
        self._refuse_wear()
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

    def restart(self, X, t: float = 0.0, history: tuple | None = None) -> None:
        """Start again from the state ``X`` (N,) at the time ``t`` (s): step ``k = 0``, no
        impulse, the warm starts and carried load signals of the last run dropped, the
        factorised operators kept. ``history``: the state of the history the contact carries
        outside ``X`` (:meth:`Contact.history_snapshot
        <femrub.contact.gap.Contact.history_snapshot>`, e.g. of a run's
        :class:`~femrub.output.results.Snapshot`), needed when it carries one.

        Raises
        ------
        TypeError
            The stepper does not say how to reset what its step carries (``restartable``).
        ValueError
            ``X`` is not a finite state of the model, or the contact has a history outside
            ``X`` (an abradable coating, casing heat: not a function of ``X``) and no
            ``history`` is given.

        Notes
        -----
        A state within ``h |ġ|`` inside the casing is a state the θ-method reaches (it
        does not prevent penetration at the position level), so it is not refused here.
        """
        if not self.restartable:
            raise TypeError(f"the {self.name} stepper cannot restart from a given state")
        c = self.model.contact
        carried = c is not None and bool(c.carried_state)
        if carried and history is None:
            raise ValueError(
                "a contact with a history outside the state (abradable coating, casing heat) "
                "cannot restart from a state alone: pass history=contact.history_snapshot()"
            )
        X = np.array(X, dtype=float)
        if X.shape != (self.model.n_dofs,) or not np.all(np.isfinite(X)):
            raise ValueError(f"restart state must be a finite vector of length {self.model.n_dofs}")
        if carried:
            c.restore_history(history)
        self.k, self.t0, self.t, self.X = 0, float(t), float(t), X
        self.impulse = np.zeros(self.model.n_contacts)
        self.friction = None
        self._restart()

    def _restart(self) -> None:
        """Reset what the step carries from step to step (warm starts, signals)."""

    @property
    def state(self) -> State:
        c, t, X = self.model.contact, self.t, self.X
        if c is None:
            return State(self.k, t, X, self.impulse, np.zeros(0), np.zeros(0))
        return State(self.k, t, X, self.impulse, c.gap(t, X), c.gap_velocity(t, X))

    def advance(self) -> StepRecord:
        """One step of size ``h``; its :class:`StepRecord`."""
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
