"""Compiled dyadic algebra of the exponential stepper's exact flows (numba).

The exact flows of :mod:`~.flows` over ``unit 2^e`` are built once per held set by squaring
the increment ``D = Z − I`` of the smallest level (:func:`square_levels`), and a state is
advanced over any duration ``k unit 2^LEVEL_MIN`` by composing the levels of the binary
expansion of ``k`` from the top bit down (:func:`compose`); the work integrals of
:mod:`~.work` compose their stacked level rows ``[Γ_e; C J_e]`` the same way
(:func:`compose_integrals`). A whole step without event is one product of a matrix stacked
once per held set, its integrals and event check read off it (:func:`flight`). These loops
are the only implementation of that algebra:
compiled with :func:`femrub.contact.jit.njit` (one compilation per machine, cached on disk),
and plain Python/numpy under ``NUMBA_DISABLE_JIT=1``.
"""

from __future__ import annotations

import numpy as np

from ...contact.jit import compiled, njit

__all__ = [
    "compose",
    "compose_integrals",
    "double_integrals",
    "flight",
    "first_zero_row",
    "form_values",
    "hermite_root",
    "integrals_over",
    "open_end",
    "part_rows",
    "quiet",
    "square_levels",
    "warm_up",
]


@njit
def square_levels(D, count, flush):
    """The flows ``Z_e = I + D_e`` (count, N, N) of ``count`` successive dyadic levels from
    the increment ``D`` (N, N) of the first: ``D_{e+1} = 2 D_e + D_e²`` (no cancellation
    against the identity); entries below ``flush`` are set to zero before each level (no
    subnormal products, they are slow). ``D`` is overwritten."""
    n = D.shape[0]
    out = np.empty((count, n, n))
    for lev in range(count):
        for i in range(n):
            for j in range(n):
                if abs(D[i, j]) < flush:
                    D[i, j] = 0.0
        out[lev] = D
        for i in range(n):
            out[lev, i, i] += 1.0
        if lev + 1 < count:
            D = 2.0 * D + D @ D
    return out


@njit
def compose(Z, z, k):
    """``z`` advanced over ``k`` smallest units: ``Z[e] @ z`` for each set bit ``e`` of ``k``
    from the top down (``Z`` (levels, N, N), level 0 the smallest; ``k < 2^levels``)."""
    e = Z.shape[0] - 1
    while k > 0 and e >= 0:
        if k >> e & 1:
            z = Z[e] @ z
            k -= 1 << e
        e -= 1
    return z


@njit
def compose_integrals(Y, Z, z, k, lo, n_forms):
    """The integrals over the levels ``e >= lo`` of the binary expansion of ``k`` (top bit
    first), each level's stacked rows ``Y[e − lo] = [Γ_e (n_forms × N rows); C J_e (2 rows)]``
    and its flow ``Z[e]`` applied to the state at its start::

        w_f += z_eᵀ Γ_{e,f} z_e,      w_lin += C J_e z_e,      z_{e+1} = Z_e z_e

    Returns ``(w_forms (n_forms,), w_lin (2,), z after these levels, the bits left below lo)``.
    """
    n = z.size
    kn = n_forms * n
    wq = np.zeros(n_forms)
    wl = np.zeros(2)
    e = lo + Y.shape[0] - 1
    while e >= lo:
        if k >> e & 1:
            y = Y[e - lo] @ z
            for f in range(n_forms):
                wq[f] += y[f * n : (f + 1) * n] @ z
            wl += y[kn : kn + 2]
            z = Z[e] @ z
            k -= 1 << e
        e -= 1
    return wq, wl, z, k


@njit
def integrals_over(Y, lo, Q, C, M, Z, z, k, terms, d_min, state):
    """The integrals over ``k`` smallest units ``d_min`` from ``z``: the levels ``e >= lo``
    by :func:`compose_integrals`, the bits below ``lo`` (duration ``d``) by the Taylor series
    ``Σ_t d^{t+1}/(t+1)! (zᵀ A_t z, C M^t z)``, ``t < terms``, ``A_t = Σ_j C(t, j) (Mᵀ)^j Q
    M^{t−j}`` read off the Krylov vectors ``v_j = M^j z`` (``zᵀ A_t z = Σ_j C(t, j) v_jᵀ Q
    v_{t−j}``: products with the small ``M``, ``Q`` (n_forms, N, N), ``C`` (2, N) only).
    Returns ``(w_forms, w_lin, z)``, ``z`` at the end of the duration with ``state``
    (:func:`compose` of the bits below ``lo``), else at the end of the levels' part."""
    nf = Q.shape[0]
    wq, wl, z, k = compose_integrals(Y, Z, z, k, lo, nf)
    if k:
        n = z.size
        d = k * d_min
        v = np.empty((terms, n))
        v[0] = z
        for t in range(1, terms):
            v[t] = M @ v[t - 1]
        for f in range(nf):
            u = v @ Q[f]  # rows u_j = Q v_j (Q symmetric)
            c = 1.0
            for t in range(terms):
                c *= d / (t + 1)
                acc, b = 0.0, 1.0  # Σ_j C(t, j) v_j · u_{t−j}
                for j in range(t + 1):
                    acc += b * (v[j] @ u[t - j])
                    b = b * (t - j) / (j + 1)
                wq[f] += c * acc
        cv = v @ C.T
        c = 1.0
        for t in range(terms):
            c *= d / (t + 1)
            wl += c * cv[t]
        if state:
            z = compose(Z, z, k)
    return wq, wl, z


