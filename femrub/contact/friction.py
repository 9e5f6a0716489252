"""The per-step frictional contact problem: Signorini–Coulomb at the impulse level.

For ``n`` contacts with impulses ``P_i = (P_n, P_t1, P_t2)`` (N s; the normal one pushes the
structure away from the obstacle, the tangential ones act along the casing tangents) and
local velocities ``u_i = (u_n, u_t1, u_t2)`` that depend linearly on them through the
Delassus operator ``W`` (stepper-specific, e.g. ``Gvᵀ D⁻¹ H`` for the θ-method)::

    u = W P + q                          q: free (impulse-less) local velocities
    0 <= P_n  ⊥  u_n >= 0                 Signorini / Newton impact law (normal)
    |P_t| <= μ P_n,  P_t = −μ P_n u_t / |u_t|  when u_t ≠ 0   (Coulomb, set-valued)

Newton's impact law enters through the normal velocity: ``u_n = (u_n⁺ + e u_n⁻) / (1 + e)``
with the velocity ``u_n⁻`` at the start of the step and the restitution ``e``; the caller
gives ``u_n⁺``'s free part and ``u_n⁻``. The problem is solved exactly (never regularised)
by the semi-smooth Newton method of Alart & Curnier (1991) on::

    F_n = P_n − proj_[0, U](P_n − ρ u_n) = 0
    F_t = P_t − proj_{B(μ proj_[0, U](P_n − ρ u_n))}(P_t − ρ u_t) = 0

with an optional bound ``U`` on the normal impulse (``U = ∞`` by default; an abradable
coating yields at ``U = h F_y``, :mod:`femrub.contact.abradable`): a contact at its bound
may penetrate and its tangential impulse lies in the cone of the bounded normal impulse,
``|P_t| <= μ U``.

with per-contact ``ρ_i = 1 / ‖W_ii‖_F``, an Armijo line search on ``‖F‖²/2``, and projected
block Gauss–Seidel sweeps on the same map (then Newton again) when Newton stalls. The
converged impulses are put on the cone exactly: a sliding contact gets ``|P_t| = μ P_n``
and the direction of ``−u_t``. Without friction (``μ = 0`` everywhere) the problem is the
LCP of :func:`femrub.contact.impulses.solve_impulses`, which is used instead (exact
pivoting, and the one-contact closed form).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .coulomb import (
    MAX_HEAT_ITERATIONS,
    NON_POSITIVE,
    OPEN,
    SLIP,
    SOLVED,
    STICK,
    frictional_solve,
    newton_law,
    power_heat,
)
from .impulses import solve_impulses

__all__ = [
    "FrictionResult",
    "OPEN",
    "SLIP",
    "STICK",
    "coulomb_check",
    "coulomb_check_rows",
    "merge_coulomb_checks",
    "power_heat_fixed_point",
    "solve_frictional_contact",
]


@dataclass(frozen=True)
class FrictionResult:
    """Solution of the frictional contact problem of one step.

    Attributes
    ----------
    P : (n, 3) impulses ``(P_n, P_t1, P_t2)`` (zero on inactive contacts).
    u : (n, 3) local velocities ``W P + q`` after the step (normal ``u_n⁺``, slip ``u_t``).
    state : (n,) ``OPEN`` (0), ``STICK`` (1) or ``SLIP`` (2).
    residual : ``‖F‖_∞`` relative to the impulse scale of the problem.
    iterations : Newton iterations.
    """

    P: np.ndarray
    u: np.ndarray
    state: np.ndarray
    residual: float
    iterations: int


def _as_local(W, n):
    W = np.asarray(W, dtype=float)
    if W.shape != (3 * n, 3 * n):
        raise ValueError(f"Delassus operator must be {(3 * n, 3 * n)}, got {W.shape}")
    return np.array(W, order="C")  # writable and contiguous: one compiled signature


def _per_contact(value, n, default=0.0):
    """``value`` broadcast to a writable, contiguous (n,) float array (kernel argument)."""
    v = default if value is None else value
    return np.array(np.broadcast_to(np.asarray(v, dtype=float), (n,)), dtype=float)  # a copy


def _kernel_args(W, q, mu, active, restitution, u_before, upper):
    """``(W, q, mu, active, e, u_before, U)`` as the compiled kernels take them."""
    q = np.array(np.asarray(q, dtype=float).reshape(-1, 3), order="C")
    n = q.shape[0]
    active = np.array(np.broadcast_to(np.asarray(active, dtype=bool), (n,)))
    e, ub = _per_contact(restitution, n), _per_contact(u_before, n)
    return _as_local(W, n), q, _per_contact(mu, n), active, e, ub, _per_contact(upper, n, np.inf)


def check_status(status: int, residual: float) -> None:
    """Raise the error of a kernel's status code (:mod:`femrub.contact.coulomb`)."""
    if status == NON_POSITIVE:
        raise FloatingPointError("non-positive Delassus operator at a contact")
    if status != SOLVED:
        raise FloatingPointError(f"frictional contact not solved: residual {residual:.3g}")


