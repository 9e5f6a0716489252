"""Exponential Moreau-type stepper: exact flight between contact events, Newton impulses.

Between events the model is linear and every step is integrated exactly
(:mod:`femrub.steppers.flows`: ``e^{hL}`` and the φ-functions of the linearly interpolated
load, one augmented matrix exponential per step size, precomputed for the constant ``h``)::

    X_{k+1} = e^{hL} X_k + h φ1(hL) G s_k + h φ2(hL) G (s_{k+1} − s_k),     L = A⁻¹ B

Contact enters at instants: an impulse ``P`` at time ``t_e`` changes the state by
``ΔX = A⁻¹ (Hm + Ht diag α) P`` (velocity jump and frictional heat ``α P`` at once). The
impulses solve the same LCP as the θ-method, with the same shared solve
(:func:`femrub.contact.impulses.solve_impulses`): with the pre-impact gap velocity ``ġ⁻``
(the *free velocity*) and the Delassus operator ``W = Gvᵀ A⁻¹ (Hm + Ht diag α)``, Newton's
law ``ġ⁺ = ġ⁻ + W P``::

    0 <= P  ⊥  (ġ⁺ + e ġ⁻) / (1 + e) >= 0

Energy: the impulse changes the kinetic energy by ``Pᵀ (ġ⁻ + ġ⁺) / 2 = −(1 − e) / (2 (1 + e))
Pᵀ W P <= 0`` (fixed obstacle), and the exact free flight neither creates nor dissipates
energy, so no step creates energy for e <= 1. The stepper reports this contact work to the
energy meter (the meter's midpoint formula is the θ-method's).

Events (``events=True``): a contact open at the start of a (sub)step whose exact free-flight
gap is negative at its end closes inside it; its closing time is located on the exact flow
(Illinois regula falsi on ``g(τ)``, one matrix exponential per evaluation), the flow is
stopped there and the impulse is given at contact (no penetration, exact contact time). With
e = 0 on a fixed obstacle and constant α, an impacted contact is then *held* closed by the
exact multiplier flow (``flows``: ``λ = −W⁻¹ Gvᵀ A⁻¹ (B X + F)``, its impulse ``∫ λ dt`` and
heat integrated exactly) until ``λ`` vanishes; that release time is located the same way.
So persistent contact phases (a blade pressed on the casing) are integrated exactly too.
Without events (``events=False``), or for contacts that close again after the event budget
of a step, the impulse is given at the end of the step on penetrating, approaching
contacts (velocity-level Moreau, penetration below ``h |ġ|``) and releases happen at step
ends. A moving obstacle or a time-varying α leaves only impulses (nothing is held).

Cost: one dense product per step (as the θ-method's dense path) plus one matrix exponential
per event-location evaluation, so the model must be small (dense, reduced): at most
:data:`MAX_COORDINATES` coordinates.
"""

from __future__ import annotations

import math

import numpy as np

from ..contact.impulses import solve_impulses
from ..fem.linalg import Factorised
from .base import Stepper
from .flows import FlowFamily

__all__ = ["ExponentialMoreau", "MAX_COORDINATES"]

#: Largest model (coordinates) the dense exponential stepper accepts.
MAX_COORDINATES = 3000
#: Events located per step; later closings of the step get end-of-step impulses.
MAX_EVENTS = 64
#: Most sign checks per step (see ``probes``).
MAX_PROBES = 512
_XTOL = 1e-11  # relative tolerance (of h) on an event time


