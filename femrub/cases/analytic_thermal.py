"""Closed-form references of the thermal side and of damping (SI units), used by the tests.

* Heat flux ``Q s(t)`` (W) into the tip of a bar of length ``L`` held at ambient at its root
  (``θ(0, t) = 0``), insulated elsewhere, ``θ(x, 0) = 0``; with ``s(t) = 1 − exp(−t / t_r)``
  (a smooth start) the Fourier series on the modes ``sin(μ_n x)``, ``μ_n = (2n − 1) π / (2L)``,
  ``λ_n = κ μ_n²``, ``κ = k / (ρ c)`` is (Duhamel)::

      θ(x, t) = Σ_n 2 Q (−1)^(n+1) / (ρ c A L) sin(μ_n x) I_n(t)
      I_n(t)  = (1 − e^(−λ_n t)) / λ_n − (e^(−t/t_r) − e^(−λ_n t)) / (λ_n − 1/t_r)

  (its steady state is ``Q x / (k A)``).
* Adiabatic heating of an insulated body: ``Δθ_mean = ∫ Q dt / (m c)``.
* Thermal expansion under a temperature history: a bar clamped at its root, heated
  uniformly at the rate ``r`` (K/s), sees the tip force ``E A α r t`` of its thermal
  stress; the modal solution of that ramp is::

      u(L, t) = α L r t − Σ_n 2 E α r / (ρ L ω_n³) sin(ω_n t),   ω_n = μ_n √(E / ρ)

* Thermoelastic (Zener) damping of a bar clamped at both ends with insulated ends
  (uniaxial stress, ``b = E α``): ``u = U(t) sin(k x)``, ``θ = Θ(t) cos(k x)``,
  ``k = m π / L``, is an exact solution of::

      ρ ü = E u'' − b θ',      ρ c θ̇ = k_th θ'' − T0 b u̇'

  reducing to ``U̇ = V``, ``ρ V̇ = −E k² U + b k Θ``, ``ρ c Θ̇ = −k_th k² Θ − T0 b k V``.
  For a small relaxation strength ``Δ = E α² T0 / (ρ c)`` the decay of the oscillating pair
  is Zener's ``ζ = (Δ / 2) ω τ / (1 + ω² τ²)``, ``τ = ρ c / (k_th k²)``.
* A viscously damped mode: ``q(t) = e^(−ζ ω t) (cos ω_d t + ζ / √(1 − ζ²) sin ω_d t)``,
  ``ω_d = ω √(1 − ζ²)``; Rayleigh damping ``C = a M + b K`` gives ``ζ = a / (2ω) + b ω / 2``.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla

__all__ = [
    "bar_heat_flux_temperature",
    "adiabatic_temperature_rise",
    "heated_bar_tip_displacement",
    "zener_mode_history",
    "zener_damping_ratio",
    "rayleigh_ratio",
    "damped_mode",
]

_TERMS = 4000


def bar_heat_flux_temperature(
    x, t, *, flux, length, conductivity, rho_c, area, ramp_time, terms=_TERMS
) -> np.ndarray:
    """Temperature rise (K) at points ``x`` (m) and times ``t`` (s), shape (len(t), len(x))."""
    x, t = np.atleast_1d(np.asarray(x, float)), np.atleast_1d(np.asarray(t, float))
    n = np.arange(1, terms + 1)
    mu = (2 * n - 1) * math.pi / (2.0 * length)
    lam = conductivity / rho_c * mu**2
    a = 1.0 / ramp_time
    tt = t[:, None]
    integral = (1.0 - np.exp(-lam * tt)) / lam - (np.exp(-a * tt) - np.exp(-lam * tt)) / (lam - a)
    coef = 2.0 * flux * (-1.0) ** (n + 1) / (rho_c * area * length)
    return (integral * coef) @ np.sin(np.outer(mu, x))


def adiabatic_temperature_rise(heat, mass, specific_heat) -> float:
    """Mean temperature rise (K) of an insulated body of ``mass`` (kg) receiving ``heat`` (J)."""
    return heat / (mass * specific_heat)


def heated_bar_tip_displacement(
    t, *, rate, length, young, rho, expansion, terms=_TERMS
) -> np.ndarray:
    """Tip displacement (m) of a root-clamped bar heated uniformly at ``rate`` (K/s)."""
    t = np.atleast_1d(np.asarray(t, float))
    n = np.arange(1, terms + 1)
    w = (2 * n - 1) * math.pi / (2.0 * length) * math.sqrt(young / rho)
    dyn = np.sin(np.outer(t, w)) @ (2.0 * young * expansion * rate / (rho * length * w**3))
    return expansion * length * rate * t - dyn


def _zener_matrix(*, young, rho, rho_c, conductivity, expansion, t0, wavenumber):
    b, k = young * expansion, wavenumber
    return np.array(
        [
            [0.0, 1.0, 0.0],
            [-young * k**2 / rho, 0.0, b * k / rho],
            [0.0, -t0 * b * k / rho_c, -conductivity * k**2 / rho_c],
        ]
    )


def zener_mode_history(t, *, u0, **params) -> np.ndarray:
    """``(U, V, Θ)`` (m, m/s, K) at times ``t`` from ``U(0) = u0``, ``V = Θ = 0``.

    Parameters: ``young, rho, rho_c, conductivity, expansion, t0, wavenumber`` (SI).
    """
    S = _zener_matrix(**params)
    x0 = np.array([u0, 0.0, 0.0])
    return np.array([sla.expm(S * ti) @ x0 for ti in np.atleast_1d(t)])


def zener_damping_ratio(**params) -> tuple[float, float]:
    """``(ζ, ω)`` of the oscillating pair of the exact modal equations (module docstring)."""
    s = np.linalg.eigvals(_zener_matrix(**params))
    s = s[np.argmax(np.abs(s.imag))]
    return float(-s.real / abs(s)), float(abs(s))


def rayleigh_ratio(a: float, b: float, omega) -> np.ndarray:
    """Damping ratio ``a / (2ω) + b ω / 2`` of ``C = a M + b K`` at ``omega`` (rad/s)."""
    omega = np.asarray(omega, float)
    return a / (2.0 * omega) + b * omega / 2.0


def damped_mode(t, omega: float, zeta: float) -> np.ndarray:
    """Free response of a damped mode released from ``q = 1`` at rest."""
    t = np.asarray(t, float)
    wd = omega * math.sqrt(1.0 - zeta**2)
    c = zeta / math.sqrt(1.0 - zeta**2)
    return np.exp(-zeta * omega * t) * (np.cos(wd * t) + c * np.sin(wd * t))
