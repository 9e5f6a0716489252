"""Damping: Rayleigh coefficients that give a modal damping ratio at two modes.

``C = a M + b K`` damps mode ``ω`` with ratio ``ζ(ω) = a / (2 ω) + b ω / 2``; choosing
``ζ(ω_1) = ζ(ω_2) = ζ`` gives ``a = 2 ζ ω_1 ω_2 / (ω_1 + ω_2)``, ``b = 2 ζ / (ω_1 + ω_2)``
(between the two modes the ratio is slightly lower, outside it grows).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from .linalg import sparse_lu

__all__ = ["rayleigh_coefficients", "lowest_frequencies"]


def lowest_frequencies(K, M, n: int) -> np.ndarray:
    """The ``n`` lowest angular frequencies (rad/s) of ``K φ = ω² M φ`` (shift-invert)."""
    N = K.shape[0]
    if N <= 400:
        w2 = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)[:n]
    else:
        lu = sparse_lu(K, symmetric=True, what="stiffness (is the structure clamped?)")
        op = spla.LinearOperator(K.shape, matvec=lu.solve, dtype=float)
        w2 = spla.eigsh(K.tocsc(), k=n, M=M.tocsc(), sigma=0.0, which="LM", OPinv=op)[0]
    return np.sqrt(np.sort(np.abs(w2)))


def rayleigh_coefficients(zeta: float, omega1: float, omega2: float) -> tuple[float, float]:
    """``(a, b)`` with ``ζ(ω_1) = ζ(ω_2) = zeta`` for ``C = a M + b K``."""
    if not (0.0 <= zeta < 1.0):
        raise ValueError(f"damping ratio must be in [0, 1), got {zeta!r}")
    if not (0.0 < omega1 < omega2):
        raise ValueError(f"need 0 < omega1 < omega2, got {omega1!r}, {omega2!r}")
    s = omega1 + omega2
    return 2.0 * zeta * omega1 * omega2 / s, 2.0 * zeta / s