def solve_frictional_contact(
    W,
    q,
    mu,
    active,
    *,
    restitution=0.0,
    u_before=None,
    warm=None,
    upper=None,
    tol: float = 1e-12,
    max_iter: int = 60,
) -> FrictionResult:
    """Impulses of the active contacts under Signorini–Coulomb with Newton's impact law.

    Parameters
    ----------
    W : (3n, 3n) Delassus operator, contact-major (rows/columns ``3 i + (n, t1, t2)``).
    q : (n, 3) free local velocities at the end of the step (normal ``u_n⁺``, slip ``u_t``).
    mu : (n,) or scalar friction coefficients.
    active : (n,) bool, the contacts that may carry an impulse.
    restitution : (n,) or scalar ``e``; the normal law acts on ``(u_n⁺ + e u_n⁻) / (1 + e)``.
    u_before : (n,) normal velocity ``u_n⁻`` at the start of the step (default 0).
    warm : (n, 3) impulses of the previous step (a start for Newton).
    upper : (n,) bound ``U`` on the normal impulses (``None``: unbounded).
    tol : convergence tolerance on the relative residual.
    max_iter : Newton iterations before the fixed-point fallback.

    Returns
    -------
    FrictionResult

    Raises
    ------
    FloatingPointError
        No solution within ``sqrt(tol)`` (non-positive Delassus block, divergence).
    """
    W, q, mu, active, e, ub, U = _kernel_args(W, q, mu, active, restitution, u_before, upper)
    n = q.shape[0]
    if active.any() and not np.any(mu[active] > 0.0):
        # frictionless: the exact LCP on the normal part (pivoting; one-contact closed form)
        idx = np.flatnonzero(active)
        Wa, qa = newton_law(W, q, e, ub, idx)
        P = np.zeros((n, 3))
        P[idx, 0] = solve_impulses(
            Wa[::3, ::3], qa[:, 0], np.ones(idx.size, dtype=bool), upper=U[idx]
        )
        u = (W @ P.reshape(-1)).reshape(n, 3) + q
        state = np.where(P[:, 0] > 0.0, SLIP, OPEN).astype(np.int8)
        return FrictionResult(P, u, state, 0.0, 0)
    use_warm = warm is not None
    w = np.zeros((n, 3)) if warm is None else np.asarray(warm, dtype=float).reshape(n, 3)
    P, u, state, res, it, status = frictional_solve(
        W, q, mu, e, ub, U, active, np.array(w, order="C"), use_warm, tol, max_iter
    )
    check_status(status, res)
    return FrictionResult(P, u, state, float(res), int(it))


def power_heat_fixed_point(  # noqa: PLR0913 (the arrays handed to the compiled kernel)
    first: FrictionResult,
    slip_before,
    heat_partition,
    W,
    q,
    W_heat,
    mu,
    active,
    *,
    restitution=0.0,
    u_before=None,
    upper=None,
    tol: float = 1e-12,
    max_iter: int = 60,
) -> tuple[FrictionResult, np.ndarray]:
    """The ``"power"`` heat of a frictional step and the solve that meets it (the fixed
    point :func:`femrub.contact.coulomb.power_heat`, the one implementation).

    Parameters
    ----------
    first : the solution of :func:`solve_frictional_contact` with ``(W, q, mu, active, …)``.
    slip_before : (n, 2) slip velocity before the step (m/s).
    heat_partition : (n,) or scalar η, the blade's share of the friction power.
    W_heat : (3n, n) the local velocities' change per unit heat of each contact (m/s/J).
    W, q, mu, active, restitution, u_before, upper, tol, max_iter : as
        :func:`solve_frictional_contact`.

    Returns
    -------
    (FrictionResult, heat) with ``heat`` (n,) the blade's heat ``η (−P_t · w_t^mid)`` (J).
    """
    W, q, mu, active, e, ub, U = _kernel_args(W, q, mu, active, restitution, u_before, upper)
    n = q.shape[0]
    P, u, state, heat, res, status = power_heat(
        np.array(first.P, dtype=float, order="C"),
        np.array(first.u, dtype=float, order="C"),
        np.array(first.state, dtype=np.int8),
        np.array(np.asarray(slip_before, dtype=float).reshape(n, 2), order="C"),
        _per_contact(heat_partition, n),
        W,
        q,
        np.array(W_heat, dtype=float, order="C"),
        mu,
        e,
        ub,
        U,
        active,
        tol,
        max_iter,
        MAX_HEAT_ITERATIONS,
    )
    check_status(status, res)
    return FrictionResult(P, u, state, max(float(res), first.residual), first.iterations), heat


