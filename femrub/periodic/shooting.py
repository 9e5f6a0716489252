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

__all__ = ["Shooting", "ShootingResult", "state_scale"]

#: relative finite-difference step ε of Eq. (2)
FD_STEP = 1e-6
#: scaled residual ``max |R_j| / s_j`` below which an orbit is periodic
TOLERANCE = 1e-8


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
    converged : ``residual <= tolerance``.
    monodromy : ``M = ∂Φ_T/∂X0`` (N, N) at ``X0``.
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
    """

    def __init__(
        self,
        period_map: PeriodMap,
        *,
        eps: float = FD_STEP,
        tolerance: float = TOLERANCE,
        max_iterations: int = 40,
    ):
        self.map, self.eps = period_map, float(eps)
        self.tolerance, self.max_iterations = float(tolerance), int(max_iterations)
        self.layout = period_map.model.layout

    def residual(self, X0) -> np.ndarray:
        """``R(X0) = Φ_T(X0) − X0`` (N,), Eq. (1)."""
        return self.map(X0) - X0

    def monodromy(self, X0, scale, phi=None) -> np.ndarray:
        """``M`` (N, N) at ``X0`` by Eq. (2); ``phi``: ``Φ_T(X0)`` when known."""
        phi = self.map(X0) if phi is None else phi
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
        k = 0
        while r > self.tolerance and k < self.max_iterations:
            M = self.monodromy(X, s, orbit.X[-1])
            dX = np.linalg.lstsq(M - np.eye(X.size), -R, rcond=None)[0]
            X, R, r = self._damped(X, dX, r, s)
            k += 1
            if scale is None:
                s = state_scale(self.layout, np.vstack([s, self.map.orbit(X).X]))
            orbit = self.map.orbit(X)
        return ShootingResult(X, r, k, r <= self.tolerance, self.monodromy(X, s), s)

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


def _norm(R, s) -> float:
    return float(np.max(np.abs(R) / s))
