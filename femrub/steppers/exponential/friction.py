"""Coulomb friction of the exponential stepper: frictional impulses and sliding held contacts.

**Impulses.** At an event (or a step end) the impulses ``(P_n, P_t1, P_t2)`` of the touching,
approaching contacts and of the held ones solve Signorini–Coulomb with Newton's impact law,
with the θ-method's shared solve (:func:`femrub.contact.friction.solve_frictional_contact`,
compiled kernels of :mod:`femrub.contact.coulomb`): the local velocities
``u = (ġ, w_t)`` jump by ``W₃ P`` with ``W₃ = V₃ᵀ A⁻¹ H₃`` (``H₃ = [Hm, Hmt]`` per contact,
``V₃ = [Gv, Gvt]``), the free velocity is the pre-impact one ``u⁻`` and::

    0 <= P_n  ⊥  (ġ⁺ + e ġ⁻) / (1 + e) >= 0,    |P_t| <= μ P_n,
    P_t = −μ P_n w_t⁺ / |w_t⁺|  when w_t⁺ ≠ 0

The blade's heat of the impulse is ``α P_n`` (heat law ``"alpha"``: ``α`` on the normal
columns of ``W₃``) or ``η (−P_t · (w_t⁻ + w_t⁺) / 2)`` (``"power"``: the work of the
tangential impulse on the slip velocity, exact for an impulse); with the latter a heat that
moves the velocities (``V₃ᵀ A⁻¹ Ht ≠ 0``) is fed back into the solve by the θ-method's fixed
point (:func:`femrub.contact.friction.power_heat_fixed_point`, one implementation). Work of
the impulse on the structure: ``P · V₃ᵀ (X⁻ + X⁺) / 2`` (normal and tangential).

**Held contacts slide along their slip, one direction per step.** A held contact (closed,
``ġ = 0``) with ``μ > 0`` slides against a casing moving at ``v_c``. Over a flight its friction
force is ``λ_t = −μ λ ŝ`` along a unit direction ``ŝ`` that is constant over the step, so the
held contact's force column ``H = Hm − μ Hmt ŝ + Ht α_h`` is constant and its flow stays linear
and exact (:class:`~.flows.FlowFamily`). ``ŝ`` is the direction of the slip
``w_t = Gvtᵀ X − v_c`` at the end of the step's held flight, found by a fixed point over the
step (:mod:`~.slide`: the step is repeated from its start until the direction it
was flown with is its end slip's, up to an angle quantum), so that the recorded friction
impulse of the step is opposite to the end slip as Coulomb's law wants; the casing's direction
``−v_c / |v_c|`` is where the first hold starts. The slip along ``ŝ``,
``σ = ŝ · w_t = R_σ X + σ0``, is checked with the held multipliers; its first zero (stick or
reversal) is located as an event and the run is refused there
(:class:`~femrub.steppers.record.StepRefused`: status ``failed`` with a message, the results
up to the step before kept): a sticking contact would need
a held stick (a tangential constraint) that this stepper does not have, and velocity-level
impulses alone let a pressed contact sink by ``g̈ h² / 2`` per step. For the same reason an
impulse that would start a hold (``e = 0``) and leaves the contact sticking is refused, and so
is a contact with ``μ > 0`` on a casing at rest (``v_c = 0``: no direction to start from),
when the model is built.

**Heat of held contacts.** ``"alpha"``: ``α λ`` in the flow (``α_h = α``). ``"power"``: the
heat rate ``η μ λ σ = η μ σ0 λ + η μ λ R_σ X``; its first part is in the flow
(``α_h = η μ σ0``), the second is quadratic in the state and is integrated exactly on the
flight (:class:`~.work.WorkIntegrals`, ``held_friction_heat``) and put into the blade at the
end of the flight segment (``A⁻¹ Ht`` times it, split over the sliding held contacts in
proportion to their linear heat), so the heat entering the blade is ``η`` times the friction
work ``∫ −λ_t · w_t dt`` exactly and the heat balance closes. The tangential work
``∫ λ_t · Gvtᵀ X dt`` of held contacts is integrated exactly too (``tangential_work``).
"""

