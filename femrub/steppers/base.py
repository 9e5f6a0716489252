"""Common machinery of the time steppers: ``step()``, ``iterate()`` and ``run()``.

A stepper works on any :class:`~femrub.model.first_order.FirstOrderModel` and advances
``t_{k+1} = t0 + (k + 1) h``. Subclasses implement ``_step()`` (advance one step, return the
new state and the contact impulses); the public ``step()`` returns the new :class:`State`,
``iterate()`` yields states, ``run()`` hands the steps to a
:class:`~femrub.output.recorder.Recorder`, which collects the
:class:`~femrub.output.results.Results` (energy balance, progress bar, physical stop criteria,
protection against numerical blow-up). Whatever stops a run (instability, a stop criterion,
Ctrl-C, SIGTERM, an exception), ``run()`` returns what was computed so far; a run the
recorder ends as ``ok`` is then judged by :func:`femrub.output.verdict.assess` (balance
tolerances -> ``inaccurate``, resolution warnings). Every stepper refuses a model that
starts inside the casing (initial penetration) and a run longer than :data:`MAX_STEPS`.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ..blas import SERIAL_SETUP_DOFS, one_blas_thread
from ..model.first_order import FirstOrderModel
from ..output.limits import run_limits
from ..output.recorder import Recorder, State
from ..output.results import Results
from ..output.verdict import assess
from ..scene.validate import MAX_STEPS

__all__ = ["MAX_STEPS", "PENETRATION_TOLERANCE", "State", "Stepper", "check_step"]

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
    #: the recorder stops a run whose energy balance opens (numerical blow-up)
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
        nc = model.n_contacts
        self.impulse = np.zeros(nc)
        self.extra = None
        self._h_lim = None
        wear = None if model.contact is None else model.contact.wear
        if wear is not None:
            if not self.supports_wear:
                raise ValueError(
                    f"an abradable coating needs scheme.name = 'theta' (the {self.name} "
                    "scheme does not bound its contact impulses)"
                )
        self._token = next(_TOKENS)
        self._owned_states = bool(self._contact_states())
        self._claim_contact_state()
        self._check_initial_gap()
        if model.n_dofs <= SERIAL_SETUP_DOFS:  # no BLAS worker left spinning into the steps
            with one_blas_thread:
                self._setup()
        else:
            self._setup()

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
        friction, ``(X_new, impulse, extra)``: ``extra`` holds ``friction_impulse``
        (n_c, 2), the blade's ``heat`` (n_c,) (J) and the contact ``state`` (n_c,) of the step."""
        raise NotImplementedError

    def _block_writer(self):
        """A writer of whole blocks of steps for :meth:`Recorder.record` (``block``), or
        ``None``: ``run()`` then advances step by step."""
        return None

    def _stability_limit(self) -> float:
        """Largest stable step (s); ``inf`` for unconditionally stable schemes."""
        return math.inf

    # -- public API ------------------------------------------------------------------------
    def stability_limit(self) -> float:
        """Largest stable step (s), computed once per stepper (an eigen-solve for Carpenter)."""
        if self._h_lim is None:
            self._h_lim = self._stability_limit()
        return self._h_lim

    @property
    def state(self) -> State:
        c, t, X = self.model.contact, self.t, self.X
        if c is None:
            return State(self.k, t, X, self.impulse, np.zeros(0), np.zeros(0))
        return State(self.k, t, X, self.impulse, c.gap(t, X), c.gap_velocity(t, X))

    def _advance(self) -> tuple:
        """One step; return the new ``(t, X, impulse, extra)`` (``extra``: see ``_step``)."""
        if self._owned_states:
            self._check_owner()
        out = self._step()
        X, impulse = out[0], out[1]
        self.extra = out[2] if len(out) > 2 else None
        self.k += 1
        self.t = self.t0 + self.k * self.h
        if self.model.contact is not None:
            self.model.contact.after_step(self.t, X, impulse, self.h, self.extra)
        self.X, self.impulse = X, impulse
        return self.t, X, impulse, self.extra

    def step(self) -> State:
        """Advance one step of size ``h`` and return the new :class:`State`."""
        self._advance()
        return self.state

    def steps_to(self, t_end: float) -> int:
        """Number of steps from the current time to ``t_end`` (validated)."""
        check_step(self.h, t_end)
        n = int(round((t_end - self.t) / self.h))
        if n > MAX_STEPS:
            raise ValueError(
                f"h = {self.h:g} s to t_end = {t_end:g} s gives {n:.3g} steps; at most "
                f"{MAX_STEPS:.0e} allowed (raise h or lower t_end)"
            )
        return n

    def iterate(self, t_end: float):
        """Yield the initial state, then the state after every step until ``t_end``."""
        n = self.steps_to(t_end)
        yield self.state
        for _ in range(n):
            yield self.step()

    def run(
        self,
        t_end: float,
        *,
        progress: bool = False,
        limits: dict[str, float] | None = None,
        energy: bool = True,
        store_every: int = 0,
        on_state=None,
        on_rows=None,
        label: str | None = None,
        tolerances: dict | None = None,
        merge_time: float | None = None,
        lean: int = 0,
        default_limits: bool = True,
    ) -> Results:
        """Integrate to ``t_end`` and collect :class:`~femrub.output.results.Results`.

        Parameters
        ----------
        t_end : end time (s).
        progress : show a progress bar.
        limits : physical stop criteria, ``{signal name: max |value|}``; the key
            ``"contact_force"`` limits the contact force (N). Reaching one ends the run with
            status ``"diverged-physically"``. They replace the model's default limits of
            their signals (:mod:`femrub.output.limits`; ``inf``: no limit on that signal).
        energy : keep the energy balance (needs ``model.energy``); it also detects numerical
            blow-up (energy created from nothing).
        store_every : keep the full state every that many steps (0: never).
        on_state : callback ``f(state)`` after each step (e.g. streaming VTK output).
        on_rows : callback ``f(arrays)`` per checked block of rows (e.g. a streamed history).
        label : name of the run (progress bar and ``Results.info``).
        tolerances, merge_time : see :func:`femrub.output.verdict.assess` (balance
            tolerances; contact impulses closer than ``merge_time`` s form one episode of
            the resolution check, ``None``: no check).
        lean : 0: results with every per-step array. ``k >= 1``: a run held only to be
            compared with another: only times, impulses, signals and the stored states, at
            every ``k``-th step with the impulses summed over each ``k`` steps (``h`` of the
            results ``k h``); gaps, friction rows and the energy balance are never stored,
            the verdict reads its measures of them taken as the steps were recorded
            (:mod:`femrub.output.kept_rows`, ``Results.checks``).
        default_limits : also stop on the model's default physical limits
            (:func:`femrub.output.limits.model_limits`; ``False``: only ``limits``).
        """
        self._check_owner()
        recorder = Recorder(
            self.model,
            self.h,
            self.steps_to(t_end),
            scheme=self.name,
            stability_limit=self.stability_limit(),
            energy=energy,
            limits=run_limits(self.model, limits, default_limits),
            store_every=store_every,
            on_state=on_state,
            on_rows=on_rows,
            label=label,
            blowup_check=self.blowup_check,
            lean=lean,
        )
        res = recorder.record(
            self.state, self._advance, progress=progress, block=self._block_writer()
        )
        del recorder  # its per-step arrays that the results do not hold: before the checks
        if self.locates_events:
            merge_time = None
        return assess(res, tolerances=tolerances, merge_time=merge_time)
