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

from .impulses import solve_impulses

__all__ = ["FrictionResult", "OPEN", "SLIP", "STICK", "coulomb_check", "solve_frictional_contact"]

OPEN, STICK, SLIP = 0, 1, 2


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
    return W


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
    q = np.asarray(q, dtype=float).reshape(-1, 3)
    n = q.shape[0]
    W = _as_local(W, n)
    P = np.zeros((n, 3))
    idx = np.flatnonzero(active)
    if idx.size == 0:  # nothing to solve (most steps of a rub): no set-up
        return FrictionResult(P, q.copy(), np.zeros(n, dtype=np.int8), 0.0, 0)
    mu = np.broadcast_to(np.asarray(mu, dtype=float), (n,))
    e = np.broadcast_to(np.asarray(restitution, dtype=float), (n,))
    ub = np.zeros(n) if u_before is None else np.asarray(u_before, dtype=float)
    U = np.full(n, np.inf) if upper is None else np.broadcast_to(np.asarray(upper, float), (n,))
    # Newton's law: scale the normal rows by 1 / (1 + e) and shift by e u_n⁻ / (1 + e)
    s = np.ones((n, 3))
    s[:, 0] = 1.0 / (1.0 + e)
    shift = np.zeros((n, 3))
    shift[:, 0] = e * ub / (1.0 + e)
    Wl = W * s.reshape(-1)[:, None]
    ql = q * s + shift
    rows = (3 * idx[:, None] + np.arange(3)).ravel()
    Wa, qa, mua = Wl[np.ix_(rows, rows)], ql[idx], mu[idx]
    slide = np.zeros(idx.size, dtype=bool)
    if not np.any(mua > 0.0):  # frictionless: the exact LCP on the normal part
        Pn = solve_impulses(Wa[::3, ::3], qa[:, 0], np.ones(idx.size, dtype=bool), upper=U[idx])
        Pa = np.zeros((idx.size, 3))
        Pa[:, 0] = Pn
        res, it = 0.0, 0
    else:
        w0 = None if warm is None else np.asarray(warm, dtype=float).reshape(-1, 3)[idx]
        Pa, slide, res, it = _alart_curnier(Wa, qa, mua, U[idx], w0, tol, max_iter)
    P[idx] = Pa
    u = (W @ P.reshape(-1)).reshape(n, 3) + q
    state = np.zeros(n, dtype=np.int8)
    closed = P[:, 0] > 0.0
    state[closed] = STICK
    sliding = np.zeros(n, dtype=bool)
    sliding[idx] = slide
    state[closed & (sliding | (mu == 0.0))] = SLIP
    return FrictionResult(P, u, state, res, it)


def _blocks(W, m):
    """Diagonal 3x3 blocks ``W_ii`` (m, 3, 3)."""
    r = np.arange(m)
    return W.reshape(m, 3, m, 3)[r, :, r, :]


def _residual(P, W, q, mu, rho, U):
    """Alart–Curnier function ``F(P)`` (m, 3) and the quantities its Jacobian needs."""
    u = (W @ P.reshape(-1)).reshape(-1, 3) + q
    a = P[:, 0] - rho * u[:, 0]
    pn = np.clip(a, 0.0, U)
    pos = (a > 0.0) & (a < U)  # where the projected normal impulse follows a
    r = mu * pn
    x = P[:, 1:] - rho[:, None] * u[:, 1:]
    nx = np.hypot(x[:, 0], x[:, 1])
    slip = nx > r
    F = np.empty_like(P)
    F[:, 0] = P[:, 0] - pn
    scale = np.where(slip, r / np.where(nx > 0.0, nx, 1.0), 1.0)
    F[:, 1:] = P[:, 1:] - scale[:, None] * x
    return F, (u, pos, r, x, nx, slip)


#: ``(W, ρ, ρ W, I − ρ W)`` of the last :func:`_jacobian` call: constant over the Newton
#: iterations of a solve (checked by identity; holding W and ρ keeps their ids unique)
_LAST_DA: list = [None]


def _jacobian(W, mu, rho, aux):
    """An element of the generalised Jacobian of :func:`_residual` (3m, 3m).

    With ``dA = I − ρ W`` (rows contact-major): normal rows ``ρ W_n`` where ``a > 0``, else
    ``e_n``; stick rows ``e_t − dA_t = ρ W_t``; slip rows
    ``e_t − x̂ (μ [a > 0] dA_n) − (r / |x|) (I − x̂ x̂ᵀ) dA_t``.
    """
    u, pos, r, x, nx, slip = aux
    m = pos.size
    last = _LAST_DA[0]
    if last is None or last[0] is not W or last[1] is not rho:
        rW = np.repeat(rho, 3)[:, None] * W
        _LAST_DA[0] = last = (W, rho, rW, np.eye(3 * m) - rW)
    dA = last[3].reshape(m, 3, 3 * m)
    J = last[2].reshape(m, 3, 3 * m).copy()
    off = np.flatnonzero(~pos)
    if off.size:  # F_n = P_n
        J[off, 0] = 0.0
        J[off, 0, 3 * off] = 1.0
    k = np.flatnonzero(slip)
    if k.size:
        xh = x[k] / nx[k, None]
        proj = np.eye(2)[None] - xh[:, :, None] * xh[:, None, :]  # (s, 2, 2)
        dr = np.where(pos[k, None], mu[k, None] * dA[k, 0], 0.0)  # (s, 3m)
        Jk = -xh[:, :, None] * dr[:, None, :] - (r[k] / nx[k])[:, None, None] * np.einsum(
            "sab,sbj->saj", proj, dA[k, 1:]
        )
        Jk[np.arange(k.size)[:, None], np.arange(2), 3 * k[:, None] + np.arange(1, 3)] += 1.0
        J[k, 1:] = Jk
    return J.reshape(3 * m, 3 * m)


