"""Closed-form solutions used as references by the tests and the examples (SI units).

* Fixed–free bar: axial frequencies ``ω_k = (2k − 1) π c / (2 L)``, ``c = sqrt(E / ρ)``;
  static tip deflection ``F L / (E A)``; free thermal expansion ``α_th θ L``.
* Elastic bar impacting a rigid obstacle (d'Alembert solution, used as the benchmark of
  Doyen, Ern & Piperno, "Time-integration schemes for the finite element dynamic Signorini
  problem", SIAM J. Sci. Comput. 33 (2011) 223–249): a free bar of length L moving at ``v0``
  towards an obstacle at distance ``d`` touches it at ``d / v0``, stays in contact for
  ``2 L / c`` with a constant force ``ρ c A v0`` (a compression wave runs to the free end and
  back), then leaves with velocity ``−v0``: the rebound is elastic although the contact
  point has no restitution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "fixed_free_frequencies",
    "static_tip_deflection",
    "free_thermal_expansion",
    "BarImpact",
    "bar_impact",
]


def fixed_free_frequencies(length, young, rho, n_modes: int) -> np.ndarray:
    """Angular frequencies (rad/s) of the first ``n_modes`` axial modes of a fixed–free bar."""
    c = math.sqrt(young / rho)
    k = np.arange(1, n_modes + 1)
    return (2 * k - 1) * math.pi * c / (2.0 * length)


def static_tip_deflection(force, length, young, area) -> float:
    """Tip displacement (m) of a bar clamped at its root under an axial tip force."""
    return force * length / (young * area)


def free_thermal_expansion(expansion, temperature_rise, length) -> float:
    """Elongation (m) of a bar uniformly heated by ``temperature_rise`` (K), free to expand."""
    return expansion * temperature_rise * length


@dataclass(frozen=True)
class BarImpact:
    """Exact response of a free elastic bar hitting a rigid obstacle (see module docstring)."""

    contact_start: float
    contact_duration: float
    contact_force: float
    rebound_velocity: float
    impulse: float


def bar_impact(length, young, rho, area, velocity, gap=0.0) -> BarImpact:
    """Contact start (s), duration (s), force (N), rebound velocity (m/s) and impulse (N s)."""
    c = math.sqrt(young / rho)
    force = rho * c * area * velocity
    duration = 2.0 * length / c
    return BarImpact(
        contact_start=gap / velocity,
        contact_duration=duration,
        contact_force=force,
        rebound_velocity=-velocity,
        impulse=force * duration,
    )
