"""The paper's θ-method for the Measure Differential Inclusion (Sec. 3, Eqs. 16–25).

One step from ``t_k`` to ``t_{k+1} = t_k + h`` (paper Eq. 16a, impulse ``P = h λ_{k+1}``)::

    D X_{k+1} = D X_k + h [B X_k + Γ F_{k+1} + (I − Γ) F_k] + (Hm + Ht diag α) P
    D = A − h Γ B                                   (constant: factorised once)

with ``Γ = γ I`` as in the paper, or ``γ`` on the mechanical rows and ``γ_θ`` on the heat
rows (``gamma_thermal``).

so ``X_{k+1} = X_p + Z P`` with the free prediction ``X_p`` (Eq. 17) and
``Z = D⁻¹ (Hm + Ht diag α)``. The gap velocity is ``ġ_{k+1} = ġ_p + W P`` with the Delassus
operator ``W = Gvᵀ Z`` (precomputed). On the active contacts the impulse solves Newton's
impact law in velocity form (Eqs. 21–23), an LCP::

    0 <= P  ⊥  (ġ_{k+1} + e ġ_k) / (1 + e) >= 0

which for one contact is the paper's prox formula (Eq. 25b). Which contacts take an impulse
and under which law (Newton's law, capped or not, midpoint law on separating contacts) is
the activation rule of :mod:`femrub.contact.activation`; the default ``"position"`` never
pushes at an open gap and never creates energy.

The heat input ``α P`` enters the same step as the impulse. Penetration is not prevented at
the position level; it stays below ``h |ġ|`` (paper Sec. 4.3).

**Coulomb friction** (a contact with tangents and ``μ > 0``): the impulse of a contact is
``(P_n, P_t1, P_t2)``, ``X_{k+1} = X_p + Z₃ P`` with ``Z₃ = D⁻¹ [Hm, Hmt]``, and the local
velocities ``(ġ_{k+1}, w_{t,k+1})`` (gap velocity, slip velocity relative to the casing
surface) are affine in ``P`` through the Delassus operator ``W₃ = [Gv, Gvt]ᵀ Z₃``. Each step
solves Signorini–Coulomb with Newton's law exactly
(:func:`femrub.contact.friction.solve_frictional_contact`) on the contacts the activation
rule chooses: ``"paper"`` (the default with friction) or ``"predicted"``, the rules with a
frictional form; the position-level and free-step rules are refused with friction.
With the ``"power"`` heat law the blade then receives ``η (−P_t · w_t,m)`` per contact, with
``w_t,m`` the slip velocity at the mid-step state (the value the energy balance uses), as a
heat input of the same step; its effect on the step's velocities through the thermal
coupling is fed back into the contact solve by a fixed point (contact solve, heat, contact
solve with the heat's velocity shift ``W_θ Q``, ...) until the heat repeats to 1e-12.

Three step paths, as the physics needs: frictionless contacts (the activation rule's
LCPs), frictional contacts (the compiled active-set fixed point with the Coulomb solve and
the ``"power"`` heat fixed point), and the compiled blocks. ``run()`` on a dense model
advances whole chunks of steps in one compiled call (:mod:`femrub.steppers.theta_blocks`):
the same step, the same contact algebra, written into the recorder's rows; with frictional
contacts this includes the ``"power"`` heat fixed point above and an abradable coating's
wear map (:mod:`femrub.contact.rub_block`); one frictionless contact on a fixed obstacle
takes the closed-form impulse of the one-contact block, which ``step()`` runs as a block of
one step. Casing heat, a time-dependent α, frictionless contacts beyond the one-contact
case and sparse models go step by step, as do ``step()`` and ``iterate()``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..contact.activation import (
    RULES,
    compile_kernels,
    frictional_fixed_point,
    impulses,
    rule_code,
    rule_for,
)
from ..contact.friction import FrictionResult, check_status, power_heat_fixed_point
from ..contact.theta_block import ONE_RULES, one_contact_block
from ..fem.linalg import Factorised, compact
from .base import Stepper
from .record import Friction
from .theta_blocks import advance_block, prepare

__all__ = ["ThetaMethod", "ACTIVATION_RULES", "OneContactStep"]

ACTIVATION_RULES = RULES


@dataclass(frozen=True)
class OneContactStep:
    """The closed-form step of one frictionless contact on a dense model: the free step
    ``X_p = T X_k + …``, the impulse enters as ``X_{k+1} = X_p + P z``; the gap is
    ``g0 + gr · X`` (m) and the gap velocity ``gv · X`` (m/s); ``w = gv · z`` and
    ``gz = gr · z`` are the contact's compliances to its impulse; ``e`` the restitution."""

    T: np.ndarray
    z: np.ndarray
    w: float
    gv: np.ndarray
    gr: np.ndarray
    g0: float
    e: float
    gz: float


