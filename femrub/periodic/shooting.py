"""Shooting: periodic orbits as fixed points of the period map, by a damped Newton method.

The orbit through ``X0`` is periodic when the shooting residual vanishes::

    R(X0, p) = Φ_T(X0; p) − X0 = 0                                   (1)

with ``Φ_T`` the θ-method's period map (:class:`~femrub.periodic.period.PeriodMap`). Newton's
method solves (1) with the Jacobian ``R_X = M − I``, where the monodromy matrix
``M = ∂Φ_T/∂X0`` is the product of the step Jacobians where the stepper has them (one
frictionless contact: :mod:`femrub.periodic.sensitivity`), else is built by one-sided finite
differences, column by column::

    M e_j ≈ (Φ_T(X0 + δ_j e_j) − Φ_T(X0)) / δ_j,   δ_j = ε (s_j + |X0_j|)   (2)

``s_j`` (:func:`state_scale`) is the size of the orbit in the block of ``X`` that holds
coordinate ``j`` (displacements in m, velocities in m/s, temperatures in K), so each
difference moves the orbit by the same relative amount. A column that crosses a contact
switch inside the period (an impact that appears or vanishes) carries that switch into
``M``: the finite differences see the nonsmooth map as it is, which analytic
sensitivities of the step on a fixed contact set would not. Each Newton step is damped
(halved until the scaled residual decreases, Armijo's rule), which keeps the iteration
inside one contact regime when a full step would jump across a grazing orbit.

Eq. (2) costs one period per coordinate (on a compiled period map the columns run on
:data:`~femrub.fem.quadrature.THREADS` threads, each with its own copy of the stepper), so
Newton takes it only at its first iteration and when the residual stops falling, and
updates ``R_X`` in between by Broyden's rank-one formula (Eq. 3, :class:`Broyden`).

The eigenvalues of ``M`` at the solution are the orbit's Floquet multipliers
(:mod:`femrub.periodic.floquet`).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..fem.quadrature import THREADS
from .period import PeriodMap
from .sensitivity import step_monodromy

__all__ = [
    "Broyden",
    "Shooting",
    "ShootingResult",
    "checked_differences",
    "differences",
    "stalled",
    "state_scale",
]

#: relative finite-difference step ε of Eq. (2)
FD_STEP = 1e-6
#: the monodromy of the Floquet multipliers checks each column of Eq. (2) against ε / 10,
#: down to ε / 10**CHECK_LEVELS, until two agree to CHECK_TOLERANCE (scaled, relative):
#: below ε ≈ 1e-8 the columns' rounding (the contact solves' included) grows as 1/ε and
#: passes 1e-3 on reduced Rotor 37
CHECK_LEVELS = 2
CHECK_TOLERANCE = 1e-3
#: scaled residual ``max |R_j| / s_j`` below which an orbit is periodic
TOLERANCE = 1e-8
#: scaled residual accepted when Newton stalls: the period map is only piecewise continuous
#: (an impact moved by one step jumps it by ``O(h |ġ|)``), so an exact fixed point may not
#: exist; the orbit then closes to this fraction of its size
STALL_TOLERANCE = 1e-3
#: residual ratio of a Newton step on a Broyden-updated ``R_X`` above which the next step
#: takes finite differences again (Eq. 3): an update that no longer lowers the residual by
#: 10 %; on a nonsmooth map fresh differences do hardly better for 100 times the cost
RENEW = 0.9


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
        step has them (the orbit's Floquet multipliers: :mod:`femrub.periodic.sensitivity`);
        ``None`` when not asked for.
    scale : the scale ``s`` (N,) of the orbit.
    unsettled : columns of a finite-difference ``monodromy`` that depend on the step
        (:func:`checked_differences`): its multipliers are uncertain when above 0.
    """

    X0: np.ndarray
    residual: float
    iterations: int
    converged: bool
    monodromy: np.ndarray | None
    scale: np.ndarray
    unsettled: int = 0


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

    @property
    def exact(self) -> bool:
        """Whether the monodromy comes from the step Jacobians (cheap: one pass over the
        orbit) rather than from Eq. (2) (one period per column)."""
        return self.derivatives == "auto" and self.map.stepper.one_contact is not None

    def monodromy(self, X0, scale, orbit=None, saltation=False) -> np.ndarray:
        """``M`` (N, N) at ``X0``: the product of the step Jacobians on the orbit's contact set
        where the step has them (:func:`~femrub.periodic.sensitivity.step_monodromy`, with
        ``derivatives="auto"``; ``saltation``: with its impact-time terms), else Eq. (2);
        ``orbit``: the orbit from ``X0`` when known."""
        orbit = self.map.orbit(X0) if orbit is None else orbit
        if self.exact:
            return step_monodromy(self.map.stepper, orbit, saltation)
        return differences(self.map, X0, orbit.X[-1], self.eps * (scale + np.abs(X0)))

    def floquet_monodromy(self, X0, scale, orbit=None) -> tuple[np.ndarray, int]:
        """``(M, unsettled)``: the monodromy of the Floquet multipliers at ``X0``: the step
        Jacobians with their impact-time terms where the step has them (``unsettled = 0``),
        else Eq. (2) checked column by column (:func:`checked_differences`)."""
        orbit = self.map.orbit(X0) if orbit is None else orbit
        if self.exact:
            return self.monodromy(X0, scale, orbit, saltation=True), 0
        delta = self.eps * (scale + np.abs(X0))
        return checked_differences(self.map, X0, orbit.X[-1], delta, scale)

    def _residual_jacobian(self, X0, scale, orbit) -> np.ndarray:
        """``R_X = M − I`` at ``X0`` (Newton's matrix of Eq. 1)."""
        return self.monodromy(X0, scale, orbit) - np.eye(X0.size)

    def solve(self, X0, scale=None, monodromy: bool = True) -> ShootingResult:
        """Newton's method on Eq. (1) from ``X0`` (module docstring); ``monodromy``: return
        the orbit's ``M`` with its impact-time terms (else ``ShootingResult.monodromy`` is
        ``None``)."""
        X = np.array(X0, dtype=float)
        orbit = self.map.orbit(X)
        s = state_scale(self.layout, orbit.X) if scale is None else scale
        R = orbit.X[-1] - X
        r = _norm(R, s)
        k, history = 0, [r]
        jacobian = Broyden(self._residual_jacobian, self.exact)
        while r > self.tolerance and k < self.max_iterations:
            if self.stalled(history) and not jacobian.renew():
                break
            J = jacobian.at(X, s, orbit)
            dX = np.linalg.lstsq(J, -R, rcond=None)[0]
            Xn, Rn, rn = self._damped(X, dX, r, s)
            jacobian.update(Xn - X, Rn - R, rn / r, s)
            X, R, r = Xn, Rn, rn
            k += 1
            history.append(r)
            if scale is None:
                s = state_scale(self.layout, np.vstack([s, self.map.orbit(X).X]))
            orbit = self.map.orbit(X)
        ok = r <= self.tolerance or self.stalled(history)
        M, unsettled = self.floquet_monodromy(X, s) if monodromy else (None, 0)
        return ShootingResult(X, r, k, ok, M, s, unsettled)

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


