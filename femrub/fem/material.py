"""Isotropic thermoelastic material, SI units.

The inertial density ``rho`` and the volumetric heat capacity ``rho_c`` are separate
parameters: the paper's bar spreads a total mass of 0.1 kg along a 0.3 m bar of 1 mm², an
effective density far above the 4500 kg/m³ used for its heat capacity (model notes).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

__all__ = ["Material", "check_finite_positive"]


def check_finite_positive(name: str, value: float, *, allow_zero: bool = False) -> float:
    """Return ``float(value)`` or raise a one-line ``ValueError`` naming ``name``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if x < 0.0 or (x == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be {bound}, got {value!r}")
    return x


@dataclass(frozen=True)
class Material:
    """Isotropic linear thermoelastic material.

    Parameters
    ----------
    young : Young's modulus E (Pa).
    rho : mass density used for the mass matrix (kg/m³).
    poisson : Poisson's ratio ν (ignored in 1D, uniaxial stress).
    rho_c : volumetric heat capacity ρ c (J/(m³ K)).
    conductivity : thermal conductivity λ_th (W/(m K)).
    expansion : linear thermal expansion coefficient α_th (1/K).
    reference_temperature : absolute temperature T0 (K) around which θ is the rise.
    """

    young: float
    rho: float
    poisson: float = 0.3
    rho_c: float = 4500.0 * 585.0
    conductivity: float = 3.35
    expansion: float = 8.6e-6
    reference_temperature: float = 293.15

    def __post_init__(self):
        check_finite_positive("material.young", self.young)
        check_finite_positive("material.rho", self.rho)
        check_finite_positive("material.rho_c", self.rho_c)
        check_finite_positive("material.conductivity", self.conductivity, allow_zero=True)
        check_finite_positive("material.reference_temperature", self.reference_temperature)
        if not (-1.0 < float(self.poisson) < 0.5):
            raise ValueError(f"material.poisson must be in (-1, 0.5), got {self.poisson!r}")
        if not math.isfinite(float(self.expansion)):
            raise ValueError(f"material.expansion must be finite, got {self.expansion!r}")

    def as_dict(self) -> dict:
        return asdict(self)