@njit
def double_integrals(g, j, Z, flush):
    """The stacked rows ``Y[i] = [Γ_i (forms × N rows); C J_i (2 rows)]`` of successive dyadic
    levels from the integrals of the first, ``g`` (forms, N, N) and ``j`` (2, N), and the
    levels' flows ``Z`` (count, N, N): over ``[0, 2τ] = [0, τ] ∪ [τ, 2τ]``::

        Γ_{i+1} = Γ_i + Z_iᵀ Γ_i Z_i,        C J_{i+1} = C J_i + C J_i Z_i

    (``Z_iᵀ Γ Z_i = (Γ Z_i)ᵀ Z_i``, Γ symmetric). Entries of ``Y`` below ``flush`` are set to
    zero (no subnormal products when they are applied)."""
    nf, n = g.shape[0], g.shape[1]
    count = Z.shape[0]
    kn = nf * n
    Y = np.empty((count, kn + 2, n))
    for i in range(count):
        Zi = Z[i]
        for f in range(nf):
            Y[i, f * n : (f + 1) * n] = g[f]
        Y[i, kn : kn + 2] = j
        for r in range(kn + 2):
            for c in range(n):
                if abs(Y[i, r, c]) < flush:
                    Y[i, r, c] = 0.0
        if i + 1 < count:  # all forms in two products: U_f = Γ_f Z_i, then U_fᵀ Z_i
            U = g.reshape(nf * n, n) @ Zi
            V = np.empty((nf * n, n))
            for f in range(nf):
                V[f * n : (f + 1) * n] = U[f * n : (f + 1) * n].T
            g = g + (V @ Zi).reshape(nf, n, n)
            j = j + j @ Zi
    return Y


@njit
def form_values(y, u, nz, act, out):
    """The integrals of a whole step into ``out`` (quadratic forms, then two heats) from
    ``y = F u`` (:meth:`~.work.WorkIntegrals.flight_matrix`): the quadratic forms
    ``uᵀ (EᵀΓE)_f u`` of the non-zero forms ``act`` (rows ``nz + f len(u)`` on), then the
    two heats as read (the last two entries of ``out``)."""
    nu = u.size
    for f in range(act.size):
        out[act[f]] = y[nz + f * nu : nz + (f + 1) * nu] @ u
    kn = act.size * nu
    out[out.size - 2] = y[nz + kn]
    out[out.size - 1] = y[nz + kn + 1]


@njit
def quiet(V, n_c, held):
    """No event on the check grid ``V`` (q + 1, n_c + r) of exact gaps, then held multipliers
    and slips: no free gap falls below ``min(g(0), 0)`` and no held multiplier or slip is
    negative."""
    for i in range(n_c):
        if held[i]:
            continue
        ref = min(V[0, i], 0.0)
        for j in range(1, V.shape[0]):
            if V[j, i] < ref:
                return False
    for j in range(V.shape[0]):
        for i in range(n_c, V.shape[1]):
            if V[j, i] < 0.0:
                return False
    return True


@njit
def open_end(V, n_c, held):
    """Every free gap clearly open at the last row of the check grid ``V``: above ``1e-9`` of
    the largest gap there (round-off of the grid's rows cannot close it)."""
    g = 0.0
    for i in range(n_c):
        g = max(g, abs(V[V.shape[0] - 1, i]))
    for i in range(n_c):
        if not held[i] and V[V.shape[0] - 1, i] <= 1e-9 * g:
            return False
    return True