class ExponentialMoreau(Stepper):
    """Exact-in-time Moreau stepper for moderate-size models (see module docstring).

    Parameters
    ----------
    model : :class:`~femrub.model.first_order.FirstOrderModel` with at most
        :data:`MAX_COORDINATES` coordinates (reduce larger ones first).
    h : time step (s).
    events : locate contact closings and releases inside the step (default) or give
        impulses at step ends only.
    probes : points per step (``j h / probes``) where the exact gaps and held multipliers
        are checked for a sign change before an event is located (1: step ends only;
        default: four per shortest period ``2π / max |Im eig(A⁻¹B)|``, at most
        :data:`MAX_PROBES`).
    """

    name = "exponential"

    def __init__(self, model, h, *, events: bool = True, probes: int | None = None, t0=0.0):
        n = getattr(model, "n_dofs", 0)
        if n > MAX_COORDINATES:
            raise ValueError(
                f"the exponential stepper is dense: the model has {n} coordinates "
                f"(> {MAX_COORDINATES}); reduce it first (scene: reduction.method = "
                "'craig-bampton'; API: ThermoelasticCraigBampton(model, ...).reduce())"
            )
        if not isinstance(events, bool):
            raise ValueError(f"events must be true or false, got {events!r}")
        if probes is not None and not (isinstance(probes, int) and 1 <= probes <= MAX_PROBES):
            raise ValueError(f"probes must be an integer in [1, {MAX_PROBES}], got {probes!r}")
        self.events, self.probes = events, probes
        super().__init__(model, h, t0=t0)

    # -- set-up ------------------------------------------------------------------------------
    def _setup(self):
        m, h = self.model, self.h
        lu = Factorised(m.A, what="matrix A")
        L = np.asarray(lu.solve(m.B.toarray()))
        F = (
            np.column_stack([term.vector for term in m.loads])
            if m.loads
            else np.zeros((m.n_dofs, 0))
        )
        G = np.asarray(lu.solve(F)) if F.shape[1] else F
        if not (np.all(np.isfinite(L)) and np.all(np.isfinite(G))):
            raise ValueError("A⁻¹B or A⁻¹F is not finite: check the model's matrices")
        self._signals = [term.signal for term in m.loads]
        self._sk = self._signal_values(self.t)
        c = m.contact
        self._hold = False
        AinvH = GvT = None
        if c is not None:
            self._Zm = np.asarray(lu.solve(c.Hm))
            self._Zt = np.asarray(lu.solve(c.Ht))
            self._Wm, self._Wt = c.GvT @ self._Zm, c.GvT @ self._Zt
            GvT = c.GvT
            # held contacts need a fixed obstacle and a constant α (a time-invariant flow)
            self._hold = (
                not callable(c.gap0) and c.gap_rate is None and not callable(c.heat_coefficient)
            )
            if self._hold:
                AinvH = self._Zm + self._Zt * c.heat_coefficient
        self._flows = FlowFamily(L, G, AinvH, GvT, h)
        self._flows.flow((), h)  # the free step: one augmented exponential
        if self.probes is None:  # four checks per shortest period of the model
            w_max = float(np.max(np.abs(np.linalg.eigvals(L).imag), initial=0.0))
            q = math.ceil(h * w_max / (0.5 * math.pi)) if w_max > 0 else 1
            self.probes = int(min(max(q, 1), MAX_PROBES))
        self._S: tuple = ()  # held contacts
        self._warm = None
        self._work = 0.0

    def _signal_values(self, t):
        return np.array([float(sig(t)) for sig in self._signals])

    # -- one step ------------------------------------------------------------------------------
    def _advance(self):
        t, X, P = super()._advance()
        return t, X, P, self._work

    def _step(self):
        h, t, c = self.h, self.t, self.model.contact
        s0, s1 = self._sk, self._signal_values(t + h)
        self._sk = s1
        X, S, a = self.X, self._S, 0.0
        P = np.zeros(self.model.n_contacts)
        self._work = 0.0
        for n_events in range(MAX_EVENTS + 1):
            u0 = s0 + (s1 - s0) * (a / h)
            Xe, PS = self._flows.flow(S, h - a)(X, u0, s1)
            if c is None:
                return Xe, P
            ev = None
            if self.events and n_events < MAX_EVENTS:
                ev = self._event(S, X, a, Xe, s0, s1)
            if ev is None:
                break
            a, kind, i, X, PSa = ev
            P[list(S)] += PSa
            if kind == "release":
                S = tuple(j for j in S if j != i)
            else:
                X, S = self._impact(t + a, X, S, P, forced=i)
        X = Xe
        P[list(S)] += PS
        if S and not self.events:  # releases at step ends
            lam = self._flows.multiplier(S, X, s1)
            S = tuple(j for j, lj in zip(S, lam) if lj > 0.0)
        X, S = self._impact(t + h, X, S, P)
        self._S = S
        return X, P

    # -- impulses ------------------------------------------------------------------------------
    def _impact(self, te, X, S, P, forced=None):
        """Newton impulses at time ``te`` (shared LCP); update ``P`` in place; new held set."""
        c = self.model.contact
        g, gd = c.gap(te, X), c.gap_velocity(te, X)
        held = np.zeros(c.n, dtype=bool)
        held[list(S)] = True
        trigger = ~held & (g <= 0.0) & (gd < 0.0)
        if forced is not None:
            trigger[forced] = gd[forced] < 0.0
        if not trigger.any():
            return X, S
        active = trigger | held
        alpha = c.alpha_at(te)
        e = np.where(held, 0.0, c.restitution)
        W = self._Wm + self._Wt * alpha
        Pi = solve_impulses(W / (1.0 + e)[:, None], gd, active, self._warm)
        self._warm = Pi > 0.0
        Xn = X + (self._Zm + self._Zt * alpha) @ Pi
        self._work += float(Pi @ (c.structure_velocity(X) + c.structure_velocity(Xn))) / 2
        P += Pi
        if not self._hold:
            return Xn, ()
        gdn = c.gap_velocity(te, Xn)
        tol = 1e-9 * max(float(np.max(np.abs(gd[active]))), 1e-300)
        keep = active & (e == 0.0) & (gdn <= tol)
        return Xn, tuple(np.flatnonzero(keep))

    # -- events --------------------------------------------------------------------------------
    def _event(self, S, Xa, a, Xe, s0, s1):
        """Earliest closing or release in ``(a, h]``: ``(τ, kind, i, X(τ), P_S(a..τ))``.

        Signs are checked at ``q`` points of a full step (probe rows, one small product) or
        at both ends of a part step; the first sign change is then located exactly.
        """
        c, h, t, flows = self.model.contact, self.h, self.t, self._flows
        n_s = len(S)

        def state(tau):
            u0, ut = s0 + (s1 - s0) * (a / h), s0 + (s1 - s0) * (tau / h)
            Xt, Pt = flows.flow(S, tau - a)(Xa, u0, ut)
            return Xt, Pt, ut

        grid = [a, h]
        gv = [c.gap(t + a, Xa), c.gap(t + h, Xe)]
        lv = [np.zeros(0), np.zeros(0)]
        if S:
            lv = [flows.multiplier(S, Xa, s0 + (s1 - s0) * (a / h)), flows.multiplier(S, Xe, s1)]
        q = self.probes
        if q > 1:
            taus = a + (h - a) * np.arange(1, q) / q
            if a == 0.0:  # full step: cached probe rows, one small product
                Rx, R0, R1 = flows.probe(S, c.GT, q)
                V = (Rx @ Xa + R0 @ s0 + R1 @ s1).reshape(q - 1, c.n + n_s)
                if callable(c.gap0):
                    V[:, : c.n] += np.array([c.gap_at(t + tau) for tau in taus])
                else:
                    V[:, : c.n] += c.gap0
            else:  # part step after an event: march the cached flow over h / q
                taus = np.arange(1, q) * (h / q)
                taus = taus[taus > a + 1e-9 * h]
                f, rows, Xt = flows.flow(S, h / q, cache=True), [], Xa
                for lo, tau in zip([a, *taus[:-1]], taus):
                    if lo == a and tau - a != h / q:
                        f_lo = flows.flow(S, tau - a)
                    else:
                        f_lo = f
                    Xt, _ = f_lo(Xt, s0 + (s1 - s0) * (lo / h), ut := s0 + (s1 - s0) * (tau / h))
                    lam = flows.multiplier(S, Xt, ut) if S else np.zeros(0)
                    rows.append(np.r_[c.gap(t + tau, Xt), lam])
                V = np.array(rows).reshape(len(taus), c.n + n_s)
            grid = [a, *taus, h]
            gv = [gv[0], *V[:, : c.n], gv[1]]
            lv = [lv[0], *V[:, c.n :], lv[1]]
        gv, lv = np.array(gv), np.array(lv).reshape(len(grid), n_s)
        held = np.zeros(c.n, dtype=bool)
        held[list(S)] = True
        cand = []  # (bracket lo, hi, kind, contact, f, f(lo) > 0, f(hi) < 0)
        # closing: the gap falls below min(g(a), 0) after having been above it
        f_cl = gv - np.minimum(gv[0], 0.0)
        for i in np.flatnonzero(~held & np.any(f_cl[1:] < 0.0, axis=0)):
            j = 1 + int(np.argmax(f_cl[1:, i] < 0.0))
            ref = min(gv[0, i], 0.0)
            f = lambda tau, i=i, ref=ref: c.gap(t + tau, state(tau)[0])[i] - ref  # noqa: E731
            br = (grid[j - 1], grid[j], f_cl[j - 1, i], f_cl[j, i])
            if br[2] <= 0.0:  # at the surface at a (just released): find where it is open
                br = _open_side(f, a, grid[j], f_cl[j, i])
                if br is None:
                    continue  # back in within round-off: end-of-step impulse
            cand.append((*br, "closing", int(i), f))
        for k in np.flatnonzero(np.any(lv < 0.0, axis=0)):
            j = int(np.argmax(lv[:, k] < 0.0))
            if j == 0:  # pulled away already: release now
                return a, "release", S[k], Xa, np.zeros(n_s)
            f = lambda tau, k=k: flows.multiplier(S, *state(tau)[::2])[k]  # noqa: E731
            cand.append((grid[j - 1], grid[j], lv[j - 1, k], lv[j, k], "release", S[k], f))
        best, hi = None, h
        for lo, b, f_lo, f_hi, kind, i, f in sorted(cand, key=lambda x: x[1]):
            if lo >= hi:
                continue
            if b > hi:
                b, f_hi = hi, f(hi)
                if f_hi >= 0.0:
                    continue  # happens after the earliest event found so far
            hi = _locate(f, lo, b, f_lo, f_hi)
            best = (kind, i)
        if best is None:
            return None
        Xt, Pt, _ = state(hi)
        return hi, best[0], best[1], Xt, Pt


def _locate(f, lo, hi, f_lo, f_hi):
    """Root of ``f`` with ``f(lo) > 0 > f(hi)`` by Illinois regula falsi; returns the bracket
    end with ``f <= 0`` (the event has just happened)."""
    span, side = hi - lo, 0
    if f_lo <= 0.0:
        return lo
    for _ in range(200):
        if hi - lo <= _XTOL * span:
            break
        x = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        if not (lo < x < hi):
            x = 0.5 * (lo + hi)
        fx = f(x)
        if fx > 0.0:
            lo, f_lo = x, fx
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = x, fx
            if side == 1:
                f_lo *= 0.5
            side = 1
    return hi


def _open_side(f, a, b, f_b, halvings=30):
    """Bracket ``(lo, b', f(lo) > 0, f(b') < 0)`` between ``a`` (``f(a) = 0``) and ``b``."""
    for _ in range(halvings):
        x = a + 0.5 * (b - a)
        fx = f(x)
        if fx > 0.0:
            return x, b, fx, f_b
        b, f_b = x, fx
    return None