from __future__ import annotations

import numpy as np

from ...contact.friction import (
    OPEN,
    SLIP,
    STICK,
    power_heat_fixed_point,
    solve_frictional_contact,
)
from ..record import Friction, StepRefused
from .slide import SlideDirections

__all__ = ["FrictionalContact"]


class FrictionalContact(SlideDirections):
    """Coulomb friction of :class:`~femrub.steppers.exponential.ExponentialMoreau` (mixin:
    it reads the stepper's model and sets the friction operators; see module docstring)."""

    _fric = False

    def _friction_setup(self, lu) -> None:
        """Operators of the frictional impulses and of sliding held contacts (``_fric``)."""
        c = self.model.contact
        self._fric = c is not None and c.has_friction
        if not self._fric:
            return
        n, N = c.n, self.model.n_dofs
        law = c.heat_law
        self._power = law == "power" and self.model.layout.n_t > 0  # η × friction work
        self._Z3 = np.asarray(lu.solve(c.H3))
        self._W3 = c.V3T @ self._Z3
        self._W3t = c.V3T @ self._Zt  # heat columns seen by the local velocities
        self._mu = np.array(c.friction, dtype=float)
        self._eta = np.array(c.heat_partition, dtype=float)
        speed = np.linalg.norm(c.casing_velocity, axis=1)
        self._dir = np.zeros((n, 2))
        moving = speed > 0.0
        self._dir[moving] = -c.casing_velocity[moving] / speed[moving, None]  # ŝ
        rest = np.flatnonzero((self._mu > 0.0) & ~moving)
        if rest.size:
            raise ValueError(
                f"the exponential stepper starts held slides along the casing's velocity; "
                f"contact {c.names[rest[0]]!r} has friction μ = {self._mu[rest[0]]:g} on a "
                "casing at rest (no slip direction): use scheme.name = 'theta' or "
                "contact.friction = 0"
            )
        # held slides: slip along ŝ σ_i = R_σ,i X + σ0_i, tangential work rate λ_i T_i X,
        # "power" heat rate α_h,i λ_i + λ_i (rest rows) X, column A⁻¹ H (arrays updated in place
        # by _set_direction: the flows and integrals hold them)
        self._Zmt = np.asarray(lu.solve(c.Hmt))
        self._speed, self._sliding = speed, self._mu > 0.0
        self._slip = (np.zeros((n, N)), np.zeros(n), self._sliding)
        self._T = np.zeros((n, N))
        self._rest_rows = np.zeros((n, N)) if self._power else None
        if self._power:
            self._alpha_h = np.zeros(n)
        elif law == "power":  # no thermal field: no heat
            self._alpha_h = np.zeros(n)
        else:
            self._alpha_h = None if callable(c.heat_coefficient) else c.heat_coefficient
        self._AinvH = None
        self._slide_setup()
        self._warm3 = None

    def _held_columns(self, lu):
        """``A⁻¹ H`` of held contacts: ``H = Hm − μ Hmt ŝ + Ht α_h`` (``None``: no hold)."""
        return self._AinvH

    def _friction_step_start(self) -> None:
        n = self.model.n_contacts
        self._Pt = np.zeros((n, 2))
        self._heat = np.zeros(n)
        self._seen = np.zeros((2, n), dtype=bool)  # a stick, a slip in this step
        self._work_t = 0.0
        self._slid = set()  # contacts with a held flight in this step

    def _friction_extra(self, S) -> Friction:
        """The step's friction impulse, blade heat and contact state."""
        seen = self._seen
        seen[1, list(S)] = True
        state = np.where(seen[0], STICK, np.where(seen[1], SLIP, OPEN)).astype(np.int8)
        return Friction(self._Pt, self._heat, state)

    def _still_sliding(self, j: int, X) -> bool:
        """Held contact ``j`` still slides along ``ŝ`` at ``X`` (true without friction)."""
        R, off, sliding = self._slip
        return not sliding[j] or float(R[j] @ X) + off[j] > 0.0

    def _held_segment(self, S, PS, w, X):
        """A flight of held set ``S``: its friction impulses ``−μ ŝ P_S`` and heats, and with
        the ``"power"`` law its heat rest ``w[5]`` put into the blade at the segment end."""
        if not S or not PS.size:
            return X
        idx = list(S)
        self._Pt[idx] += -(self._mu[idx] * PS)[:, None] * self._dir[idx]
        if self._target is not None:  # the state at the end of the held flight
            for i in idx:
                self._target[int(i)] = X
                self._slid.add(int(i))
        lin = self._alpha_h[idx] * PS
        self._heat[idx] += lin
        if self._power and w is not None and w[5] != 0.0:
            share = lin / lin.sum() if lin.sum() > 0.0 else np.full(len(idx), 1.0 / len(idx))
            rest = np.zeros(self.model.n_contacts)
            rest[idx] = w[5] * share
            self._heat += rest
            Xn = X + self._Zt @ rest
            self._jump(X, Xn)
            return Xn
        return X

    def _impact_friction(self, te, X, S, P, forced=None, plastic=None):
        """Signorini–Coulomb impulses with Newton's law at ``te`` (see module docstring);
        update ``P`` and the step's friction quantities; return the state and held set."""
        hit = self._struck(te, X, S, forced, plastic)
        if hit is None:
            return X, S
        gd, active, e = hit
        c = self.model.contact
        power = c.heat_law == "power"
        alpha = np.zeros(c.n) if power else np.asarray(c.alpha_at(te), dtype=float)
        W = self._W3
        if np.any(alpha):  # α P_n heat enters with the normal impulse
            W = W.copy()
            W[:, ::3] += self._W3t * alpha
        w_before = c.slip_velocity(X)
        q = np.column_stack([gd, w_before])
        res = solve_frictional_contact(
            W, q, self._mu, active, restitution=e, u_before=gd, warm=self._warm3
        )
        heat = alpha * res.P[:, 0]
        if self._power:  # η (−P_t · w_mid), fed back into the solve when it moves velocities
            res, heat = power_heat_fixed_point(
                res,
                w_before,
                self._eta,
                W,
                q,
                self._W3t,
                self._mu,
                active,
                restitution=e,
                u_before=gd,
            )
        Pi = res.P
        Xn = X + self._Z3 @ Pi.reshape(-1) + self._Zt @ heat
        v = c.V3T @ (X + Xn) / 2  # mean local structure velocity of the impulse
        self._work += float(Pi[:, 0] @ v[::3])
        self._work_t += float(Pi[:, 1:].reshape(-1) @ v.reshape(c.n, 3)[:, 1:].reshape(-1))
        self._jump(X, Xn)
        self._warm3 = Pi
        P += Pi[:, 0]
        self._Pt += Pi[:, 1:]
        self._heat += heat
        self._seen[0] |= active & (res.state == STICK)
        self._seen[1] |= active & (res.state == SLIP)
        if not self._hold:
            return Xn, ()
        gdn = c.gap_velocity(te, Xn)
        tol = 1e-9 * max(float(np.max(np.abs(gd[active]))), 1e-300)
        keep = active & (e == 0.0) & (gdn <= tol)
        w = c.slip_velocity(Xn)
        self._start_slides([i for i in np.flatnonzero(keep & self._sliding) if i not in S], Xn)
        ws = np.einsum("ij,ij->i", self._dir, w)
        slides = (self._mu == 0.0) | ((res.state != STICK) & (ws > 0.0))
        if np.any(keep & ~slides):
            self._refuse_stick(int(np.argmax(keep & ~slides)), te, Xn)
        return Xn, tuple(np.flatnonzero(keep))

    def _refuse_stick(self, i: int, te: float, X) -> None:
        """A held (or to be held) contact stops sliding along its direction ``ŝ``."""
        c = self.model.contact
        sigma = float(self._dir[i] @ c.slip_velocity(X)[i])
        raise StepRefused(
            f"contact {c.names[i]!r} stops sliding at t = {te:.9g} s (slip {sigma:.3g} m/s "
            "along its sliding direction): the exponential stepper holds "
            "sliding contacts only, not sticking ones; use scheme.name = 'theta'"
        )
