"""The period map of a model: its state after one period of the excitation, by the θ-method.

A periodic orbit of a forced model is a fixed point of its period map (the shooting
method; Colaïtis & Batailly, J. Sound Vib. 502, 2021, for blade-casing contact)::

    Φ_T(X0; p) = X(t0 + T)   with   X(t0) = X0,   T = m 2π / ω_f

where ω_f (rad/s) is the fundamental frequency of everything that forces the model: the
harmonic loads (``sin(ω t)``, ω = k Ω for an engine order k) and the casing's lobes passing
a contact (``n Ω`` for ``n`` lobes); ω_f is the largest frequency of which each of them is a
whole multiple, and ``m`` (``multiple``) asks for a subharmonic orbit. The map is the
model's own :class:`~femrub.steppers.theta.ThetaMethod` over ``N = ceil(T / h)`` steps of
``h = T / N`` (at most the step asked for, so a period is a whole number of steps): the
stepper, its factorisation and its contact algebra are built once per model and restarted
from each ``X0`` (:meth:`~femrub.steppers.base.Stepper.restart`); on a dense model whole
periods run in one compiled call (the stepper's block writer). Nothing of the contact
algebra is written here: the period map is a client of the stepper.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from ..steppers.theta import ThetaMethod

__all__ = ["Orbit", "PeriodMap", "forcing_frequency"]

#: largest harmonic order searched for a common fundamental of the forcing frequencies
MAX_ORDER = 64


def _frequencies(model) -> list[float]:
    """Angular frequencies (rad/s) forcing ``model``: its ``sin`` loads and lobe passing."""
    out = []
    for term in model.loads:
        law = getattr(term.signal, "law", None)
        if law == "sin":
            out.append(abs(float(term.signal.omega)))
        elif law == "ramp":
            raise ValueError(
                "a ramped load is not periodic; use loads.tip_force.law = 'sin' or 'constant'"
            )
        elif law is None and np.any(term.vector):
            raise ValueError(
                f"load {term.name!r} has a signal of unknown period; give the period "
                "(period=...) or a femrub ForceLaw signal"
            )
    sweep = model.sweep
    omega = model.parameters.get("rotation_speed", 0.0)
    lobes = 0 if sweep is None else int(getattr(sweep.casing, "lobes", 0))
    if lobes and omega:
        out.append(lobes * abs(float(omega)))
    return [w for w in out if w > 0.0]


def forcing_frequency(model) -> float:
    """The fundamental angular frequency ω_f (rad/s) of the model's excitation.

    ``ω_f`` is the largest frequency of which every forcing frequency ω_i is a whole
    multiple (``ω_i = k_i ω_f``, ``k_i <= MAX_ORDER``): ``k Ω`` for a tip force at engine
    order ``k``, ``n Ω`` for a casing of ``n`` lobes, ``gcd(k, n) Ω`` for both.

    Raises
    ------
    ValueError
        Nothing forces the model periodically, or its frequencies are incommensurate.
    """
    freqs = _frequencies(model)
    if not freqs:
        raise ValueError(
            "nothing forces this model periodically (no harmonic load, no lobed casing "
            "turning); give loads.tip_force.law = 'sin' or a lobed contact.casing"
        )
    top = min(freqs)
    for q in range(1, MAX_ORDER + 1):
        base = top / q
        if all(abs(w / base - round(w / base)) < 1e-9 * w / base for w in freqs):
            return base
    raise ValueError(
        f"the forcing frequencies {sorted(freqs)} rad/s have no common period (ratios not "
        f"whole up to {MAX_ORDER})"
    )


@dataclass(frozen=True)
class Orbit:
    """One period of a trajectory from ``t0``: times ``t`` (N + 1,) (s), states ``X``
    (N + 1, n), contact impulses ``P`` (N + 1, n_c) (N s; row 0 holds zeros)."""

    t: np.ndarray
    X: np.ndarray
    P: np.ndarray


class PeriodMap:
    """``Φ_T``: the θ-method's state after one period from a given state (module docstring).

    Parameters
    ----------
    model : :class:`~femrub.model.first_order.FirstOrderModel`, without temperature dofs
        (refused by :func:`femrub.periodic.continuation.check_model`) or any other.
    h : largest time step (s); the step used is ``h_used = T / N``, ``N = ceil(T / h)``.
    multiple : the orbit's period in periods of the excitation (1: period-1 orbits).
    period : the period T (s) of one excitation cycle; default ``2π / ω_f``
        (:func:`forcing_frequency`).
    steps : ``N``, the number of steps per orbit period, instead of ``ceil(T / h)`` (a branch
        keeps ``N`` through one point's corrections).
    t0 : the phase of the orbit's start (s).
    gamma, activation : the θ-method's options (:class:`~femrub.steppers.theta.ThetaMethod`).
    """

    def __init__(
        self,
        model,
        h: float,
        *,
        multiple: int = 1,
        period: float | None = None,
        steps: int | None = None,
        t0: float = 0.0,
        gamma: float = 0.5,
        activation: str | None = None,
    ):
        if int(multiple) != multiple or multiple < 1:
            raise ValueError(f"multiple must be a whole number >= 1, got {multiple!r}")
        base = 2.0 * math.pi / forcing_frequency(model) if period is None else float(period)
        if not (math.isfinite(base) and base > 0.0):
            raise ValueError(f"period must be finite and > 0 (s), got {period!r}")
        self.period = base * int(multiple)
        self.steps = int(steps) if steps else max(1, math.ceil(self.period / float(h) - 1e-9))
        self.h = self.period / self.steps
        self.t0 = float(t0)
        self.model = model
        self._options = {"gamma": gamma, "activation": activation}
        self.stepper = ThetaMethod(model, self.h, t0=t0, **self._options)
        self._block = self.stepper.block_writer()
        self._copies = [self]

    @property
    def compiled(self) -> bool:
        """Whether whole periods run in one compiled call (which releases the GIL)."""
        return self._block is not None

    def copies(self, count: int) -> list[PeriodMap]:
        """``count`` maps equal to this one, each with its own stepper (this one first): the
        maps of threads that run periods side by side."""
        while len(self._copies) < count:
            twin = copy.copy(self)
            twin.stepper = ThetaMethod(self.model, self.h, t0=self.t0, **self._options)
            twin._block = twin.stepper.block_writer()
            twin._copies = []
            self._copies.append(twin)
        return self._copies[:count]

    @property
    def n(self) -> int:
        """Size of the state."""
        return self.model.n_dofs

    def __call__(self, X0) -> np.ndarray:
        """``Φ_T(X0)``: the state one period after ``X0`` (N,)."""
        return self.orbit(X0).X[-1]

    def orbit(self, X0) -> Orbit:
        """The trajectory over one period from ``X0`` at ``t0`` (:class:`Orbit`)."""
        st, m = self.stepper, self.steps
        st.restart(X0, self.t0)
        nc = self.model.n_contacts
        X, t, P = np.empty((m + 1, self.n)), np.empty(m + 1), np.zeros((m + 1, nc))
        X[0], t[0] = st.X, st.t
        if self._block is not None:
            done, _, err = self._block(
                m,
                X[1:],
                t[1:],
                P[1:],
                np.zeros((m, nc, 2)),
                np.zeros((m, nc)),
                np.zeros((m, nc), dtype=np.int8),
            )
            if err is not None:
                raise err
            if done != m:
                raise FloatingPointError(f"the period map stopped after {done} of {m} steps")
        else:
            for k in range(1, m + 1):
                rec = st.advance()
                X[k], t[k], P[k] = rec.X, rec.t, rec.impulse
        if not np.all(np.isfinite(X[-1])):
            raise FloatingPointError("the period map gave a non-finite state")
        return Orbit(t, X, P)
