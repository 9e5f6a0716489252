"""Penalty baseline: regularised contact integrated by a stiff scipy integrator.

What a Python user would write instead of a nonsmooth scheme: the unilateral contact is
replaced by a spring (and optional dashpot) that acts only when the gap is closed::

    λ(t, X) = max(0, −k_p g − c_p ġ) if g < 0 else 0,   g = g0(t) + Gᵀ X,  ġ = ġ0(t) + Gvᵀ X
    Ẋ = A⁻¹ (B X + F(t) + (Hm + Ht diag α) λ(t, X))

integrated by scipy's ``Radau`` or ``BDF`` (the solvers behind ``solve_ivp``) with an
analytic Jacobian. The dashpot acts on the relative normal velocity ``ġ``, casing motion
``ġ0`` included. The right-hand side is only piecewise smooth, so the solver is restarted
at every contact closing/opening (an event located on the dense output), as ``solve_ivp``
event handling would. The accumulated impulse ``∫ λ dt`` is integrated with the state, so
the contact impulse per output step is exact to the solver tolerance. Output is on the
uniform grid ``t_k = k h`` like the other steppers; ``h`` is the output step, not the
integrator's (adaptive) step.

Impacts are perfectly plastic: a restitution coefficient ``e > 0`` is refused (``ValueError``)
rather than silently ignored.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import BDF, Radau

from ..fem.linalg import Factorised, compact
from .base import Stepper

__all__ = ["Penalty"]

_SOLVERS = {"Radau": Radau, "BDF": BDF}
# default absolute tolerance per unit of relative tolerance (states in m, m/s, K)
ATOL_PER_RTOL = 1e-9
# bisection on the switching function: at most this many halvings of the bracket ...
EVENT_BISECTIONS = 60
# ... stopping once the bracket is this narrow relative to max(1 s, |t|)
EVENT_TIME_RTOL = 1e-14


class Penalty(Stepper):
    """Penalty-regularised contact with a stiff adaptive integrator (see module docstring).

    Parameters
    ----------
    stiffness : penalty stiffness k_p (N/m).
    damping : penalty damping c_p (N s/m), acting only while the gap is closed.
    method : "Radau" or "BDF".
    rtol, atol : integrator tolerances (``atol`` defaults to ``ATOL_PER_RTOL × rtol``).
    """

    name = "penalty"

    def __init__(
        self,
        model,
        h,
        *,
        stiffness: float,
        damping: float = 0.0,
        method: str = "Radau",
        rtol: float = 1e-6,
        atol: float | None = None,
        t0: float = 0.0,
    ):
        k = float(stiffness)
        if not np.isfinite(k) or k <= 0:
            raise ValueError(f"penalty stiffness must be finite and > 0 (N/m), got {stiffness!r}")
        if not np.isfinite(float(damping)) or float(damping) < 0:
            raise ValueError(f"penalty damping must be finite and >= 0, got {damping!r}")
        if method not in _SOLVERS:
            raise ValueError(f"unknown method {method!r}; use one of {', '.join(_SOLVERS)}")
        self.stiffness, self.damping, self.method = k, float(damping), method
        self.rtol = float(rtol)
        self.atol = float(atol) if atol is not None else ATOL_PER_RTOL * self.rtol
        super().__init__(model, h, t0=t0)

    def _setup(self):
        m = self.model
        self._refuse_restitution()
        if m.contact is not None and m.contact.has_friction:
            raise ValueError(
                "the penalty baseline has no Coulomb friction; use scheme.name = 'theta' or "
                "'carpenter', or contact.friction = 0"
            )
        self._lu = Factorised(m.A, what="matrix A")
        self._B = compact(m.B)
        self._AinvB = self._lu.solve(m.B.toarray()) if self._lu.dense else None
        c = m.contact
        self._nc = 0 if c is None else c.n
        if c is not None:
            self._AHm, self._AHt = self._lu.solve(c.Hm), self._lu.solve(c.Ht)
        self._Y = np.concatenate([self.X, np.zeros(self._nc)])
        self._lam_out = np.zeros(self._nc)
        self._restart(self.t)

    # -- the regularised dynamics ----------------------------------------------------------
    def _forces(self, t, X):
        c = self.model.contact
        g = c.gap(t, X)
        gd = c.gap_velocity(t, X)
        closed = g < 0.0
        lam = np.where(closed, np.maximum(0.0, -self.stiffness * g - self.damping * gd), 0.0)
        return lam, closed & (lam > 0.0)

    def _rhs(self, t, Y):
        m = self.model
        X = Y[: m.n_dofs]
        rhs = self._B @ X + m.load(t)
        dX = self._lu.solve(rhs)
        if not self._nc:
            return dX
        lam, _ = self._forces(t, X)
        alpha = m.contact.alpha_at(t)
        dX = dX + self._AHm @ lam + self._AHt @ (alpha * lam)
        return np.concatenate([dX, lam])

    def _jac(self, t, Y):
        m = self.model
        n = m.n_dofs
        J = np.zeros((n + self._nc, n + self._nc))
        J[:n, :n] = self._AinvB if self._AinvB is not None else self._lu.solve(m.B.toarray())
        if self._nc:
            _, act = self._forces(t, Y[:n])
            if act.any():
                c = m.contact
                dlam = -(self.stiffness * c.GT + self.damping * c.GvT) * act[:, None]
                J[:n, :n] += (self._AHm + self._AHt * c.alpha_at(t)) @ dlam
                J[n:, :n] = dlam
        return J

    def _restart(self, t):
        self._solver = _SOLVERS[self.method](
            self._rhs, t, self._Y.copy(), np.inf, rtol=self.rtol, atol=self.atol, jac=self._jac
        )

    def _closed(self, t, Y):
        if not self._nc:
            return np.zeros(0, dtype=bool)
        return self._forces(t, Y[: self.model.n_dofs])[1]

    # -- stepping on the output grid ---------------------------------------------------------
    def _step(self):
        t_target = self.t + self.h
        n = self.model.n_dofs
        s, out = self._solver, None
        while out is None:
            if s.t >= t_target:
                out = s.dense_output()(t_target) if s.t > t_target else s.y.copy()
                break
            state0 = self._closed(s.t, s.y)
            t_old = s.t
            msg = s.step()
            if s.status == "failed":
                raise FloatingPointError(f"{self.method} failed: {msg}")
            if self._nc and not np.array_equal(self._closed(s.t, s.y), state0):
                sol = s.dense_output()
                te = self._event_time(sol, t_old, s.t, state0)
                if te >= t_target:
                    out = sol(t_target)
                self._Y = sol(te)  # restart at the switch: the right-hand side has a kink
                self._restart(te)
                s = self._solver
        impulse = out[n:] - self._lam_out if self._nc else np.zeros(0)
        self._lam_out = out[n:].copy()
        return out[:n].copy(), np.maximum(impulse, 0.0)

    def _event_time(self, sol, ta, tb, state0):
        """First time in (ta, tb] at which the set of closed contacts changes."""

        def changed(t):
            return not np.array_equal(self._closed(t, sol(t)), state0)

        lo, hi = ta, tb
        for _ in range(EVENT_BISECTIONS):
            mid = 0.5 * (lo + hi)
            if changed(mid):
                hi = mid
            else:
                lo = mid
            if hi - lo <= EVENT_TIME_RTOL * max(1.0, abs(hi)):
                break
        return hi
