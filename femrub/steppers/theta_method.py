"""The paper's θ-method for the Measure Differential Inclusion (Sec. 3, Eqs. 16–25).

One step from ``t_k`` to ``t_{k+1} = t_k + h`` (paper Eq. 16a, impulse ``P = h λ_{k+1}``)::

    D X_{k+1} = D X_k + h [B X_k + γ F_{k+1} + (1 − γ) F_k] + (Hm + Ht diag α) P
    D = A − h γ B                                   (constant: factorised once)

so ``X_{k+1} = X_p + Z P`` with the free prediction ``X_p`` (Eq. 17) and
``Z = D⁻¹ (Hm + Ht diag α)``. The gap velocity is ``ġ_{k+1} = ġ_p + W P`` with the Delassus
operator ``W = Gvᵀ Z`` (precomputed). On the active contacts the impulse solves Newton's
impact law in velocity form (Eqs. 21–23), an LCP::

    0 <= P  ⊥  (ġ_{k+1} + e ġ_k) / (1 + e) >= 0

which for one contact is the paper's prox formula (Eq. 25b). Active contacts:

* ``"paper"``: the gap at ``t_{k+1}`` is closed (``g_{k+1} <= 0``), iterated to a fixed point
  with the impulse (the paper's semi-smooth Newton loop, Sec. 3);
* ``"predicted"``: Moreau–Jean (Siconos) rule ``g_k + γ h ġ_k <= 0``.

The heat input ``α P`` enters the same step as the impulse. Penetration is not prevented at
the position level; it stays below ``h |ġ|`` (paper Sec. 4.3).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from .base import Stepper
from .contact_solve import solve_impulses

__all__ = ["ThetaMethod", "ACTIVATION_RULES"]

ACTIVATION_RULES = ("paper", "predicted")


class ThetaMethod(Stepper):
    """Implicit θ-method with Newton impact law (paper Sec. 3).

    Parameters
    ----------
    model : :class:`~femrub.model.FirstOrderModel`.
    h : time step (s).
    gamma : θ-method parameter γ in [1/2, 1] (1/2: trapezoidal, no numerical dissipation).
    activation : ``"paper"`` or ``"predicted"`` (see module docstring).
    """

    name = "theta"

    def __init__(self, model, h, *, gamma: float = 0.5, activation: str = "paper", t0=0.0):
        gamma = float(gamma)
        if not (0.5 <= gamma <= 1.0):
            raise ValueError(f"gamma must be in [0.5, 1] for a stable θ-method, got {gamma!r}")
        if activation not in ACTIVATION_RULES:
            raise ValueError(
                f"unknown activation rule {activation!r}; use one of {', '.join(ACTIVATION_RULES)}"
            )
        self.gamma, self.activation = gamma, activation
        super().__init__(model, h, t0=t0)

    def _setup(self):
        m, h, g = self.model, self.h, self.gamma
        D = (m.A - (h * g) * m.B).tocsc()
        try:
            self._lu = spla.splu(D)
        except RuntimeError as exc:
            raise ValueError(f"the iteration matrix D = A - h γ B is singular ({exc})") from None
        self._hB = (h * m.B).tocsr()
        self._Fk = m.load(self.t)
        c = m.contact
        if c is not None:
            self._Zm = self._solve_many(c.Hm)
            self._Zt = self._solve_many(c.Ht)
            self._Wm, self._Wt = c.Gv.T @ self._Zm, c.Gv.T @ self._Zt
        self._warm = None

    def _solve_many(self, H):
        return np.column_stack([self._lu.solve(np.ascontiguousarray(col)) for col in H.T])

    def _step(self):
        m, h, g = self.model, self.h, self.gamma
        t1 = self.t + h
        F1 = m.load(t1)
        Xk = self.X
        rhs = self._hB @ Xk + h * (g * F1 + (1.0 - g) * self._Fk)
        Xp = Xk + self._lu.solve(rhs)
        self._Fk = F1
        c = m.contact
        if c is None:
            return Xp, np.zeros(0)
        alpha = c.alpha_at(t1)
        Z = self._Zm + self._Zt * alpha
        W = self._Wm + self._Wt * alpha
        e = c.restitution
        gdot_k = c.Gv.T @ Xk
        gdot_p = c.Gv.T @ Xp
        q = (gdot_p + e * gdot_k) / (1.0 + e)
        Wn = W / (1.0 + e)
        if self.activation == "predicted":
            gap_k = c.gap_at(self.t) + c.G.T @ Xk
            active = gap_k + g * h * gdot_k <= 0.0
            P = solve_impulses(Wn, q, active, self._warm)
        else:
            gap0 = c.gap_at(t1)
            gap_p = gap0 + c.G.T @ Xp
            GZ = c.G.T @ Z
            active = gap_p <= 0.0
            P = np.zeros(c.n)
            for _ in range(2 * c.n + 2):
                P = solve_impulses(Wn, q, active, self._warm)
                new = (gap_p + GZ @ P <= 0.0) | (P > 0.0)
                if np.array_equal(new, active):
                    break
                active = new
        self._warm = P > 0.0
        return Xp + Z @ P, P