@njit
def flight(F, u, k, q, gap0, off, held, nz, act, measure, works):
    """A whole step's exact flight in one product ``y = F u`` (``F``: the state rows, the
    integrals' rows with ``measure``, then from row ``k`` the check grid's rows): the
    integrals into ``works`` (:func:`form_values`), the check grid ``V`` (q + 1, r) with the
    casing's gaps ``gap0`` (q + 1, n_c) added to its first columns and the constants ``off``
    (r − n_c,) to the others (held slips), whether the step is :func:`quiet` and, if so,
    whether its free gaps end :func:`open_end` (no impulse due at the step end).
    Returns ``(y, V, quiet, open)`` (``V``: ``y``'s rows past ``k``, which may share its memory;
    empty, quiet and not known open without grid rows)."""
    y = F @ u
    if measure:
        form_values(y, u, nz, act, works)
    if k >= y.size:
        return y, np.empty((0, 0)), True, False
    V = np.ascontiguousarray(y[k:]).reshape(q + 1, (y.size - k) // (q + 1))
    n_c = gap0.shape[1]
    V[:, :n_c] += gap0
    if off.size:
        V[:, n_c:] += off
    calm = quiet(V, n_c, held)
    return y, V, calm, calm and open_end(V, n_c, held)


@njit
def part_rows(Z, R, Rz, za, k1, mid, nj, zh):
    """The check rows of a part step (:meth:`~.events.EventLocation._part_grid`) without the
    casing's gaps and slip offsets: ``R z`` at its start ``za``, with ``mid`` at the first grid
    point (``za`` advanced by ``k1`` smallest units, :func:`compose`), ``nj`` probe rows ``Rz``
    from there, and ``R zh`` at the step end. Returns ``(V (rows, r), z at the grid point)``."""
    r = R.shape[0]
    V = np.empty((2 + (1 if mid else 0) + nj, r))
    V[0] = R @ za
    i, z1 = 1, za
    if mid:
        z1 = compose(Z, za.copy(), k1) if k1 else za.copy()
        V[1] = R @ z1
        i = 2
    if nj > 0:
        V[i : i + nj] = (Rz[: nj * r] @ z1).reshape(nj, r)
        i += nj
    V[i] = R @ zh
    return V, z1


@njit
def next_iterate(hermite, lo, f_lo, df_lo, x, fx, dfx, a, f_a, bh, f_bh, df_bh, slow):
    """The next iterate ``(x_new, slow)`` of the safeguarded Newton search for the first zero
    of a gap-like function (``flows.first_zero``, :func:`first_zero_row`): the cubic Hermite
    root between ``lo`` and ``x`` on the first iteration from an open start (``hermite``),
    bisection once the bracket ``(a, bh)`` stopped shrinking (``slow >= 3``), else Newton at
    ``x`` or from the closed side ``bh``; outside the bracket regula falsi, else bisection."""
    if hermite and f_lo > 0.0:
        x_new = hermite_root(lo, f_lo, df_lo, x, fx, dfx)
    elif slow >= 3:  # the bracket stopped shrinking: bisection
        x_new, slow = 0.5 * (a + bh), 0
    else:
        x_new = x - fx / dfx if dfx != 0.0 else np.nan
        if not (a < x_new < bh) and df_bh != 0.0:  # Newton from the closed side
            x_new = bh - f_bh / df_bh
    if not (a < x_new < bh):  # outside the bracket: regula falsi, else bisection
        x_new = a - f_a * (bh - a) / (f_bh - f_a) if f_bh != f_a else np.nan
        if not (a < x_new < bh):
            x_new = 0.5 * (a + bh)
    return x_new, slow


@njit
def hermite_root(a, fa, dfa, b, fb, dfb):
    """First guess of the zero in ``(a, b)``: Newton on the cubic Hermite interpolant of
    ``f`` from its values and slopes at the ends (``fa > 0 > fb``); NaN if it fails."""
    if fa == fb:
        return np.nan
    d = b - a
    p0, p1, q0, q1 = fa, d * dfa, fb, d * dfb
    c2, c3 = 3 * (q0 - p0) - 2 * p1 - q1, 2 * (p0 - q0) + p1 + q1
    s = fa / (fa - fb)  # secant start
    for _ in range(8):
        val = p0 + s * (p1 + s * (c2 + s * c3))
        der = p1 + s * (2 * c2 + 3 * s * c3)
        if der == 0.0:
            return np.nan
        s = min(max(s - val / der, 0.0), 1.0)
    return a + s * d


@njit
def _at_row(Z, kt, kz, nk, tau, r, rM, c0, d_min):
    """``(z(τ), f, df/dτ)`` of the row event ``f = r·z + c0`` at ``τ``, ``z`` composed
    (:func:`compose`) from the latest known state at or before ``τ`` (``kt[:nk]``, ``kz``)."""
    best = 0
    for i in range(nk):
        if kt[i] <= tau and kt[i] >= kt[best]:
            best = i
    rest = tau - kt[best]
    k = int(rest / d_min * (1.0 + 1e-12)) if rest > 0.0 else 0
    k = min(k, (1 << Z.shape[0]) - 1)
    z = compose(Z, kz[best].copy(), k) if k else kz[best].copy()
    return z, r @ z + c0, rM @ z


@njit
def _open_side(Z, kt, kz, lo, hi, r, rM, c0, d_min):
    """A row event at the surface at ``lo`` (``f(lo) <= 0``): the bracket halved towards
    ``lo`` until ``f > 0`` (at most 40 times), that point kept as the second known state
    (``kt[1]``, ``kz[1]``). Returns ``(x, f(x))``, ``f(x) <= 0`` when none was found."""
    x, fx = hi, 0.0
    for _ in range(40):
        x = lo + 0.5 * (x - lo)
        zx, fx, dfx = _at_row(Z, kt, kz, 1, x, r, rM, c0, d_min)
        if fx > 0.0:
            kt[1], kz[1] = x, zx
            break
    return x, fx


@njit
def first_zero_row(Z, z_lo, r, rM, c0, lo, hi, tol, d_min):
    """First zero in ``(lo, hi]`` of the row event ``f(τ) = r·z(τ) + c0`` (``df/dτ =
    rM·z``, ``rM = Mᵀ r``) on the flow composed of the levels ``Z`` (smallest ``d_min``)
    from ``z(lo) = z_lo``, by the safeguarded Newton iteration of
    :func:`~.flows.first_zero` (cubic Hermite start, Newton from the closed
    side, regula falsi, bisection; each evaluation from the latest state known on the open
    side). Returns ``(found, τ, z(τ))`` with ``f(τ) <= 0`` within ``tol`` of the zero."""
    kt = np.empty(128)
    kz = np.empty((128, z_lo.size))
    kt[0], kz[0], nk = lo, z_lo, 1
    f_lo, df_lo = r @ z_lo + c0, rM @ z_lo
    a, f_a = lo, f_lo
    if f_lo <= 0.0:  # at the surface at lo: the open side first
        a, f_a = _open_side(Z, kt, kz, lo, hi, r, rM, c0, d_min)
        if not f_a > 0.0:
            return False, hi, z_lo
        nk = 2
    x = hi
    z, fx, dfx = _at_row(Z, kt, kz, nk, x, r, rM, c0, d_min)
    if fx > 0.0 and nk < kt.size:
        kt[nk], kz[nk], nk = x, z, nk + 1
    bt, bz = x, z
    bh, f_bh, df_bh = hi, fx, dfx
    width, slow = bh - a, 0
    for it in range(60):
        x_new, slow = next_iterate(
            it == 0, lo, f_lo, df_lo, x, fx, dfx, a, f_a, bh, f_bh, df_bh, slow
        )
        if abs(x_new - x) <= tol:  # converged
            if fx > 0.0 and bh - x > tol:  # from the open side: step just past the zero
                x = min(x + 2.0 * tol, bh)
                z, fx, dfx = _at_row(Z, kt, kz, nk, x, r, rM, c0, d_min)
                if fx <= 0.0:
                    bt, bz = x, z
            break
        x = x_new
        z, fx, dfx = _at_row(Z, kt, kz, nk, x, r, rM, c0, d_min)
        if fx > 0.0:
            a, f_a = x, fx
            if nk < kt.size:
                kt[nk], kz[nk], nk = x, z, nk + 1
        else:
            bh, f_bh, df_bh, bt, bz = x, fx, dfx, x, z
        if bh - a <= tol:
            break
        slow = slow + 1 if bh - a > 0.5 * width else 0
        width = min(width, bh - a) if slow == 0 else width
    return True, bt, bz


def warm_up() -> None:
    """Compile (or load from the disk cache) the kernels for the argument types of a run,
    before any timed step (nothing is computed that is kept)."""
    if not compiled():
        return
    Z = square_levels(np.zeros((2, 2)), 2, 1e-150)
    compose(Z, np.zeros(2), 1)
    compose_integrals(np.zeros((2, 4, 2)), Z, np.zeros(2), 1, 0, 1)
    q2 = np.zeros((1, 2, 2))
    integrals_over(
        np.zeros((2, 4, 2)), 1, q2, np.zeros((2, 2)), Z[0], Z, np.ones(2), 1, 2, 1.0, True
    )
    double_integrals(np.zeros((1, 2, 2)), np.zeros((2, 2)), Z, 1e-150)
    act, held, w = np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.bool_), np.zeros(8)
    off = np.zeros(0)
    part_rows(Z, np.ones((1, 2)), np.ones((2, 2)), np.ones(2), 1, True, 1, np.ones(2))
    first_zero_row(Z, np.ones(2), np.ones(2), np.ones(2), -3.0, 0.0, 1.0, 1e-3, 0.5)
    next_iterate(True, 0.0, 1.0, -1.0, 1.0, -1.0, -1.0, 0.0, 1.0, 1.0, -1.0, -1.0, 0)
    flight(np.zeros((10, 2)), np.zeros(2), 6, 1, np.zeros((2, 1)), off, held, 2, act, True, w)
