"""Compiled kernels of the Signorini–Coulomb impulse problem (the one implementation).

The problem and its Alart–Curnier form are stated in :mod:`femrub.contact.friction`; this
module holds the arithmetic, written in the numba-compatible subset of Python (loops over
contacts, no Python objects) and compiled by :func:`femrub.contact.jit.njit`. Every
frictional solve of femrub goes through :func:`frictional_solve`
(:func:`femrub.contact.friction.solve_frictional_contact` and the compiled active-set fixed
point :func:`femrub.contact.activation.frictional_fixed_point` of the θ-method), so there is
no second copy of the algebra; with ``NUMBA_DISABLE_JIT=1`` the same functions run as
Python. Every compiled function of the frictional step lives in this one file: numba's
on-disk cache is invalidated by the source file of the function it compiled, not by the
files of the functions that one calls.

Local rows are contact-major: index ``3 i + (n, t1, t2)``. With ``dA = I − ρ W`` the
Alart–Curnier function and an element of its generalised Jacobian are::

    F_n = P_n − proj_[0, U](a),  a = P_n − ρ u_n        ∂F_n = ρ W_n  (0 < a < U), else e_n
    F_t = P_t − proj_B(μ proj(a))(x),  x = P_t − ρ u_t
        stick (|x| <= r):  ∂F_t = ρ W_t
        slip:              ∂F_t = e_t − x̂ (μ [0 < a < U] dA_n) − (r / |x|) (I − x̂ x̂ᵀ) dA_t

Status codes returned by the kernels: :data:`SOLVED`, :data:`NOT_SOLVED` (residual above
``sqrt(tol)``), :data:`NON_POSITIVE` (a diagonal Delassus block is not positive).
"""

from __future__ import annotations

import math

import numpy as np

from .jit import njit

__all__ = [
    "SOLVED",
    "NOT_SOLVED",
    "NON_POSITIVE",
    "OPEN",
    "STICK",
    "SLIP",
    "FIXED_POINT",
    "PREDICTED",
    "frictional_fixed_point",
    "frictional_solve",
    "power_heat",
    "MAX_HEAT_ITERATIONS",
    "alart_curnier",
    "newton_law",
]

SOLVED, NOT_SOLVED, NON_POSITIVE = 0, 1, 2
OPEN, STICK, SLIP = 0, 1, 2


@njit
def newton_law(W, q, e, ub, idx):
    """``(W_a, q_a)`` of the contacts ``idx``, Newton's impact law folded into their rows.

    ``u_n = (u_n⁺ + e u_n⁻) / (1 + e)``: the normal rows of ``W`` and ``q`` (n, 3) scaled by
    ``1 / (1 + e)``, ``q_n`` shifted by ``e u_n⁻ / (1 + e)``; rows and columns of the other
    contacts dropped.
    """
    ma = idx.size
    Wa = np.empty((3 * ma, 3 * ma))
    qa = np.empty((ma, 3))
    for a in range(ma):
        i = idx[a]
        s = 1.0 / (1.0 + e[i])
        for c in range(3):
            sc = s if c == 0 else 1.0
            qa[a, c] = q[i, c] * sc
            for b in range(ma):
                for d in range(3):
                    Wa[3 * a + c, 3 * b + d] = W[3 * i + c, 3 * idx[b] + d] * sc
        qa[a, 0] += e[i] * ub[i] * s
    return Wa, qa


@njit
def _residual(P, W, q, mu, rho, U):
    """Alart–Curnier function ``F(P)`` (m, 3) and what its Jacobian needs."""
    m = q.shape[0]
    F, u, x = np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 2))
    pos, slip = np.empty(m, dtype=np.bool_), np.empty(m, dtype=np.bool_)
    r, nx = np.empty(m), np.empty(m)
    _residual_into(P, W, q, mu, rho, U, F, u, pos, r, x, nx, slip)
    return F, u, pos, r, x, nx, slip


