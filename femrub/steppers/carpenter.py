"""Carpenter's forward-increment Lagrange multiplier scheme (Carpenter, Taylor, Katona 1991).

Central differences with the contact multiplier and the gap taken at ``t_{n+1}``, written on
the first-order model so it runs on full and reduced models alike. With
``a(Y) = A⁻¹ (B Y + F_n)`` (``A`` factorised once; diagonal for a lumped full model)::

    v_{n+1/2} = v_{n−1/2} + h a_v(u_n, v_{n−1/2}, θ_n) + Δv(P)       central difference
    θ_{n+1}   = θ_n + h a_θ(u_n, v_{n−1/2}, θ_n) + Δθ(P)             forward Euler heat
    u_{n+1}   = u_n + h a_u(u_n, v_{n+1/2}, θ_n) + Δu(P)             (= u_n + h v_{n+1/2})

For a full model ``a_u = v``, which is the classical scheme. The velocity reported in the
state is ``v_{n+1/2}``, the one consistent with the position update: the contact force at
``t_{n+1}`` is not known when the step ends, so ``v_{n+1/2} + h/2 a_{n+1}`` would give the
tip a spurious velocity during a persistent contact. The increments ``Δ(P)`` are
linear in the impulses ``P = h λ_{n+1}``; on contacts whose predicted gap is negative the
impulse makes the gap exactly zero (projection), an LCP ``0 <= P ⊥ g_p + W_c P >= 0``
(``W_c = Gᵀ ∂X/∂P``, the ``G A⁻¹ Gᵀ`` of the model notes). The heat input ``α P`` enters the
same step.

With Coulomb friction the impulses are ``(P_n, P_t1, P_t2)`` per contact and
:func:`femrub.contact.friction.solve_frictional_contact` solves the same projection with the
Coulomb cone: the normal rows act on the predicted gap (``W_c``), the tangential rows on the
slip velocity ``Gvtᵀ X − v_c`` of ``v_{n+1/2}`` (``Gvtᵀ ∂X/∂P``). With the ``"power"`` heat
law the blade receives ``η (−P_t · w_t,m)`` after the contact solve (explicitly: unlike the
θ-method, not iterated with the contact solve).

The scheme is conditionally stable: ``h < 2 / ω_max`` for the mechanical part and
``h < 2 / μ_max`` for the explicit heat equation; :meth:`Carpenter.stability_limit` computes
both from sparse eigen-solvers, once per stepper, and ``run()`` reports
``status = "unstable"`` above it (and stops on blow-up, keeping what it computed) instead of
returning NaN.

Impacts are perfectly plastic: a restitution coefficient ``e > 0`` is refused (``ValueError``)
rather than silently ignored.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..contact.friction import solve_frictional_contact
from ..contact.impulses import solve_impulses
from ..fem.eigen import largest_modulus
from ..fem.linalg import Factorised
from .base import Stepper
from .record import Friction

__all__ = ["Carpenter"]


class Carpenter(Stepper):
    """Explicit central-difference scheme with forward-increment contact (see module doc).

    Carpenter, Taylor and Katona's scheme on the first-order model ``A Ẋ = B X + F + H λ``
    (paper Eqs. 8-9): central differences for the mechanics, forward Euler for the heat
    equation, the impulse ``P = h λ_{n+1}`` (N s) closing the predicted gap of ``t_{n+1}``.

    Parameters
    ----------
    model : :class:`~femrub.model.first_order.FirstOrderModel`.
    h : time step (s); below :meth:`stability_limit` (``2 / ω_max`` and ``2 / μ_max``, s),
        above it a run reports ``status = "unstable"``.
    t0 : start time (s).
    """

    name = "carpenter"

    def _setup(self):
        m, h, L = self.model, self.h, self.model.layout
        self._refuse_restitution()
        A = m.A.tocsc()
        self._diagA = None
        if (A - sp.diags(A.diagonal())).count_nonzero() == 0:
            self._diagA = A.diagonal()
        else:
            self._lu = Factorised(A, what="matrix A")
        self._B = m.B.tocsr()
        X = self.X
        self._a = self._deriv(X, m.load(self.t))
        self._vh = X[L.v] - 0.5 * h * self._a[L.v]  # v_{-1/2}
        self.X = X.copy()
        self.X[L.v] = self._vh
        c = m.contact
        self._friction = False
        if c is not None:
            self._Cm = self._impulse_map(c.Hm)
            self._Ct = self._impulse_map(c.Ht)
            self._Wm, self._Wt = c.GT @ self._Cm, c.GT @ self._Ct
            self._friction = c.has_friction
            if self._friction:  # normal rows on the gap, tangential rows on the slip velocity
                self._C3 = self._impulse_map(c.H3)
                rows = c.V3T.copy()
                rows[::3] = c.GT
                self._R3 = rows
                self._W3, self._W3t = rows @ self._C3, rows @ self._Ct

    def _solve(self, rhs):
        if self._diagA is not None:
            return rhs / (self._diagA if rhs.ndim == 1 else self._diagA[:, None])
        return self._lu.solve(rhs)

    def _deriv(self, Y, F):
        return self._solve(self._B @ Y + F)

    def _impulse_map(self, H):
        """State increment per unit impulse (columns), through the v- and u-updates."""
        L, h = self.model.layout, self.h
        d1 = self._solve(np.asarray(H, dtype=float))
        dv = np.zeros_like(d1)
        dv[L.v] = d1[L.v]
        out = d1.copy()
        out[L.u] += h * self._solve(self._B @ dv)[L.u]
        return out

    def _step(self):
        m, h, L = self.model, self.h, self.model.layout
        X = self.X
        Fn = m.load(self.t)
        a = self._a
        vh = self._vh + h * a[L.v]
        Y = X.copy()
        Y[L.v] = vh
        au = self._deriv(Y, Fn)
        Xp = X.copy()
        Xp[L.u] = X[L.u] + h * au[L.u]
        Xp[L.t] = X[L.t] + h * a[L.t]
        Xp[L.v] = vh
        c = m.contact
        P = np.zeros(m.n_contacts)
        if c is not None and self._friction:
            return self._contact_friction(X, Xp)
        if c is not None:
            t1 = self.t + h
            alpha = c.alpha_at(t1)
            gp = c.gap(t1, Xp)
            if np.any(gp < 0.0):
                Wc = self._Wm + self._Wt * alpha
                P = solve_impulses(Wc, gp, np.ones(c.n, dtype=bool), gp < 0.0)
                Xp = Xp + (self._Cm + self._Ct * alpha) @ P
        self._vh = Xp[L.v].copy()
        self._a = self._deriv(Xp, m.load(self.t + h))
        return Xp, P

    def _contact_friction(self, X, Xp):
        """Signorini–Coulomb projection of the step (module docstring)."""
        c, L, m = self.model.contact, self.model.layout, self.model
        t1 = self.t + self.h
        alpha = c.alpha_at(t1) if c.heat_law == "alpha" else np.zeros(c.n)
        C3, W3 = self._C3, self._W3
        if np.any(alpha):
            C3, W3 = C3.copy(), W3.copy()
            C3[:, ::3] += self._Ct * alpha
            W3[:, ::3] += self._W3t * alpha
        q = np.column_stack([c.gap(t1, Xp), c.slip_velocity(Xp)])
        res = solve_frictional_contact(W3, q, c.friction, np.ones(c.n, dtype=bool))
        P = res.P
        Xn = Xp + C3 @ P.reshape(-1)
        heat = alpha * P[:, 0]
        if c.heat_law == "power" and L.n_t:
            w_mid = 0.5 * (c.slip_velocity(X) + c.slip_velocity(Xn))
            heat = c.heat_partition * -np.einsum("ij,ij->i", P[:, 1:], w_mid)
            Xn = Xn + self._Ct @ heat
        self._vh = Xn[L.v].copy()
        self._a = self._deriv(Xn, m.load(t1))
        return Xn, P[:, 0].copy(), Friction(P[:, 1:], heat, res.state)

    def _stability_limit(self) -> float:
        """Largest stable step (s): ``min(2 / ω_max, 2 / μ_max)`` of the explicit parts."""
        m, L = self.model, self.model.layout
        A, B = m.A.tocsc(), m.B.tocsc()
        limits = []
        if L.n_u:
            mech = np.r_[np.arange(L.u.start, L.u.stop), np.arange(L.v.start, L.v.stop)]
            lam = largest_modulus(A[mech][:, mech], B[mech][:, mech])
            if lam > 0:
                limits.append(2.0 / lam)
        if L.n_t:
            th = np.arange(L.t.start, L.t.stop)
            lam = largest_modulus(A[th][:, th], B[th][:, th])
            if lam > 0:
                limits.append(2.0 / lam)
        return min(limits) if limits else math.inf
