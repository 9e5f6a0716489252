"""Impulses of the active contacts: the per-step LCP ``0 <= P ⊥ W P + q >= 0``.

One active contact has the closed form ``P = max(0, −q / W)`` (the paper's prox, Eq. 25b);
several are solved exactly by :func:`femrub.contact.lcp.solve_lcp` (Lemke pivoting), never
by penalty.
"""

from __future__ import annotations

import numpy as np

from .lcp import solve_lcp

__all__ = ["solve_impulses"]


def solve_impulses(W: np.ndarray, q: np.ndarray, active: np.ndarray, warm=None) -> np.ndarray:
    """Impulses ``P`` (zero on inactive contacts) solving the LCP restricted to ``active``."""
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
