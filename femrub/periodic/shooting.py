"""Shooting: periodic orbits as fixed points of the period map, by a damped Newton method.

The orbit through ``X0`` is periodic when the shooting residual vanishes::

    R(X0, p) = Φ_T(X0; p) − X0 = 0                                   (1)

with ``Φ_T`` the θ-method's period map (:class:`~femrub.periodic.period.PeriodMap`). Newton's
method solves (1) with the Jacobian ``R_X = M − I``, where the monodromy matrix
``M = ∂Φ_T/∂X0`` is built by one-sided finite differences, column by column::

    M e_j ≈ (Φ_T(X0 + δ_j e_j) − Φ_T(X0)) / δ_j,   δ_j = ε s_j           (2)

``s_j`` (:func:`state_scale`) is the size of the orbit in the block of ``X`` that holds
coordinate ``j`` (displacements in m, velocities in m/s, temperatures in K), so each
difference moves the orbit by the same relative amount. A column that crosses a contact
switch inside the period (an impact that appears or vanishes) carries that switch into
``M``: the finite differences see the nonsmooth map as it is, which analytic
sensitivities of the step on a fixed contact set would not. Each Newton step is damped
(halved until the scaled residual decreases, Armijo's rule), which keeps the iteration
inside one contact regime when a full step would jump across a grazing orbit.

The eigenvalues of ``M`` at the solution are the orbit's Floquet multipliers
(:mod:`femrub.periodic.floquet`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .period import PeriodMap
from .sensitivity import step_monodromy

__all__ = ["Shooting", "ShootingResult", "stalled", "state_scale"]

#: relative finite-difference step ε of Eq. (2)
FD_STEP = 1e-6
#: scaled residual ``max |R_j| / s_j`` below which an orbit is periodic
TOLERANCE = 1e-8
#: scaled residual accepted when Newton stalls: the period map is only piecewise continuous
#: (an impact moved by one step jumps it by ``O(h |ġ|)``), so an exact fixed point may not
#: exist; the orbit then closes to this fraction of its size
STALL_TOLERANCE = 1e-3


def state_scale(layout, X: np.ndarray) -> np.ndarray:
    """Per-coordinate scale ``s`` (N,) of the states ``X`` (m, N): the largest magnitude over
    the rows in each block ``u``, ``v``, ``θ`` of :class:`~femrub.model.first_order.Layout`
    (a block at rest takes ``1e-9`` times the largest block's scale, or 1 for a state at
    rest)."""
    X = np.atleast_2d(X)
    s = np.empty(X.shape[1])
    blocks = [b for b in (layout.u, layout.v, layout.t) if b.stop > b.start]
    sizes = np.array([np.abs(X[:, b]).max() for b in blocks])
    top = sizes.max() if sizes.size and sizes.max() > 0.0 else 1.0
    for b, size in zip(blocks, sizes):
        s[b] = max(size, 1e-9 * top)
    return s


@dataclass(frozen=True)
class ShootingResult:
    """An orbit found by :meth:`Shooting.solve`.

    Attributes
    ----------
    X0 : the orbit's state at ``t0`` (N,).
    residual : scaled residual ``max_j |R_j| / s_j`` of Eq. (1) at ``X0``.
    iterations : Newton iterations.
    converged : ``residual <= tolerance``, or Newton stalled (no 10 % decrease in three
        iterations) below ``stall_tolerance``.
    monodromy : ``M = ∂Φ_T/∂X0`` (N, N) at ``X0``, with the impact-time terms where the
        step has them (the orbit's Floquet multipliers: :mod:`femrub.periodic.sensitivity`).
    scale : the scale ``s`` (N,) of the orbit.
    """

    X0: np.ndarray
    residual: float
    iterations: int
    converged: bool
    monodromy: np.ndarray
    scale: np.ndarray


class Shooting:
    """Eq. (1) on the period map of ``model`` (module docstring).

    Parameters
    ----------
    period_map : :class:`~femrub.periodic.period.PeriodMap`.
    eps : ε of Eq. (2).
    tolerance : scaled residual of a converged orbit.
    max_iterations : Newton iterations before giving up.
    stall_tolerance : scaled residual accepted when Newton stalls (:data:`STALL_TOLERANCE`).
    derivatives : ``"auto"``: the step Jacobians' product where the step has them (one
        frictionless contact on a dense model), finite differences otherwise; ``"fd"``:
        finite differences always.
    """

    def __init__(
        self,
        period_map: PeriodMap,
        *,
        eps: float = FD_STEP,
        tolerance: float = TOLERANCE,
        max_iterations: int = 40,
        derivatives: str = "auto",
        stall_tolerance: float = STALL_TOLERANCE,
    ):
        if derivatives not in ("auto", "fd"):
            raise ValueError(f"derivatives must be 'auto' or 'fd', got {derivatives!r}")
        self.derivatives = derivatives
        self.map, self.eps = period_map, float(eps)
        self.tolerance, self.max_iterations = float(tolerance), int(max_iterations)
        self.stall_tolerance = max(float(stall_tolerance), self.tolerance)
        self.layout = period_map.model.layout

    def residual(self, X0) -> np.ndarray:
        """``R(X0) = Φ_T(X0) − X0`` (N,), Eq. (1)."""
        return self.map(X0) - X0

    def monodromy(self, X0, scale, orbit=None, saltation=False) -> np.ndarray:
        """``M`` (N, N) at ``X0``: the product of the step Jacobians on the orbit's contact set
        where the step has them (:func:`~femrub.periodic.sensitivity.step_monodromy`, with
        ``derivatives="auto"``; ``saltation``: with its impact-time terms), else Eq. (2);
        ``orbit``: the orbit from ``X0`` when known."""
        orbit = self.map.orbit(X0) if orbit is None else orbit
        if self.derivatives == "auto":
            M = step_monodromy(self.map.stepper, orbit, saltation)
            if M is not None:
                return M
        phi = orbit.X[-1]
        delta = self.eps * (scale + np.abs(X0))
        M = np.empty((X0.size, X0.size))
        for j in range(X0.size):  # the columns of Eq. (2), one period each
            Xj = X0.copy()
            Xj[j] += delta[j]
            M[:, j] = (self.map(Xj) - phi) / delta[j]
        return M

    def solve(self, X0, scale=None) -> ShootingResult:
        """Newton's method on Eq. (1) from ``X0`` (module docstring)."""
        X = np.array(X0, dtype=float)
        orbit = self.map.orbit(X)
        s = state_scale(self.layout, orbit.X) if scale is None else scale
        R = orbit.X[-1] - X
        r = _norm(R, s)
        k, history = 0, [r]
        while r > self.tolerance and k < self.max_iterations:
            if self.stalled(history):
                break
            M = self.monodromy(X, s, orbit)
            dX = np.linalg.lstsq(M - np.eye(X.size), -R, rcond=None)[0]
            X, R, r = self._damped(X, dX, r, s)
            k += 1
            history.append(r)
            if scale is None:
                s = state_scale(self.layout, np.vstack([s, self.map.orbit(X).X]))
            orbit = self.map.orbit(X)
        ok = r <= self.tolerance or self.stalled(history)
        return ShootingResult(X, r, k, ok, self.monodromy(X, s, saltation=True), s)

    def stalled(self, history: list) -> bool:
        """:func:`stalled` below ``stall_tolerance``."""
        return stalled(history, self.stall_tolerance)

    def _damped(self, X, dX, r, s):
        """The Newton step ``dX`` halved until the scaled residual decreases (Armijo); else
        the best of the tries."""
        alpha, best = 1.0, None
        for _ in range(8):
            Xn = X + alpha * dX
            alpha *= 0.5
            try:
                Rn = self.residual(Xn)
            except (ValueError, FloatingPointError):  # a blow-up: a shorter step
                continue
            rn = _norm(Rn, s)
            if rn <= (1.0 - 2e-4 * alpha) * r:
                return Xn, Rn, rn
            if best is None or rn < best[2]:
                best = (Xn, Rn, rn)
        if best is None:
            raise FloatingPointError("every damped Newton step left the model's domain")
        return best


def stalled(history: list, limit: float) -> bool:
    """Newton, below ``limit``, has not decreased the residual by 10 % in three iterations
    (``history``: the scaled residuals so far)."""
    return len(history) > 3 and history[-1] <= limit and history[-1] > 0.9 * min(history[-4:-1])


def _norm(R, s) -> float:
    return float(np.max(np.abs(R) / s))
