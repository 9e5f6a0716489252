"""Damping: Rayleigh coefficients that give a modal damping ratio at two modes.

``C = a M + b K`` damps mode ``ω`` with ratio ``ζ(ω) = a / (2 ω) + b ω / 2``; choosing
``ζ(ω_1) = ζ(ω_2) = ζ`` gives ``a = 2 ζ ω_1 ω_2 / (ω_1 + ω_2)``, ``b = 2 ζ / (ω_1 + ω_2)``
(between the two modes the ratio is slightly lower, outside it grows).
"""

from __future__ import annotations

__all__ = ["rayleigh_coefficients"]


def rayleigh_coefficients(zeta: float, omega1: float, omega2: float) -> tuple[float, float]:
    """``(a, b)`` with ``ζ(ω_1) = ζ(ω_2) = zeta`` for ``C = a M + b K``."""
    if not (0.0 <= zeta < 1.0):
        raise ValueError(f"damping ratio must be in [0, 1), got {zeta!r}")
    if not (0.0 < omega1 < omega2):
        raise ValueError(f"need 0 < omega1 < omega2, got {omega1!r}, {omega2!r}")
    s = omega1 + omega2
    return 2.0 * zeta * omega1 * omega2 / s, 2.0 * zeta / s
