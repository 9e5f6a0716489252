"""Frictional heat laws: the coefficient ``α_i`` (m/s) of the heat input ``α_i λ_i`` (W).

* ``"alpha"`` (the paper's bar, Eq. 2b): ``α`` given directly, ``f_tip = η α λ``;
* ``"friction"`` (blades): the sliding speed of a contact at radius ``r_i`` is ``|Ω| r_i``
  and Coulomb friction dissipates ``μ |Ω| r_i λ_i``; the blade receives the share ``η``
  (``heat_partition``), the rest goes into the casing: ``α_i = η μ |Ω| r_i``.
"""

from __future__ import annotations

import numpy as np

from ..fem.material import check_finite_positive

__all__ = ["HEAT_LAWS", "heat_coefficients"]

HEAT_LAWS = ("alpha", "friction")


def heat_coefficients(
    radii,
    law: str,
    *,
    alpha: float = 0.0,
    friction: float = 0.0,
    rotation_speed: float = 0.0,
    heat_partition: float = 1.0,
) -> np.ndarray:
    """``α_i`` (m/s) of each contact at ``radii`` (m) under ``law`` (module docstring)."""
    eta = check_finite_positive("heat_partition", heat_partition, allow_zero=True)
    if eta > 1.0:
        raise ValueError(f"heat_partition must be in [0, 1], got {heat_partition!r}")
    radii = np.asarray(radii, dtype=float)
    if law == "alpha":
        a = check_finite_positive("heat coefficient alpha", alpha, allow_zero=True)
        return np.full(radii.shape, eta * a)
    if law == "friction":
        mu = check_finite_positive("friction", friction, allow_zero=True)
        omega = float(rotation_speed)
        if not np.isfinite(omega):
            raise ValueError(f"rotation_speed must be finite (rad/s), got {rotation_speed!r}")
        return eta * mu * abs(omega) * radii
    raise ValueError(f"unknown heat law {law!r}; use one of {', '.join(HEAT_LAWS)}")
