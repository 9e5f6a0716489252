"""Physical bounds of dimensional scene values: a unit error is refused before any work.

A length of 1e-200 m or a Young's modulus of 1e-300 Pa is no material or blade: it is a
unit slip (``15e-6`` meant as µm written in a key that wants metres, a value in mm given
as m, ...), and left alone it surfaces much later as a singular matrix that names no key.
:func:`check_physical` refuses a non-zero value whose magnitude lies outside the range of
its dimension (:data:`PHYSICAL_BOUNDS`, SI units), naming the key and the range. The upper
bound applies to every key of the dimension; the lower bound only to keys that must be
strictly positive (a length, a modulus, a time step: a vanishing value makes a matrix
singular), not to those that may be zero (a clearance of 1e-30 m is a zero clearance).
"""

from __future__ import annotations

import math

from .spec import Spec, fail
from .units import SI_LABEL

__all__ = ["PHYSICAL_BOUNDS", "check_physical"]

#: dimension -> (smallest, largest) magnitude of a non-zero value (SI units)
PHYSICAL_BOUNDS: dict[str, tuple[float, float]] = {
    "length": (1e-9, 1e3),
    "area": (1e-16, 1e2),
    "time": (1e-12, 1e7),
    "angular_speed": (1e-6, 1e6),
    "force": (1e-9, 1e9),
    "mass": (1e-9, 1e6),
    "pressure": (1e3, 1e13),
    "density": (1e-2, 1e5),
    "temperature": (1e-3, 1e5),
    "specific_heat": (1e-1, 1e6),
    "conductivity": (1e-6, 1e5),
    "expansion": (1e-12, 1e-2),
    "velocity": (1e-9, 1e4),
    "length_per_K": (1e-15, 1e-2),
    "stiffness": (1e-3, 1e16),
    "damping": (1e-6, 1e12),
    "rate": (1e-9, 1e9),
}


def check_physical(key: str, spec: Spec, value) -> None:
    """Raise a one-line ``SceneError`` when a dimensional ``value`` of ``key`` is out of bounds.

    ``value`` is the normalised (SI) value of a float, pair, vec3 or floats key; words (``"auto"``)
    and dimensionless keys pass.
    """
    bounds = PHYSICAL_BOUNDS.get(spec.dim)
    if bounds is None or spec.kind not in ("float", "pair", "vec3", "floats"):
        return
    items = value if isinstance(value, list) else [value]
    for i, x in enumerate(items):
        if isinstance(x, bool) or not isinstance(x, int | float) or x == 0 or not math.isfinite(x):
            continue
        lo, hi = bounds
        positive = spec.lo == 0.0 and spec.lo_open
        if abs(x) > hi or (positive and abs(x) < lo):
            unit = SI_LABEL[spec.dim]
            where = f"{key}[{i}]" if isinstance(value, list) else key
            bound = f"{lo:g} to {hi:g}" if positive else f"at most {hi:g}"
            fail(
                where,
                x,
                f"outside the physical range {bound} {unit} (in magnitude) of a "
                f"{spec.dim.replace('_', ' ')}; check the unit (e.g. '15 um', '2000 rpm')",
            )