class Broyden:
    """A Jacobian taken by ``take(*args)`` and, between two takes, updated by Broyden's
    rank-one formula with the weights ``w = 1 / scale²`` of the unknowns (Dennis & Schnabel
    1996, Sec. 8.1)::

        J ← J + (ΔR − J Δx) (w Δx)ᵀ / (Δxᵀ (w Δx))                        (3)

    for Newton's method on Eq. (1) (:meth:`Shooting.solve`, the orbit's scale ``s``) and
    for the bordered corrections of a branch (:mod:`femrub.periodic.continuation`, scaled
    unknowns, ``w = 1``). An ``exact`` Jacobian (the step Jacobians: cheap) is taken anew
    at every step; one from finite differences (Eq. 2, one period per column) is taken anew
    when a step does not lower the residual by 10 % (:data:`RENEW`), or when Newton stalls
    on an updated matrix (:meth:`renew`).

    Parameters
    ----------
    take : callable returning a fresh Jacobian from the arguments of :meth:`at`.
    exact : whether ``take`` gives exact derivatives cheaply (then no update).
    J : a Jacobian to start from (e.g. the previous branch point's), or ``None``.
    """

    def __init__(self, take, exact: bool, J=None):
        self.take, self.exact = take, bool(exact)
        self.J = None if self.exact else J
        self.fresh = False

    def at(self, *args) -> np.ndarray:
        """The current Jacobian (taken anew when there is none)."""
        if self.J is None:
            self.J, self.fresh = self.take(*args), True
        return self.J

    def update(self, dx, dR, ratio: float, scale=1.0) -> None:
        """Eq. (3) after a step ``dx`` that changed the residual by ``dR`` and multiplied
        its norm by ``ratio``, with the weights ``w = 1 / scale²``; the next :meth:`at`
        takes a fresh one when the update is not worth it."""
        if self.J is None or self.exact or ratio > RENEW:
            self.J = None
            return
        w = dx / scale**2
        self.J = self.J + np.outer(dR - self.J @ dx, w) / max(float(dx @ w), 1e-300)
        self.fresh = False

    def renew(self) -> bool:
        """Whether a stall may be an updated matrix's: then the next one is taken anew."""
        if self.exact or self.fresh:
            return False
        self.J = None
        return True