@njit
def _residual_into(P, W, q, mu, rho, U, F, u, pos, r, x, nx, slip):
    """:func:`_residual` written into ``F, u, pos, r, x, nx, slip`` (every entry)."""
    m = q.shape[0]
    for i in range(m):  # u = W P + q, by hand: a BLAS call costs more at this size
        for c in range(3):
            s = 0.0
            for j in range(3 * m):
                s += W[3 * i + c, j] * P[j // 3, j % 3]
            u[i, c] = q[i, c] + s
    for i in range(m):
        a = P[i, 0] - rho[i] * u[i, 0]
        pn = min(max(a, 0.0), U[i])
        pos[i] = a > 0.0 and a < U[i]  # where the projected normal impulse follows a
        r[i] = mu[i] * pn
        x0 = P[i, 1] - rho[i] * u[i, 1]
        x1 = P[i, 2] - rho[i] * u[i, 2]
        x[i, 0], x[i, 1] = x0, x1
        nx[i] = math.hypot(x0, x1)
        slip[i] = nx[i] > r[i]
        s = r[i] / nx[i] if slip[i] else 1.0
        F[i, 0] = P[i, 0] - pn
        F[i, 1] = P[i, 1] - s * x0
        F[i, 2] = P[i, 2] - s * x1


@njit
def _jacobian_into(J, rW, mu, pos, r, x, nx, slip):
    """An element of the generalised Jacobian of :func:`_residual` (3m, 3m) written into
    ``J``; ``ρ W`` given, ``dA = I − ρ W``."""
    m = pos.size
    J[:, :] = rW
    for i in range(m):
        if not pos[i]:  # F_n = P_n
            J[3 * i, :] = 0.0
            J[3 * i, 3 * i] = 1.0
        if slip[i]:
            xh0, xh1 = x[i, 0] / nx[i], x[i, 1] / nx[i]
            c = r[i] / nx[i]
            p00, p01, p11 = 1.0 - xh0 * xh0, -xh0 * xh1, 1.0 - xh1 * xh1
            for j in range(3 * m):
                dr = mu[i] * ((j == 3 * i) - rW[3 * i, j]) if pos[i] else 0.0
                a1 = (j == 3 * i + 1) - rW[3 * i + 1, j]
                a2 = (j == 3 * i + 2) - rW[3 * i + 2, j]
                J[3 * i + 1, j] = -xh0 * dr - c * (p00 * a1 + p01 * a2)
                J[3 * i + 2, j] = -xh1 * dr - c * (p01 * a1 + p11 * a2)
            J[3 * i + 1, 3 * i + 1] += 1.0
            J[3 * i + 2, 3 * i + 2] += 1.0


#: largest Newton system solved by the in-kernel elimination (above it: LAPACK)
SMALL_SYSTEM = 36


@njit
def _eliminate(M, x):
    """Forward elimination with partial pivoting of ``M x = b`` in place (``x`` holds
    ``b``): ``M`` upper triangular on return; ``False`` for a singular ``M``."""
    n = x.size
    for k in range(n):
        p, big = k, abs(M[k, k])
        for i in range(k + 1, n):
            if abs(M[i, k]) > big:
                p, big = i, abs(M[i, k])
        if not big > 0.0:
            return False
        if p != k:
            for j in range(k, n):
                M[k, j], M[p, j] = M[p, j], M[k, j]
            x[k], x[p] = x[p], x[k]
        for i in range(k + 1, n):
            f = M[i, k] / M[k, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    M[i, j] -= f * M[k, j]
                x[i] -= f * x[k]
    return True


@njit
def _solve(J, b):
    """``(J⁻¹ b, ok)``, ``J`` and ``b`` overwritten (the caller's fresh arrays): Gaussian
    elimination with partial pivoting for small systems (a LAPACK call costs more than the
    arithmetic there), ``numpy.linalg.solve`` above :data:`SMALL_SYSTEM` unknowns; ``ok``
    is False for a singular ``J``."""
    n = b.size
    if n > SMALL_SYSTEM:
        try:
            return np.linalg.solve(J, b), True
        except Exception:  # singular (numba raises a plain exception)
            return b, False
    if not _eliminate(J, b):
        return b, False
    for k in range(n - 1, -1, -1):  # back substitution
        s = b[k]
        for j in range(k + 1, n):
            s -= J[k, j] * b[j]
        b[k] = s / J[k, k]
    return b, True


@njit
def _max_abs(F) -> float:
    """``max |F|`` as ``numpy.max(numpy.abs(F))`` gives it, NaN included (no temporary)."""
    big = 0.0
    for i in range(F.shape[0]):
        for c in range(F.shape[1]):
            a = abs(F[i, c])
            if a > big:
                big = a
            elif a != a:  # NaN: the maximum is NaN
                return a
    return big


@njit
def _half_square(F) -> float:
    """``‖F‖² / 2`` summed in the order of the entries."""
    s = 0.0
    for i in range(F.shape[0]):
        for c in range(F.shape[1]):
            s += F[i, c] ** 2
    return 0.5 * s


@njit
def _newton(P, W, rW, q, mu, rho, U, tol, max_iter, at_P):
    """Semi-smooth Newton with Armijo line search on ``‖F‖²/2``; stops when it stalls.
    ``at_P``: :func:`_residual` at ``P`` (the caller has it). The iterate and a trial point
    live in two sets of arrays made once, swapped when a step is taken (no allocation per
    iteration); ``P`` and ``at_P``'s arrays are among them.

    Returns ``(P, F, u, iterations)``.
    """
    m = q.shape[0]
    F, u, pos, r, x, nx, slip = at_P
    Pn, Fn, un, xn = np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 2))
    posn, slipn = np.empty(m, dtype=np.bool_), np.empty(m, dtype=np.bool_)
    rn, nxn = np.empty(m), np.empty(m)
    J, b = np.empty((3 * m, 3 * m)), np.empty(3 * m)
    merit = _half_square(F)
    it = 0
    for k in range(1, max_iter + 1):
        it = k
        if _max_abs(F) <= tol:
            break
        _jacobian_into(J, rW, mu, pos, r, x, nx, slip)
        for i in range(m):
            for c in range(3):
                b[3 * i + c] = -F[i, c]
        d, ok = _solve(J, b)
        if not ok:  # singular Jacobian
            break
        t = 1.0
        while True:
            for i in range(m):
                for c in range(3):
                    Pn[i, c] = P[i, c] + t * d[3 * i + c]
            _residual_into(Pn, W, q, mu, rho, U, Fn, un, posn, rn, xn, nxn, slipn)
            mn = _half_square(Fn)
            if mn <= (1.0 - 1e-4 * t) * merit:
                break
            t *= 0.5
            if t < 1e-8:
                return P, F, u, it
        P, Pn, F, Fn, u, un, merit = Pn, P, Fn, F, un, u, mn
        pos, posn, r, rn, x, xn = posn, pos, rn, r, xn, x
        nx, nxn, slip, slipn = nxn, nx, slipn, slip
    return P, F, u, it


