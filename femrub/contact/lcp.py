"""Exact solver for small dense linear complementarity problems (LCP).

Find ``z >= 0`` such that ``w = M z + q >= 0`` and ``z . w = 0``, as arises at each
step of a Moreau-Jean / theta-method contact stepper.  ``M`` is dense, small
(``n`` up to about 100) and need not be symmetric.  The main method is Lemke's
complementary pivoting with covering vector ``d = 1`` and the lexicographic
ratio test (no cycling on degenerate problems); a semi-smooth Newton method on the
Fischer-Burmeister reformulation is the fallback.  Every candidate is polished by
an exact solve on its active set and checked before it is returned.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LCPError", "LCPResult", "solve_lcp"]

_PIV_TOL = 1e-12  # smallest admissible pivot, relative to max(1, max|entering column|)
_TIE_TOL = 1e-12  # ratios closer than this (relative to max(1, |ratio|)) are tied


class LCPError(RuntimeError):
    """Raised when no method produces a solution of the LCP."""


@dataclass(frozen=True, eq=False)
class LCPResult:
    """Solution of ``w = M z + q``, ``z >= 0``, ``w >= 0``, ``z . w = 0``.

    Attributes
    ----------
    z, w : numpy.ndarray
        Complementary pair, shape ``(n,)``; ``z`` is exactly non-negative.
    pivots : int
        Number of Lemke pivots performed (0 for fast paths and warm starts).
    method : str
        ``"empty"``, ``"trivial"`` (``q >= 0``), ``"closed-form"`` (``n == 1``),
        ``"warm-start"``, ``"lemke"`` or ``"newton-fb"``.
    residual : float
        ``max|min(z', w')| / max(1, max|z'|)`` for the problem scaled so that
        ``max|M'| = max|q'| = 1`` (invariant under a common scaling of ``M, q``).
    converged : bool
        ``residual <= tol``.  A result with ``tol < residual <= sqrt(tol)`` is
        returned with ``converged=False``; anything worse raises `LCPError`.
    """

    z: np.ndarray
    w: np.ndarray
    pivots: int
    method: str
    residual: float
    converged: bool


def _residual(M, q, z):
    return float(np.max(np.abs(np.minimum(z, M @ z + q)), initial=0.0) / max(1.0, np.abs(z).max()))


def _on_set(M, q, active):
    """Solve ``(M z + q)[active] = 0`` with ``z = 0`` off ``active``; ``None`` if singular."""
    z = np.zeros_like(q)
    if active.any():
        try:
            z[active] = np.linalg.solve(M[np.ix_(active, active)], -q[active])
        except np.linalg.LinAlgError:
            return None
    return z if np.isfinite(z).all() else None


def _pivot(T, r, c):
    T[r] /= T[r, c]
    col = T[:, c].copy()
    col[r] = 0.0
    T -= np.outer(col, T[r])


def _lex_row(T, col, n, prefer):
    """Lexicographic minimum-ratio row over ``[rhs, B^-1]``, or ``None`` (secondary ray).

    ``prefer`` (the row of ``z0``) wins any tie on the right-hand-side ratio.
    """
    rows = np.flatnonzero(col > _PIV_TOL * max(1.0, np.abs(col).max()))
    for k in (-1, *range(n)):  # a further column only when the previous one ties
        if rows.size <= 1:
            break
        ratios = T[rows, k] / col[rows]
        best = ratios.min()
        rows = rows[ratios <= best + _TIE_TOL * max(1.0, abs(best))]
        if k == -1 and prefer in rows:
            return prefer
    return int(rows[0]) if rows.size else None


def _lemke(M, q, max_pivots):
    """Lemke's method with ``d = 1``; returns ``(z or None, pivots)``."""
    n = q.size
    T = np.hstack([np.eye(n), -M, -np.ones((n, 1)), q[:, None]])
    basis = np.arange(n)  # columns: w_i -> i, z_i -> n + i, z0 -> 2n, rhs -> 2n + 1
    # the last index among the most negative q_i keeps all rows lexico-positive
    r, entering = int(np.flatnonzero(q <= q.min() + _TIE_TOL)[-1]), 2 * n
    for pivots in range(1, max_pivots + 1):
        _pivot(T, r, entering)
        leaving, basis[r] = basis[r], entering
        if leaving == 2 * n:  # z0 left the basis: the basis is complementary
            z, is_z = np.zeros(n), basis >= n
            z[basis[is_z] - n] = T[is_z, -1]
            return np.maximum(z, 0.0), pivots
        entering = leaving + n if leaving < n else leaving - n
        r = _lex_row(T, T[:, entering], n, int(np.flatnonzero(basis == 2 * n)[0]))
        if r is None:
            return None, pivots  # secondary ray
    return None, max_pivots


def _fb(M, q, z):
    w = M @ z + q
    return np.hypot(z, w) - z - w, w


def _newton_fb(M, q, z, tol, maxit=100):
    """Semi-smooth Newton with Armijo search on ``|phi_FB|^2 / 2``, polished every step."""
    z = np.maximum(z, 0.0)
    for _ in range(maxit):
        zp = _polish(M, q, z)
        if _residual(M, q, zp) <= tol:
            return zp
        phi, w = _fb(M, q, z)
        rad = np.hypot(z, w)
        kink = rad <= 1e-14  # (0, 0): any element of the generalised Jacobian will do
        da = np.where(kink, np.sqrt(0.5), z / np.where(kink, 1.0, rad)) - 1.0
        db = np.where(kink, np.sqrt(0.5), w / np.where(kink, 1.0, rad)) - 1.0
        J = np.diag(da) + db[:, None] * M
        grad = J.T @ phi
        try:
            dz = np.linalg.solve(J, -phi)
        except np.linalg.LinAlgError:
            dz = -grad
        if not np.isfinite(dz).all() or grad @ dz > -1e-10 * (dz @ dz):
            dz = -grad  # not a descent direction: steepest descent
        psi, slope, t = 0.5 * (phi @ phi), grad @ dz, 1.0
        while t > 1e-12 and 0.5 * np.sum(_fb(M, q, z + t * dz)[0] ** 2) > psi + 1e-4 * t * slope:
            t *= 0.5
        z = np.maximum(z + t * dz, 0.0) if t > 1e-12 else z
        if t <= 1e-12:
            break  # stalled at a stationary point of the merit function
    return _polish(M, q, z)


def _polish(M, q, z):
    """Return the better of ``z`` and the exact solution on its active set ``{z > w}``."""
    cand = _on_set(M, q, z > M @ z + q)
    if cand is not None:
        cand = np.maximum(cand, 0.0)
        if _residual(M, q, cand) <= _residual(M, q, z):
            return cand
    return z


def _validate(M, q, tol, max_pivots, warm_start):
    if np.iscomplexobj(M) or np.iscomplexobj(q):
        raise ValueError("M and q must be real, got complex values")
    try:
        M, q = np.array(M, dtype=float), np.array(q, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"M and q must be numeric arrays ({exc})") from None
    if q.ndim != 1:
        raise ValueError(f"q must be 1-D, got shape {q.shape}")
    if M.shape != (q.size, q.size):
        raise ValueError(f"M must have shape {(q.size, q.size)} to match q, got {M.shape}")
    if not (np.isfinite(M).all() and np.isfinite(q).all()):
        raise ValueError("M and q must be finite (NaN or inf found)")
    if not (isinstance(tol, (int, float, np.floating)) and 0 < tol < np.inf):
        raise ValueError(f"tol must be a positive finite number, got {tol!r}")
    if max_pivots is not None and not (
        isinstance(max_pivots, (int, np.integer)) and not isinstance(max_pivots, bool)
    ):
        raise ValueError(f"max_pivots must be a positive integer, got {max_pivots!r}")
    if max_pivots is not None and max_pivots < 1:
        raise ValueError(f"max_pivots must be a positive integer, got {max_pivots!r}")
    if warm_start is not None:
        warm_start = np.asarray(warm_start)
        if warm_start.shape != q.shape or warm_start.dtype != bool:
            raise ValueError(f"warm_start must be a boolean mask of shape {q.shape}")
    return M, q, warm_start


def solve_lcp(M, q, *, tol=1e-12, max_pivots=None, warm_start=None) -> LCPResult:
    """Solve the LCP ``z >= 0``, ``w = M z + q >= 0``, ``z . w = 0``.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Dense matrix, not necessarily symmetric; a solution is guaranteed for
        P-matrices (unique) and positive semi-definite ``M`` with a feasible ``q``.
    q : array_like, shape (n,)
        Constant vector.
    tol : float, optional
        Acceptance threshold on `LCPResult.residual`.
    max_pivots : int, optional
        Lemke pivot budget before the Newton fallback; default ``50 * n``.
    warm_start : array_like of bool, shape (n,), optional
        Guess of the set ``z > 0`` (e.g. from the previous time step).  It is
        tried first by one linear solve and accepted if it meets ``tol``.

    Returns
    -------
    LCPResult

    Raises
    ------
    ValueError
        Bad shapes, non-finite entries or invalid options.
    LCPError
        If no method reaches a residual below ``sqrt(tol)`` (e.g. infeasible LCP).
    """
    M, q, warm_start = _validate(M, q, tol, max_pivots, warm_start)
    n = q.size
    if n == 0 or (q >= 0).all():
        return LCPResult(np.zeros(n), q.copy(), 0, "empty" if n == 0 else "trivial", 0.0, True)
    if n == 1 and M[0, 0] <= 0:
        raise LCPError(f"1x1 LCP has no solution: M = {M[0, 0]:g} <= 0 and q = {q[0]:g} < 0")
    m_scale, q_scale = np.abs(M).max(), np.abs(q).max()
    if m_scale == 0.0:
        raise LCPError("LCP has no solution: M = 0 and q has a negative entry")
    Ms, qs = M / m_scale, q / q_scale  # z = zs * q_scale / m_scale, w = ws * q_scale

    def result(zs, pivots, method):
        res = _residual(Ms, qs, zs)
        if not res <= np.sqrt(tol):
            raise LCPError(f"LCP not solved: best residual {res:.3g} > sqrt(tol) after {method}")
        z = zs * (q_scale / m_scale)
        return LCPResult(z, M @ z + q, pivots, method, res, bool(res <= tol))

    if n == 1:
        return result(np.array([-qs[0] / Ms[0, 0]]), 0, "closed-form")
    if warm_start is not None:
        zs = _on_set(Ms, qs, warm_start)
        if zs is not None and _residual(Ms, qs, zs := np.maximum(zs, 0.0)) <= tol:
            return result(zs, 0, "warm-start")
    zs, pivots = _lemke(Ms, qs, 50 * n if max_pivots is None else int(max_pivots))
    if zs is not None:
        zs = _polish(Ms, qs, zs)
        if _residual(Ms, qs, zs) <= tol:
            return result(zs, pivots, "lemke")
    start = np.zeros(n) if zs is None else zs
    return result(_newton_fb(Ms, qs, start, tol), pivots, "newton-fb")