def differences(period_map: PeriodMap, X0, image, delta, columns=None) -> np.ndarray:
    """Eq. (2): the columns ``columns`` (default all) of ``M`` (N, len(columns)),
    ``image = Φ_T(X0)``, ``delta`` (N,) the steps; the columns are shared among
    :data:`THREADS` copies of a compiled period map."""
    js = np.arange(X0.size) if columns is None else np.asarray(columns)
    M = np.empty((X0.size, js.size))
    maps = period_map.copies(THREADS if period_map.compiled and js.size > 1 else 1)

    def fill(job):
        pm, ks = job
        for k in ks:
            j = js[k]
            Xj = X0.copy()
            Xj[j] += delta[j]
            M[:, k] = (pm(Xj) - image) / delta[j]

    jobs = list(zip(maps, np.array_split(np.arange(js.size), len(maps))))
    if len(jobs) == 1:
        fill(jobs[0])
    else:
        with ThreadPoolExecutor(len(jobs)) as pool:
            list(pool.map(fill, jobs))
    return M


def checked_differences(period_map: PeriodMap, X0, image, delta, scale) -> tuple:
    """Eq. (2) with each column checked against a ten times smaller step: ``(M, unsettled)``.

    A perturbation that switches a contact inside the period (stick to slip, an impact one
    step earlier) gives a column of size ``jump / δ``, not a derivative: on reduced Rotor 37
    (16 frictional contacts) the largest multiplier of one orbit is 1.165 at ε = 1e-8 and
    1e-7 but 49 at ε = 1e-6, where one column of 176 crosses a switch. A column is kept
    when it agrees with the column of ``δ / 10`` to :data:`CHECK_TOLERANCE` (scaled by
    ``s``, relative to the column's largest entry or 1); the others are taken again at
    ``δ / 10``, down to :data:`CHECK_LEVELS` times.
    ``unsettled`` counts the columns that never agree (the map switches within every
    step tried): the multipliers are then uncertain.
    """
    M = differences(period_map, X0, image, delta)
    left = np.arange(X0.size)
    for _ in range(CHECK_LEVELS):
        delta = delta / 10.0
        finer = differences(period_map, X0, image, delta, left)
        coarse = M[:, left]
        size = np.maximum(np.abs(finer * scale[left] / scale[:, None]).max(axis=0), 1.0)
        gap = np.abs((finer - coarse) * scale[left] / scale[:, None]).max(axis=0)
        M[:, left] = finer
        left = left[gap > CHECK_TOLERANCE * size]
        if not left.size:
            break
    return M, int(left.size)


def stalled(history: list, limit: float) -> bool:
    """Newton, below ``limit``, has not decreased the residual by 10 % in three iterations
    (``history``: the scaled residuals so far)."""
    return len(history) > 3 and history[-1] <= limit and history[-1] > 0.9 * min(history[-4:-1])


def _norm(R, s) -> float:
    return float(np.max(np.abs(R) / s))