@njit
def _gauss_seidel(P, W, q, mu, rho, U, tol, sweeps):
    """Projected block Gauss–Seidel on the Alart–Curnier map (robust, linear convergence)."""
    P = P.copy()
    m = q.shape[0]
    for _ in range(sweeps):
        change = 0.0
        for i in range(m):
            u = np.zeros(3)
            for a in range(3):
                s = 0.0
                for j in range(3 * m):
                    s += W[3 * i + a, j] * P[j // 3, j % 3]
                u[a] = s + q[i, a]
            pn = min(max(0.0, P[i, 0] - rho[i] * u[0]), U[i])
            x0 = P[i, 1] - rho[i] * u[1]
            x1 = P[i, 2] - rho[i] * u[2]
            nx = math.hypot(x0, x1)
            r = mu[i] * pn
            s = 1.0 if nx <= r else r / nx
            new = (pn, s * x0, s * x1)
            for a in range(3):
                change = max(change, abs(new[a] - P[i, a]))
                P[i, a] = new[a]
        if change <= tol:
            break
    return P


@njit
def _on_cone(P, u, mu, rho, U):
    """Exact cone membership; sliding contacts get ``|P_t| = μ P_n`` along ``P_t − ρ u_t``.

    Returns the impulses and the mask of sliding contacts.
    """
    P = P.copy()
    m = P.shape[0]
    slide = np.zeros(m, dtype=np.bool_)
    for i in range(m):
        P[i, 0] = min(max(P[i, 0], 0.0), U[i])
        bound = mu[i] * P[i, 0]
        x0 = P[i, 1] - rho[i] * u[i, 1]
        x1 = P[i, 2] - rho[i] * u[i, 2]
        nx = math.hypot(x0, x1)
        if nx > bound and P[i, 0] > 0.0:
            slide[i] = True
            P[i, 1], P[i, 2] = bound / nx * x0, bound / nx * x1
        else:
            nt = math.hypot(P[i, 1], P[i, 2])
            if nt > bound:
                P[i, 1] *= bound / nt
                P[i, 2] *= bound / nt
    return P, slide


@njit
def alart_curnier(W, q, mu, U, warm, use_warm, tol, max_iter):
    """Signorini–Coulomb on ``m`` contacts, ``u = W P + q`` (Newton's law already folded in).

    ``ρ_i = 1 / ‖W_ii‖_F``; Newton from ``warm`` (when ``use_warm`` and not worse than a
    cold start), projected Gauss–Seidel then Newton again if it stalls, then the exact cone.

    Returns ``(P (m, 3), sliding (m,), relative residual, iterations, status)``.
    """
    m = q.shape[0]
    rho = np.empty(m)
    for i in range(m):  # Frobenius norm of the diagonal block: no SVD per step
        s = 0.0
        for a in range(3):
            for b in range(3):
                s += W[3 * i + a, 3 * i + b] ** 2
        if not (s > 0.0) or W[3 * i, 3 * i] <= 0.0:
            return np.zeros((m, 3)), np.zeros(m, dtype=np.bool_), np.inf, 0, NON_POSITIVE
        rho[i] = 1.0 / math.sqrt(s)
    scale = 1e-300
    for i in range(m):
        for a in range(3):
            scale = max(scale, abs(rho[i] * q[i, a]))
    rW = W.copy()
    for i in range(3 * m):
        rW[i, :] *= rho[i // 3]
    P = np.zeros((m, 3))
    at_P = _residual(P, W, q, mu, rho, U)
    if use_warm:  # a cold start when the warm one is worse
        at_warm = _residual(warm, W, q, mu, rho, U)
        if _half_square(at_warm[0]) <= _half_square(at_P[0]):
            P, at_P = warm.copy(), at_warm
    P, F, u, it = _newton(P, W, rW, q, mu, rho, U, tol * scale, max_iter, at_P)
    if _max_abs(F) > tol * scale:  # Newton stalled: Gauss-Seidel sweeps, then Newton
        P = _gauss_seidel(P, W, q, mu, rho, U, tol * scale, 5000)
        at_P = _residual(P, W, q, mu, rho, U)
        P, F, u, it2 = _newton(P, W, rW, q, mu, rho, U, tol * scale, max_iter, at_P)
        it += it2
    res = _max_abs(F) / scale
    P, slide = _on_cone(P, u, mu, rho, U)
    status = SOLVED if res <= math.sqrt(tol) else NOT_SOLVED
    return P, slide, res, it, status


@njit
def frictional_solve(W, q, mu, e, ub, U, active, warm, use_warm, tol, max_iter):
    """The frictional problem of one step on the ``active`` contacts (of ``n``).

    ``W`` (3n, 3n) and ``q`` (n, 3) as seen by the local velocities after the step; Newton's
    law with ``e`` (n,) and the pre-step normal velocity ``ub`` (n,); ``U`` (n,) bounds on
    the normal impulses (``inf``: none); ``warm`` (n, 3) used when ``use_warm``.

    Returns ``(P (n, 3), u = W P + q (n, 3), state (n,), residual, iterations, status)``.
    """
    n = q.shape[0]
    P = np.zeros((n, 3))
    state = np.zeros(n, dtype=np.int8)
    idx = np.flatnonzero(active)
    ma = idx.size
    if ma == 0:  # nothing to solve (most steps of a rub): no set-up
        return P, q.copy(), state, 0.0, 0, SOLVED
    Wa, qa = newton_law(W, q, e, ub, idx)
    wa = np.empty((ma, 3))
    mua = np.empty(ma)
    Ua = np.empty(ma)
    for a in range(ma):
        i = idx[a]
        mua[a], Ua[a] = mu[i], U[i]
        for c in range(3):
            wa[a, c] = warm[i, c]
    Pa, slide, res, it, status = alart_curnier(Wa, qa, mua, Ua, wa, use_warm, tol, max_iter)
    u = q.copy()  # W P + q over the active columns only
    for a in range(ma):
        i = idx[a]
        for c in range(3):
            P[i, c] = Pa[a, c]
        for r in range(3 * n):
            u[r // 3, r % 3] += (
                W[r, 3 * i] * P[i, 0] + W[r, 3 * i + 1] * P[i, 1] + (W[r, 3 * i + 2] * P[i, 2])
            )
    for a in range(ma):
        i = idx[a]
        if P[i, 0] > 0.0:
            state[i] = SLIP if slide[a] or mu[i] == 0.0 else STICK
    return P, u, state, res, it, status


#: fixed-point iterations between the contact solve and the frictional heat of a step
MAX_HEAT_ITERATIONS = 20


@njit
def power_heat(P, u, st, w_k, eta, W, q, W3t, mu, e, ub, U, active, tol, max_iter, max_heat):
    """The ``"power"`` heat of a frictional impulse, fixed point with the contact solve.

    The blade receives ``Q_i = η_i (−P_t,i · w_t,i^mid)``, ``w_t^mid = (w_t,k + u_t) / 2``
    (W s = J; ``w_k`` (n, 2) the slip velocity before the step or impact, ``u`` the local
    velocities after it), in the same step; through the thermal coupling it shifts the
    local velocities by ``W3t Q`` (``W3t`` the local rows of the heat columns), so::

        Q⁰ = 0,   P^j = solve(W, q + W3t Q^{j−1}, active),   Q^j = η (−P_t^j · w_t^mid(P^j))

    from the solution ``(P, u, st)`` of ``solve(W, q, active)``, stopped when
    ``max |Q^j − Q^{j−1}| <= 1e-12 max |Q^j|``, at most ``max_heat`` solves, and at once
    when the heat moves no velocity (``W3t = 0``). Each solve is :func:`frictional_solve`
    of ``(W, ·, mu, e, ub, U, active)`` warm-started from the previous one.

    Returns ``(P, u, state, Q, residual, status)``.
    """
    n = mu.size
    feedback = np.any(W3t != 0.0)
    heat = np.zeros(n)
    new = heat
    res, status = 0.0, 0
    for _ in range(max_heat):
        new = np.empty(n)
        diff, big = 0.0, 0.0
        for i in range(n):
            a = P[i, 1] * (0.5 * (w_k[i, 0] + u[i, 1]))
            new[i] = eta[i] * -(a + P[i, 2] * (0.5 * (w_k[i, 1] + u[i, 2])))
            diff = max(diff, abs(new[i] - heat[i]))
            big = max(big, abs(new[i]))
        if diff <= 1e-12 * big or not feedback:
            break
        heat = new
        qh = q + np.dot(W3t, heat).reshape((n, 3))
        P, u, st, res, it, status = frictional_solve(
            W, qh, mu, e, ub, U, active, P, True, tol, max_iter
        )
        if status != 0:
            break
    return P, u, st, new, res, status


#: rule codes of the compiled fixed point: the Moreau–Jean rule, or the "paper" fixed point
FIXED_POINT, PREDICTED = 0, 1


@njit
def frictional_fixed_point(
    code, g_k, gd_k, g_p, GZ3, W, q, mu, e, ub, U, warm, use_warm, h, gamma, tol, max_iter
):
    """Active set and solution of a frictional step (compiled; one call per step).

    ``code``: :func:`femrub.contact.activation.rule_code` (the rules are described in
    :mod:`femrub.contact.activation`, which exports this function). ``PREDICTED`` is the
    Moreau–Jean rule ``g_k + γ h ġ_k <= 0``; every other rule uses the ``"paper"`` fixed
    point: closed at ``t_k`` or closed at ``t_{k+1}`` after the impulse
    (``g_p + GZ3 P <= 0``, ``GZ3 = ∂g_{k+1}/∂P`` (n_c, 3 n_c)). These are the rules with a
    frictional form (:data:`femrub.contact.activation.FRICTIONAL_RULES`; the others are
    refused with friction before a step). If no consistent set exists
    the contact is kept active (the union of the last two sets; when that union was solved
    already in this step, its solution is returned, not solved again). Each solve is
    :func:`frictional_solve` of ``(W, q, mu, e, ub, U)``, warm-started from the previous
    solve of the step (from ``warm`` for the first, when ``use_warm``).

    Returns ``(active, P, u, state, residual, iterations, status)``.
    """
    if code == PREDICTED:
        active = g_k + gamma * h * gd_k <= 0.0
        P, u, st, res, it, status = frictional_solve(
            W, q, mu, e, ub, U, active, warm, use_warm, tol, max_iter
        )
        return active, P, u, st, res, it, status
    closed = g_k <= 0.0
    active = closed | (g_p <= 0.0)
    first = True
    # seen[:n_seen]: the sets solved before the current one, with their solutions
    seen, n_seen = [active], 0
    s_P, s_u, s_st, s_res, s_it = [warm], [warm], [np.zeros(q.shape[0], np.int8)], [0.0], [0]
    while True:
        P, u, st, res, it, status = frictional_solve(
            W, q, mu, e, ub, U, active, warm, use_warm, tol, max_iter
        )
        # an error; or no impulse at the start, so the set is consistent (most steps of a rub)
        if status != 0 or (first and not active.any()):
            return active, P, u, st, res, it, status
        first = False
        if active.any():  # the next active set starts from here
            warm, use_warm = P, True
        new = closed | (g_p + GZ3 @ P.reshape(-1) <= 0.0)
        if np.array_equal(new, active):
            return active, P, u, st, res, it, status
        for j in range(n_seen):
            if np.array_equal(new, seen[j]):  # no consistent set: keep the impulse
                keep = new | active
                if np.array_equal(keep, active):  # the set just solved
                    return active, P, u, st, res, it, status
                for i in range(n_seen):  # a set solved before: the same problem, its solution
                    if np.array_equal(keep, seen[i]):
                        return keep, s_P[i], s_u[i], s_st[i], s_res[i], s_it[i], 0
                P, u, st, res, it, status = frictional_solve(
                    W, q, mu, e, ub, U, keep, warm, use_warm, tol, max_iter
                )
                return keep, P, u, st, res, it, status
        if n_seen < len(seen):
            seen[n_seen], s_P[n_seen], s_u[n_seen], s_st[n_seen] = active, P, u, st
            s_res[n_seen], s_it[n_seen] = res, it
        else:
            seen.append(active)
            s_P.append(P)
            s_u.append(u)
            s_st.append(st)
            s_res.append(res)
            s_it.append(it)
        n_seen += 1
        active = new