class ThetaMethod(Stepper):
    """Implicit θ-method with Newton impact law (paper Sec. 3).

    Parameters
    ----------
    model : :class:`~femrub.model.first_order.FirstOrderModel`.
    h : time step (s).
    gamma : θ-method parameter γ in [1/2, 1] (1/2: trapezoidal, no numerical dissipation).
    gamma_thermal : γ of the heat-equation rows (default: ``gamma``). The trapezoidal rule is
        not L-stable: on a stiff heat equation (fine elements at the tip, large
        conductivity) its stiff thermal modes ring from step to step, and through the
        coupling and the frictional heat this can drive a spurious runaway. 1 (backward
        Euler on the heat rows) damps them while the mechanics stays trapezoidal.
    activation : one of :data:`femrub.contact.activation.RULES`; ``None`` (default):
        ``"position"``, or ``"paper"`` with friction. With friction only the rules of
        :data:`~femrub.contact.activation.FRICTIONAL_RULES` have a frictional form (the
        others raise a one-line ``ValueError``).
    """

    name = "theta"
    supports_wear = True
    restartable = True
    #: ``run()`` advances dense models in compiled blocks of steps where
    #: :func:`~femrub.steppers.theta_blocks.block_kind` allows (``False``: step by step,
    #: same results)
    block_steps = True

    def __init__(
        self,
        model,
        h,
        *,
        gamma: float = 0.5,
        gamma_thermal: float | None = None,
        activation: str | None = None,
        t0=0.0,
    ):
        gamma = float(gamma)
        gamma_t = gamma if gamma_thermal is None else float(gamma_thermal)
        for name, val in (("gamma", gamma), ("gamma_thermal", gamma_t)):
            if not (0.5 <= val <= 1.0):
                raise ValueError(f"{name} must be in [0.5, 1] for a stable θ-method, got {val!r}")
        c = getattr(model, "contact", None)
        activation = rule_for(activation, c is not None and c.has_friction)
        self.gamma, self.gamma_thermal, self.activation = gamma, gamma_t, activation
        super().__init__(model, h, t0=t0)

    def _setup(self):
        m, h = self.model, self.h
        gam = np.full(m.n_dofs, self.gamma)
        gam[m.layout.t] = self.gamma_thermal  # Γ: per-row θ-method parameter
        D = (m.A - h * (sp.diags(gam) @ m.B)).tocsc()
        self._lu = Factorised(D, what="iteration matrix D = A - h Γ B")
        hB = (h * m.B).tocsc()
        if self._lu.dense:  # amplification matrix: X_p = T X_k + Y1 s_{k+1} + Y0 s_k
            self._T = np.eye(m.n_dofs) + self._lu.solve(hB.toarray())
        else:
            self._hB = compact(hB)
        self._signals = [term.signal for term in m.loads]
        F = (
            np.column_stack([term.vector for term in m.loads])
            if m.loads
            else np.zeros((m.n_dofs, 0))
        )
        self._hF1, self._hF0 = h * gam[:, None] * F, h * (1.0 - gam)[:, None] * F
        self._Y1 = self._Y0 = None
        if self._lu.dense and F.shape[1]:
            self._Y1, self._Y0 = self._lu.solve(self._hF1), self._lu.solve(self._hF0)
        self._sk = self._signal_values(self.t)
        c = m.contact
        self._fast = False
        if c is not None:
            self._Zm = self._lu.solve(c.Hm)
            self._Zt = self._lu.solve(c.Ht)
            self._Wm, self._Wt = c.GvT @ self._Zm, c.GvT @ self._Zt
            # one contact, constant gap and α, fixed obstacle, dense: the closed-form impulse
            # of the compiled one-contact block, also for step() (a block of one step), with
            # Contact.gap and gap_velocity written out for that contact
            if (
                c.n == 1
                and self._lu.dense
                and not callable(c.gap0)
                and not callable(c.heat_coefficient)
                and c.gap_rate is None
                and not c.has_friction
                and c.wear is None
                and c.casing_heat is None
            ):
                a = c.heat_coefficient
                self._fast = True
                self._z = (self._Zm + self._Zt * a)[:, 0].copy()
                self._w = float((self._Wm + self._Wt * a)[0, 0])
                self._gv, self._gr = c.GvT[0].copy(), c.GT[0].copy()
                self._g0, self._e = float(c.gap0[0]), float(c.restitution)
                self._gz = float(self._gr @ self._z)
                if self._w <= 0.0 or self._gz <= 0.0:
                    raise ValueError("non-positive Delassus operator at the contact")
        self._warm = None
        self._friction = c is not None and c.has_friction
        if self._friction:
            self._Z3 = self._lu.solve(c.H3)
            self._W3 = c.V3T @ self._Z3
            self._W3t = c.V3T @ self._Zt  # heat columns seen by the local velocities
            self._GZ3 = c.GT @ self._Z3
            self._GZt = c.GT @ self._Zt
            self._warm3 = None
            # arguments of the compiled contact step, contiguous and writable once
            self._rule3 = rule_code(self.activation)
            self._mu3 = np.array(np.broadcast_to(c.friction, (c.n,)), dtype=float)
            self._e3 = np.array(np.broadcast_to(c.restitution, (c.n,)), dtype=float)
            self._U3 = np.full(c.n, np.inf)
            self._warm0 = np.zeros((c.n, 3))
            compile_kernels(("friction",))  # not in the first step's time
            # gap and local velocity rows in one product: [g, ġ, w_t] = S X + casing terms
            self._S = np.vstack([c.GT, c.V3T])
            self._memo = (None, 0.0, None)
            self._n3 = c.n
        prepare(self)

    @property
    def one_contact(self) -> OneContactStep | None:
        """The operators of the one-contact closed-form step, or ``None`` when this stepper
        does not take it (several contacts, friction, a sparse model, …)."""
        if not self._fast:
            return None
        return OneContactStep(
            self._T, self._z, self._w, self._gv, self._gr, self._g0, self._e, self._gz
        )

    def _restart(self):
        self._sk = self._signal_values(self.t)
        self._warm = None
        if self._friction:
            self._warm3 = None
            self._memo = (None, 0.0, None)

    def block_writer(self):
        if not (self.block_steps and self._block_kind):
            return None
        return lambda *rows: advance_block(self, *rows)

    def _casing(self, k: int, t: float):
        """Casing terms of ``[g, ġ, w_t] = S X + o(t)`` at step ``k``: ``o = (g0(t), then
        per contact ġ0(t), −v_c)`` (4n,). Each time is asked for twice (as ``t_{k+1}``, then
        as ``t_k``); the last one is kept."""
        memo = self._memo
        if memo[0] != k or abs(memo[1] - t) > 1e-9 * self.h:
            c = self.model.contact
            n = c.n
            o = np.empty(4 * n)
            o[:n] = c.gap_at(t)
            loc = o[n:].reshape(n, 3)
            loc[:, 0] = c.rate_at(t)
            loc[:, 1:] = -c.casing_velocity
            self._memo = memo = (k, t, o)
        return memo[2]

    def _local(self, k: int, t: float, X):
        """Gap (n,), gap velocity (n,) and ``(ġ, w_t)`` (n, 3) of the state ``X`` at step ``k``."""
        n = self._n3
        y = self._S @ X
        y += self._casing(k, t)
        loc = y[n:].reshape(n, 3)
        return y[:n], loc[:, 0].copy(), loc

    def _signal_values(self, t):
        return np.array([float(sig(t)) for sig in self._signals])

    def _step(self):
        t1 = self.t + self.h
        s1 = self._signal_values(t1)
        s0, self._sk = self._sk, s1
        if self._fast:
            return self._step_one(s0, s1)
        Xk = self.X
        if self._lu.dense:
            Xp = self._T @ Xk
            if self._Y1 is not None:
                Xp += self._Y1 @ s1 + self._Y0 @ s0
        else:
            Xp = Xk + self._lu.solve(self._hB @ Xk + self._hF1 @ s1 + self._hF0 @ s0)
        if self.model.contact is None:
            return Xp, np.zeros(0)
        if self._friction:
            return self._step_friction(Xk, Xp, t1)
        return self._step_frictionless(Xk, Xp, t1)

    def _step_one(self, s0, s1):
        """One contact (see ``_setup``): a block of one step of the compiled block path
        (:func:`~femrub.contact.theta_block.one_contact_block`, the impulse in closed form)."""
        X, P = np.empty((1, self.model.n_dofs)), np.empty((1, 1))
        sig = np.vstack([s0, s1])[:, : self._bns]
        one_contact_block(
            self.X,
            self._bT,
            self._bY1,
            self._bY0,
            sig,
            ONE_RULES[self.activation],
            self._g0,
            self._gr,
            self._gv,
            self._z,
            self._w,
            self._gz,
            self._e,
            self.h,
            self.gamma,
            np.inf,
            X,
            P,
        )
        return X[0], P[0]

    def _step_frictionless(self, Xk, Xp, t1):
        """Frictionless contacts: the impulses of the activation rule (LCPs)."""
        c, h = self.model.contact, self.h
        alpha = c.alpha_at(t1)
        Z = self._Zm + self._Zt * alpha
        W = self._Wm + self._Wt * alpha
        g_k, g_p = c.gap(self.t, Xk), c.gap(t1, Xp)
        P = impulses(
            self.activation,
            g_k,
            c.gap_velocity(self.t, Xk),
            g_p,
            c.gap_velocity(t1, Xp),
            W,
            c.GT @ Z,
            np.broadcast_to(np.asarray(c.restitution, dtype=float), (c.n,)),
            h,
            self.gamma,
            self._warm,
            upper=c.impulse_cap(t1, h, g_k, g_p),
        )
        self._warm = P > 0.0
        return Xp + Z @ P, P

    def _step_friction(self, Xk, Xp, t1):
        """Signorini–Coulomb step: the compiled active-set fixed point
        (``contact.activation.frictional_fixed_point``) in one call."""
        c, h = self.model.contact, self.h
        n = c.n
        alpha = c.alpha_at(t1) if c.heat_law == "alpha" else np.zeros(n)
        Z, W, GZ = self._Z3, self._W3, self._GZ3
        if np.any(alpha):  # α λ heat enters with the normal impulse
            Z, W, GZ = Z.copy(), W.copy(), GZ.copy()
            Z[:, ::3] += self._Zt * alpha
            W[:, ::3] += self._W3t * alpha
            GZ[:, ::3] += self._GZt * alpha
        gap_k, gdot_k, _ = self._local(self.k, self.t, Xk)
        gap_p, _, q = self._local(self.k + 1, t1, Xp)
        e = np.where(gdot_k > 0.0, 1.0, self._e3)
        upper = c.impulse_cap(t1, h, gap_k, gap_p)
        U = self._U3 if upper is None else np.array(upper, dtype=float)  # writable, C
        use_warm = self._warm3 is not None
        warm = self._warm3 if use_warm else self._warm0
        active, P, u, state, res_, it, status = frictional_fixed_point(
            self._rule3,
            gap_k,
            gdot_k,
            gap_p,
            GZ,
            W,
            q,
            self._mu3,
            e,
            gdot_k,
            U,
            warm,
            use_warm,
            h,
            self.gamma,
            1e-12,
            60,
        )
        check_status(status, res_)
        heat = alpha * P[:, 0]  # the α λ heat is already in Z's normal columns
        power = c.heat_law == "power" and self.model.layout.n_t > 0
        if power:  # the heat moves the step's velocities: fixed point with the solve
            first = FrictionResult(P, u, state, res_, 0)
            res, heat = power_heat_fixed_point(
                first,
                c.slip_velocity(Xk),
                c.heat_partition,
                W,
                q,
                self._W3t,
                c.friction,
                active,
                restitution=e,
                u_before=gdot_k,
                upper=upper,
            )
            P, state = res.P, res.state
        self._warm3 = P
        X = Xp + Z @ P.reshape(-1) if active.any() else Xp
        if power:
            X = X + self._Zt @ heat
        return X, P[:, 0].copy(), Friction(P[:, 1:], heat, state)
