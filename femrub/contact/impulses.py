"""Impulses of the active contacts: the per-step LCP ``0 <= P ⊥ W P + q >= 0``.

One active contact has the closed form ``P = max(0, −q / W)`` (the paper's prox, Eq. 25b);
several are solved exactly by :func:`femrub.contact.lcp.solve_lcp` (Lemke pivoting), never
by penalty.
"""

from __future__ import annotations

import numpy as np

from .lcp import solve_lcp

__all__ = ["cap", "solve_impulses"]


def solve_impulses(
    W: np.ndarray, q: np.ndarray, active: np.ndarray, warm=None, upper=None
) -> np.ndarray:
    """Impulses ``P`` (zero on inactive contacts) solving the LCP restricted to ``active``.

    ``upper`` (n_c,) bounds the impulses (:func:`cap`; ``None`` or ``inf``: unbounded).
    """
    if upper is not None and np.any(np.isfinite(np.asarray(upper)[active])):
        return cap(_solve, W, q, active, np.asarray(upper, dtype=float), warm)
    return _solve(W, q, active, warm)


def cap(solve, W, q, active, upper, warm=None) -> np.ndarray:
    """Impulses bounded above, ``0 <= P <= upper``, with any impulse solve ``solve``.

    The box-constrained complementarity problem: on each active contact either ``P = 0``
    and ``(W P + q) >= 0``, or ``0 < P < upper`` and ``(W P + q) = 0``, or ``P = upper``
    and ``(W P + q) <= 0``. A contact whose impulse exceeds its bound is held at the bound
    (its contribution ``W[:, i] upper_i`` moves to the right-hand side) and the others are
    solved again; a held contact whose residual turns positive is released (at most
    ``2 n_c + 2`` passes; exact for one contact: ``P = min(max(0, −q / W), upper)``). At
    the bound the contact may penetrate: the abradable coating yields there
    (:mod:`femrub.contact.abradable`).
    """
    fixed = np.zeros(q.size, dtype=bool)
    tol = 1e-12 * max(float(np.max(np.abs(q), initial=0.0)), 1e-300)
    P = np.zeros(q.size)
    for _ in range(2 * q.size + 2):
        qf = q + W[:, fixed] @ upper[fixed]
        P = solve(W, qf, active & ~fixed, warm)
        P[fixed] = upper[fixed]
        over = active & ~fixed & (P > upper)
        release = fixed & ((W @ P + q) > tol)
        if not np.any(over) and not np.any(release):
            return P
        fixed = (fixed | over) & ~(release if not np.any(over) else np.zeros_like(fixed))
    return np.minimum(P, upper)


def _solve(W: np.ndarray, q: np.ndarray, active: np.ndarray, warm=None) -> np.ndarray:
    P = np.zeros(q.size)
    idx = np.flatnonzero(active)
    if idx.size == 0:
        return P
    if idx.size == 1:
        i = idx[0]
        w = W[i, i]
        if w <= 0.0:
            raise FloatingPointError("non-positive Delassus operator at a contact")
        P[i] = max(0.0, -q[i] / w)
        return P
    ws = None if warm is None else np.asarray(warm)[idx]
    res = solve_lcp(W[np.ix_(idx, idx)], q[idx], warm_start=ws)
    P[idx] = res.z
    return P
