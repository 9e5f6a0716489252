"""Exponential Moreau-type stepper: exact flight between contact events, Newton impulses.

Between events the model is linear and is integrated exactly (:mod:`~.flows`: ``e^{hL}``,
``L = A⁻¹B``, and the φ-functions of the load signals interpolated over the step by a
polynomial, one augmented matrix exponential precomputed for the constant ``h``)::

    X_{k+1} = e^{hL} X_k + Σ_i h φ_{i+1}(hL) A⁻¹F w_i          (s(t_k + σh) = Σ w_i σ^i / i!)

Contact enters at instants: an impulse ``P`` at ``t_e`` changes the state by
``ΔX = A⁻¹ (Hm + Ht diag α) P`` (velocity jump and frictional heat ``α P`` at once). The
impulses solve the θ-method's LCP with the same shared solve
(:func:`femrub.contact.impulses.solve_impulses`): free velocity = the pre-impact gap velocity
``ġ⁻``, Delassus operator ``W = Gvᵀ A⁻¹ (Hm + Ht diag α)``, ``ġ⁺ = ġ⁻ + W P``::

    0 <= P  ⊥  (ġ⁺ + e ġ⁻) / (1 + e) >= 0

The kinetic energy changes by ``Pᵀ (ġ⁻ + ġ⁺) / 2 = −(1 − e) / (2 (1 + e)) Pᵀ W P <= 0``
(fixed obstacle) and the exact flight neither creates nor dissipates energy: no step creates
energy for e <= 1. This contact work, and the works and heats of the flights integrated
exactly on them (:mod:`~.work`), are handed to the energy meter.

Events (``events=True``): exact gaps and held multipliers are checked at ``probes`` points
per step; at the first sign change the time is found on the exact flow
(:func:`~.flows.first_zero`) and the impulse is given at contact (no penetration). With
e = 0 (or a Zeno sequence) and a constant α, an impacted contact is then *held* by its exact
multiplier (fixed or moving casing, :class:`~.flows.FlowFamily`), its impulse ``∫λ dt`` and
heat integrated exactly, until ``λ`` vanishes (located the same way). Without events, or
after :data:`MAX_EVENTS` in a step, impulses are given at the step end on penetrating,
approaching contacts (velocity-level Moreau) and releases happen at step ends.

Coulomb friction (:mod:`~.friction`): the impulses solve Signorini–Coulomb with
Newton's law (the θ-method's solve); held contacts slide along their end-of-step slip (a fixed
point per step, :mod:`~.slide`), checked like a multiplier (a stick ends the hold).

Dense: at most :data:`MAX_COORDINATES` coordinates (reduce larger models first).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from ...contact.impulses import solve_impulses
from ...fem.linalg import Factorised
from ..base import Stepper
from ..record import WORK_KEYS, StepRecord
from .events import EventLocation
from .flows import FlowFamily
from .friction import FrictionalContact
from .kernels import flight, warm_up
from .loads import LoadPolynomial
from .work import METER_ORDER, NQ, WorkIntegrals

__all__ = ["ExponentialMoreau", "MAX_COORDINATES"]

#: Largest model (coordinates) the dense exponential stepper accepts.
MAX_COORDINATES = 3000
#: Events located per step; later closings of the step get end-of-step impulses.
MAX_EVENTS = 64
#: Most sign checks per step (see ``probes``).
MAX_PROBES = 512
#: Impacts of one contact in one step after which it is held (e = 0): a Zeno sequence
ZENO_HITS = 3


class ExponentialMoreau(EventLocation, FrictionalContact, Stepper):
    """Exact-in-time Moreau stepper for moderate-size models (see module docstring).

    Parameters
    ----------
    model : :class:`~femrub.model.first_order.FirstOrderModel` with at most
        :data:`MAX_COORDINATES` coordinates (reduce larger ones first).
    h : time step (s).
    events : locate contact closings and releases inside the step (default) or give
        impulses at step ends only.
    load_degree : degree of the polynomial interpolating the load signals over a step (at
        Chebyshev–Lobatto points; 1: linear interpolant), integrated exactly.
    probes : points per step (``j h / probes``) where the exact gaps and held multipliers
        are checked for a sign change before an event is located (1: step ends only;
        default: four per shortest period ``2π / max |Im eig(A⁻¹B)|``, at most
        :data:`MAX_PROBES`).
    """

    name = "exponential"
    locates_events = True

    def __init__(
        self,
        model,
        h,
        *,
        events: bool = True,
        probes: int | None = None,
        load_degree: int = 4,
        t0=0.0,
    ):
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
        if not (isinstance(load_degree, int) and 1 <= load_degree <= 8):
            raise ValueError(f"load_degree must be an integer in [1, 8], got {load_degree!r}")
        self.events, self.probes, self.load_degree = events, probes, load_degree
        super().__init__(model, h, t0=t0)

    # -- set-up ------------------------------------------------------------------------------
    def _setup(self):
        m, h = self.model, self.h
        warm_up()  # the compiled dyadic kernels: loaded (or compiled) once per process
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
        c = m.contact
        self._hold = False
        AinvH = GvT = None
        # a moving casing enters the held flow through g̈0: extra inputs, one per contact
        self._n_a = 0
        if c is not None:
            self._Zm = np.asarray(lu.solve(c.Hm))
            self._Zt = np.asarray(lu.solve(c.Ht))
            self._Wm, self._Wt = c.GvT @ self._Zm, c.GvT @ self._Zt
            GvT = c.GvT
            # held contacts need a constant α and the casing's motion (fixed, or ġ0 known)
            moving = callable(c.gap0) or c.gap_rate is not None
            self._hold = not callable(c.heat_coefficient) and (not moving or c.gap_rate is not None)
            self._friction_setup(lu)
            if self._fric:  # held contacts slide: constant columns (or none)
                AinvH = self._held_columns(lu)
                self._hold = self._hold and AinvH is not None
            elif self._hold:
                AinvH = self._Zm + self._Zt * c.heat_coefficient
            if self._hold:
                self._n_a = c.n if moving else 0
        G = np.hstack([G, np.zeros((m.n_dofs, self._n_a))])
        p = self.load_degree if G.shape[1] else 0
        rates = c.rate_at if self._n_a else None
        self._loads = LoadPolynomial(self._signals, rates, h, self.t0, self.t, p)
        self._flows = FlowFamily(L, G, AinvH, GvT, h, p, n_acc=self._n_a)
        if self._fric and self._hold:
            self._flows.slip = self._slip
        self._flows.flow((), h)  # the free step: one augmented exponential
        if self.probes is None:  # four checks per shortest period of the model
            w_max = float(np.max(np.abs(np.linalg.eigvals(L).imag), initial=0.0))
            q = math.ceil(h * w_max / (0.5 * math.pi)) if w_max > 0 else 1
            self.probes = int(min(max(q, 1), MAX_PROBES))
        self._S: tuple = ()  # held contacts
        self._warm = None
        self._work = 0.0
        # exact works and heats of the energy balance (with run(energy=True))
        self._integrals = self._Wth = self._rest = None
        held_f = self._fric and self._hold  # held contacts' tangential work and heat rest
        tang, rest = (self._T, self._rest_rows) if held_f else (None, None)
        powers = (
            np.column_stack([term.power for term in m.loads])
            if m.loads
            else np.zeros((m.n_dofs, 0))
        )
        if m.energy is not None:
            heats = [term.heat for term in m.loads]
            self._integrals = WorkIntegrals(
                self._flows, m.energy, powers, heats, GvT, tangential=tang, rest_heat=rest
            )
            self._Wth = None if m.energy.Wth is None else self._integrals.Wth
        if rest is not None:  # the heat rest moves the state: integrated in every run
            zero = np.zeros((m.n_dofs, m.n_dofs))
            forms = SimpleNamespace(Pth=zero, Wth=None, Pd=zero, heat_outflow=zero[0])
            self._rest = WorkIntegrals(
                self._flows, forms, 0 * powers, np.zeros(powers.shape[1]), rest_heat=rest
            )
        self._measure = False  # step() / iterate(): no meter to hand them to
        self._fused: dict[tuple, tuple] = {}  # (S, measure) -> whole-step matrix (_flight)
        self._probe_rows: dict[tuple, np.ndarray] = {}  # the check grids' rows (events)
        self._masks: dict[tuple, np.ndarray] = {}  # held sets as masks
        self._g0grid = None  # a fixed casing's gaps on the check grid

    # -- one step ------------------------------------------------------------------------------
    def measure_works(self, on: bool) -> None:
        """Integrate the exact works and heats of each step into its record's ``works``
        (the energy balance of a run that keeps it); the contact work always."""
        self._measure = on and self._integrals is not None

    def advance(self) -> StepRecord:
        rec = super().advance()
        if not self._measure:
            return rec._replace(works={"contact_work": self._work})
        w = self._w[METER_ORDER]  # WORK_KEYS order, the impulses' work added
        w[0] += self._work
        w[6] += self._work_t
        return rec._replace(works=dict(zip(WORK_KEYS, w)))

    def _integ(self, S):
        """The work integrals the flight of ``S`` needs: all of them with the energy balance,
        the held heat rest of sliding contacts (it moves the state), or none."""
        if self._measure:
            return self._integrals
        return self._rest if self._rest is not None and self._flows.sliding(S) else None

    def _jump(self, X, Xn) -> None:
        """A jump of the state (impulse, heat): a reduced model's expansion shapes' work."""
        if self._measure and self._Wth is not None:
            self._w[2] += float((Xn - X) @ self._Wth @ (Xn + X)) / 2

    def _step(self):
        """One step: :meth:`_one_step`, or with held slides the passes of
        :meth:`~.slide.SlideDirections._slide_passes` (the fixed point on their directions)."""
        if self._fric and self._hold:
            return self._slide_passes()
        return self._one_step()

    def _one_step(self):
        """One step: flights of the held set between located events (an impulse or a
        release at each), then the step end's releases and impulses."""
        h, t, c = self.h, self.t, self.model.contact
        b = self._loads.poly(t)
        X, S, a = self.X, self._S, 0.0
        P = np.zeros(self.model.n_contacts)
        hits = np.zeros(self.model.n_contacts, dtype=int)
        self._work = self._work_t = 0.0
        self._w = np.zeros(NQ + 2)
        if self._fric:
            self._friction_step_start()
        for n_events in range(MAX_EVENTS + 1):
            Xe, PS, rest, V, calm = self._to_step_end(S, X, a, b)
            if c is None:
                self._add(self._integrate(S, X, a, h, b) if rest is None else rest)
                return Xe, P
            ev = None
            if self.events and n_events < MAX_EVENTS and not calm:
                ev = self._event(S, X, a, Xe, b, V)
            if ev is None:
                break
            a, X, S = self._at_event(ev, S, X, a, b, P, hits)
        w = self._add(self._integrate(S, X, a, h, b) if rest is None else rest)
        X = Xe
        P[list(S)] += PS
        if self._fric:
            X = self._held_segment(S, PS, w, X)
        if S and not self.events:
            S = self._release_at_end(S, X, b)
        X, S = (X, S) if calm and self._opened else self._impact(t + h, X, S, P)
        self._S = S
        return (X, P, self._friction_extra(S)) if self._fric else (X, P)

    def _to_step_end(self, S, X, a, b):
        """The flight of ``S`` from ``(a, X)`` to the step end: ``(X(h), P_S, integrals or
        None, check grid or None, calm)`` (``calm``: a whole step whose grid shows no event)."""
        if a == 0.0:  # the whole step, its integrals and check grid in one product
            return self._flight(S, X, b)
        if self._integ(S) is not None:  # after an event: flight and integrals at once
            return (*self._integrate(S, X, a, self.h, b, state=True), None, False)
        Xe, PS = self._flows.advance(S, X, a, self.h, b, self.h / self.probes)
        return Xe, PS, None, None, False

    def _at_event(self, ev, S, X, a, b, P, hits):
        """Fly to the located event ``ev`` and act on it (a release, a stick refused, an
        impulse; a third bounce of one contact in a step ends plastically: Zeno). Returns
        the new ``(a, X, S)``; adds the held impulses to ``P``."""
        tau, kind, i, Xn, PSa = ev
        w = self._add(self._integrate(S, X, a, tau, b))
        a, X = tau, Xn
        P[list(S)] += PSa
        if self._fric:
            X = self._held_segment(S, PSa, w, X)
        if kind == "stick":
            self._refuse_stick(i, self.t + a, X)
        if kind == "release":
            return a, X, tuple(j for j in S if j != i)
        hits[i] += 1
        X, S = self._impact(self.t + a, X, S, P, forced=i, plastic=hits >= ZENO_HITS)
        return a, X, S

    def _release_at_end(self, S, X, b):
        """Without event location: releases (and stops of sliding) at the step end."""
        lam = self._flows.multiplier(S, X, self._loads.u(b, 1.0))
        S = tuple(j for j, lj in zip(S, lam) if lj > 0.0)
        for j in S:
            if not self._still_sliding(j, X):
                self._refuse_stick(j, self.t + self.h, X)
        return S

    def _add(self, w):
        """Add a flight segment's integrals (or ``None``) to the step's; return them."""
        if w is not None:
            self._w += w
        return w

    def _flight(self, S, X, b):
        """The exact flight of ``S`` over the whole step from ``X`` with the load polynomial
        ``b``, in one product of a matrix stacked once per held set (compiled,
        :func:`~.kernels.flight`): ``(X(h), P_S, integrals, V, quiet)``, the
        integrals (:meth:`~.work.WorkIntegrals.flight_matrix`) with ``run(energy=True)``
        (else ``None``), the event check grid ``V`` (:meth:`_grid_rows`, with the casing's
        gaps) when events are located and whether it shows no event (:meth:`_quiet`)."""
        key = (S, self._measure)
        q, n, nz = self.probes, self.model.n_dofs, self.model.n_dofs + len(S)
        c, integ = self.model.contact, self._integ(S)
        if key not in self._fused:
            f = self._flows.flow(S, self.h)
            act = np.zeros(0, dtype=np.int64)
            if integ is not None:
                F, act = integ.flight_matrix(S, q, self.h / q)[:2]
            else:
                F = np.hstack([f.Phi, f.Psi])
            k = F.shape[0]  # the rows past k: the check grid
            if self.events and c is not None:
                F = np.vstack([F, self._grid_rows(S, f)])
            off = self._flows.check_offsets(S) if self.events else np.zeros(0)
            act = np.asarray(act, dtype=np.int64)
            self._fused[key] = (np.ascontiguousarray(F), k, act, np.ascontiguousarray(off))
        F, k, act, off = self._fused[key]
        u = np.concatenate([X, (self._loads.T01 @ b).ravel()])
        works = np.zeros(NQ + 2)
        y, V, calm, self._opened = flight(
            F, u, k, q, self._gap_grid(), off, self._held(S), nz, act, integ is not None, works
        )
        rest = integ.expand(S, self.h / q, works) if integ is not None else None
        return y[:n], y[n:nz], rest, (V if V.size else None), calm

    def _held(self, S) -> np.ndarray:
        """Mask (n_c,) of the held set ``S`` (cached)."""
        if S not in self._masks:
            m = np.zeros(self.model.n_contacts, dtype=np.bool_)
            m[list(S)] = True
            self._masks[S] = m
        return self._masks[S]

    def _gap_grid(self) -> np.ndarray:
        """The casing's gaps ``g0`` (q + 1, n_c) at ``t + j h / q`` (constant ones once)."""
        c, q = self.model.contact, self.probes
        if c is None:
            return np.zeros((q + 1, 0))
        if callable(c.gap0):
            return np.ascontiguousarray(c.gap_at(self.t + (self.h / q) * np.arange(q + 1)))
        if self._g0grid is None:
            self._g0grid = np.ascontiguousarray(np.broadcast_to(c.gap0, (q + 1, c.n)))
        return self._g0grid

    def _integrate(self, S, X, a, tau, b, state=False):
        """The exact works and heats (6,) of the flight of ``S`` from ``(a, X)`` to ``tau``
        (:class:`~.work.WorkIntegrals`; held contacts' work included); with ``state`` also
        the flight itself, ``(X(τ), P_S, integrals)`` (composed as
        :meth:`~.flows.FlowFamily.advance`)."""
        integ = self._integ(S)
        if integ is None or (tau <= a and not state):
            return None
        z = np.concatenate([X, np.zeros(len(S)), self._flows.chain(b, a / self.h)])
        unit = self.h / self.probes
        if state:
            z, w = integ.over(S, z, tau - a, unit, state=True)
            n = self.model.n_dofs
            return z[:n], z[n : n + len(S)], w
        if a == 0.0 and tau == self.h:
            return integ.step(S, z, self.probes, unit)
        return integ.over(S, z, tau - a, unit)

    # -- impulses ------------------------------------------------------------------------------
    def _struck(self, te, X, S, forced=None, plastic=None):
        """The contacts an impulse acts on at ``te``: ``(gap rates, active, restitution)``,
        or ``None`` when no free contact touches closing (held ones in ``S`` take part with
        e = 0; ``forced`` are triggered when closing, ``plastic`` ones get e = 0)."""
        c = self.model.contact
        touch = c.gap(te, X) <= 0.0
        touch[list(S)] = False
        if forced is None and not touch.any():  # no free contact touches
            return None
        gd = c.gap_velocity(te, X)
        held = np.zeros(c.n, dtype=bool)
        held[list(S)] = True
        trigger = touch & (gd < 0.0)
        if forced is not None:
            trigger[forced] = gd[forced] < 0.0
        if not trigger.any():
            return None
        e = np.where(held, 0.0, c.restitution)
        if plastic is not None and c.restitution < 1.0:  # e = 1 has no Zeno sequence
            e[plastic] = 0.0
        return gd, trigger | held, e

    def _impact(self, te, X, S, P, forced=None, plastic=None):
        """Newton impulses at time ``te`` (shared LCP; with friction
        :meth:`~.friction.FrictionalContact._impact_friction`); update ``P`` in
        place; new held set."""
        if self._fric:
            return self._impact_friction(te, X, S, P, forced, plastic)
        hit = self._struck(te, X, S, forced, plastic)
        if hit is None:
            return X, S
        gd, active, e = hit
        c = self.model.contact
        alpha = c.alpha_at(te)
        W = self._Wm + self._Wt * alpha
        Pi = solve_impulses(W / (1.0 + e)[:, None], gd, active, self._warm)
        self._warm = Pi > 0.0
        Xn = X + (self._Zm + self._Zt * alpha) @ Pi
        self._work += float(Pi @ (c.structure_velocity(X) + c.structure_velocity(Xn))) / 2
        self._jump(X, Xn)
        P += Pi
        if not self._hold:
            return Xn, ()
        gdn = c.gap_velocity(te, Xn)
        tol = 1e-9 * max(float(np.max(np.abs(gd[active]))), 1e-300)
        keep = active & (e == 0.0) & (gdn <= tol)
        return Xn, tuple(np.flatnonzero(keep))