def _on_cone(P, u, mu, rho, U):
    """Exact cone membership; sliding contacts get ``|P_t| = μ P_n`` along ``P_t − ρ u_t``.

    Returns the impulses and the mask of sliding contacts.
    """
    P = P.copy()
    P[:, 0] = np.clip(P[:, 0], 0.0, U)
    bound = mu * P[:, 0]
    x = P[:, 1:] - rho[:, None] * u[:, 1:]
    nx = np.hypot(x[:, 0], x[:, 1])
    slide = (nx > bound) & (P[:, 0] > 0.0)
    P[slide, 1:] = (bound[slide] / nx[slide])[:, None] * x[slide]
    nt = np.hypot(P[:, 1], P[:, 2])
    over = ~slide & (nt > bound)
    if over.any():
        P[over, 1:] *= (bound[over] / nt[over])[:, None]
    return P, slide


def _newton(P, W, q, mu, rho, U, tol, max_iter):
    """Semi-smooth Newton with Armijo line search on ``‖F‖²/2``; stops when it stalls."""
    m = q.shape[0]
    F, aux = _residual(P, W, q, mu, rho, U)
    merit = 0.5 * np.sum(F**2)
    it = 0
    for it in range(1, max_iter + 1):
        if np.max(np.abs(F)) <= tol:
            break
        J = _jacobian(W, mu, rho, aux)
        try:
            d = np.linalg.solve(J, -F.reshape(-1)).reshape(m, 3)
        except np.linalg.LinAlgError:
            break
        t = 1.0
        while True:
            Fn, auxn = _residual(P + t * d, W, q, mu, rho, U)
            mn = 0.5 * np.sum(Fn**2)
            if mn <= (1.0 - 1e-4 * t) * merit:
                break
            t *= 0.5
            if t < 1e-8:
                return P, F, aux, it
        P, F, aux, merit = P + t * d, Fn, auxn, mn
    return P, F, aux, it


def _gauss_seidel(P, W, q, mu, rho, U, tol, sweeps=5000):
    """Projected block Gauss–Seidel on the Alart–Curnier map (robust, linear convergence)."""
    P = P.copy()
    m = q.shape[0]
    Wr = W.reshape(m, 3, 3 * m)
    for _ in range(sweeps):
        P0 = P.copy()
        for i in range(m):
            u = Wr[i] @ P.reshape(-1) + q[i]
            pn = min(max(0.0, P[i, 0] - rho[i] * u[0]), U[i])
            x = P[i, 1:] - rho[i] * u[1:]
            nx = np.linalg.norm(x)
            r = mu[i] * pn
            P[i] = (pn, *(x if nx <= r else x * (r / nx)))
        if np.max(np.abs(P - P0)) <= tol:
            break
    return P


def _alart_curnier(W, q, mu, U, warm, tol, max_iter):
    m = q.shape[0]
    Wd = _blocks(W, m)
    norm = np.sqrt(np.einsum("mij,mij->m", Wd, Wd))  # Frobenius: no SVD per step
    if np.any(~(norm > 0.0)) or np.any(Wd[:, 0, 0] <= 0.0):
        raise FloatingPointError("non-positive Delassus operator at a contact")
    rho = 1.0 / norm
    scale = max(float(np.max(np.abs(rho[:, None] * q))), 1e-300)
    P = np.zeros((m, 3)) if warm is None else warm.copy()
    if warm is not None:  # a cold start when the warm one is worse
        F0 = _residual(np.zeros((m, 3)), W, q, mu, rho, U)[0]
        Fw = _residual(P, W, q, mu, rho, U)[0]
        if np.sum(Fw**2) > np.sum(F0**2):
            P = np.zeros((m, 3))
    P, F, aux, it = _newton(P, W, q, mu, rho, U, tol * scale, max_iter)
    if np.max(np.abs(F)) > tol * scale:  # Newton stalled: Gauss-Seidel sweeps, then Newton
        P = _gauss_seidel(P, W, q, mu, rho, U, tol * scale)
        P, F, aux, it2 = _newton(P, W, q, mu, rho, U, tol * scale, max_iter)
        it += it2
    res = float(np.max(np.abs(F)) / scale)
    if not res <= np.sqrt(tol):
        raise FloatingPointError(f"frictional contact not solved: residual {res:.3g}")
    P, slide = _on_cone(P, aux[0], mu, rho, U)
    return P, slide, res, it


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
    where a contact slips: 0 when exactly opposite).
    """
    lam = np.asarray(normal_force, dtype=float)
    ft = np.linalg.norm(friction_force, axis=-1)
    bound = np.asarray(mu, dtype=float)[None, :] * lam
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
        "cone": float(np.max(np.where(closed, rel, -np.inf), initial=-np.inf))
        if closed.any()
        else 0.0,
        "force_without_normal": open_force,
        "slip_equality": float(np.max(np.abs(rel[slip]), initial=0.0)),
        "direction": float(np.max(1.0 + cos[slip_dir], initial=0.0)),
        "stick_steps": int(np.sum((np.asarray(state) == STICK) & closed)),
        "slip_steps": int(np.sum(slip)),
    }