#: rows of a run checked together by :func:`coulomb_check` (bounds its temporaries)
CHECK_ROWS = 65536


def coulomb_check(normal_force, friction_force, slip_velocity, state, mu) -> dict:
    """How well recorded forces satisfy Coulomb's law, over every step and contact.

    Parameters
    ----------
    normal_force : (m, n) λ (N); friction_force, slip_velocity : (m, n, 3) in global axes;
    state : (m, n) ``OPEN``/``STICK``/``SLIP``; mu : (n,).

    Returns
    -------
    dict with ``cone`` (largest ``(|λ_t| − μ λ) / (μ λ)``, <= 0 inside the cone),
    ``slip_equality`` (largest ``| |λ_t| − μ λ | / (μ λ)`` where a contact slips) and
    ``direction`` (largest ``1 + cos`` of the angle between ``λ_t`` and the slip velocity
    where a contact slips: 0 when exactly opposite). Checked :data:`CHECK_ROWS` rows at a
    time, so that a long run's check needs little memory beyond its arrays.
    """
    mu = np.asarray(mu, dtype=float)
    return merge_coulomb_checks(
        [
            coulomb_check_rows(normal_force[r], friction_force[r], slip_velocity[r], state[r], mu)
            for r in (
                slice(k, k + CHECK_ROWS) for k in range(0, max(len(normal_force), 1), CHECK_ROWS)
            )
        ]
    )


def merge_coulomb_checks(parts: list[dict]) -> dict:
    """:func:`coulomb_check` of consecutive rows from the :func:`coulomb_check_rows` of each
    block of them (maxima and sums: the same whatever the blocks)."""
    closed = [p for p in parts if p["closed"]]
    return {
        "cone": max(p["cone"] for p in closed) if closed else 0.0,
        "force_without_normal": max(p["force_without_normal"] for p in parts),
        "slip_equality": max(p["slip_equality"] for p in parts),
        "direction": max(p["direction"] for p in parts),
        "stick_steps": sum(p["stick_steps"] for p in parts),
        "slip_steps": sum(p["slip_steps"] for p in parts),
    }


def coulomb_check_rows(normal_force, friction_force, slip_velocity, state, mu) -> dict:
    """:func:`coulomb_check` on some rows, to merge with :func:`merge_coulomb_checks`
    (``closed``: whether any contact is closed)."""
    lam = np.asarray(normal_force, dtype=float)
    ft = np.linalg.norm(friction_force, axis=-1)
    bound = mu[None, :] * lam
    closed = (lam > 0.0) & (bound > 0.0)
    rel = np.where(closed, (ft - bound) / np.where(closed, bound, 1.0), 0.0)
    open_force = float(np.max(np.where(~closed, ft, 0.0), initial=0.0))
    slip = (np.asarray(state) == SLIP) & closed
    vs = np.linalg.norm(slip_velocity, axis=-1)
    slip_dir = slip & (vs > 0.0)
    cos = np.einsum("...i,...i->...", friction_force, slip_velocity) / np.where(
        slip_dir, ft * vs, 1.0
    )
    return {
        "closed": bool(closed.any()),
        "cone": float(np.max(np.where(closed, rel, -np.inf), initial=-np.inf)),
        "force_without_normal": open_force,
        "slip_equality": float(np.max(np.abs(rel[slip]), initial=0.0)),
        "direction": float(np.max(1.0 + cos[slip_dir], initial=0.0)),
        "stick_steps": int(np.sum((np.asarray(state) == STICK) & closed)),
        "slip_steps": int(np.sum(slip)),
    }
