"""Physical quantities in scene files: plain numbers are SI, strings carry a unit.

A quantity is either a plain number in the SI unit of its dimension (``15e-6`` for a
length in m) or a string ``"<number> <unit>"`` (``"15 um"``, ``"2000 rpm"``, ``"110 GPa"``).
Angles are the one exception to "plain numbers are SI": like gmsh and CAD tools, a plain
angle is in degrees (``"0.35 rad"`` is accepted too). A string must carry its unit: a
quoted number without one (``clearance = "15"``) is refused, since its writer most likely
meant a unit other than SI. :func:`to_si` converts and raises a
one-line :class:`ValueError` naming the allowed units otherwise.

:func:`convert` is the one conversion of a number in a unit to SI, used by the scene files
and by the Python presets alike (:func:`rpm`, ``femrub.cases.bar``): a decimal factor
(``um``, ``GPa``) gives the nearest double to the decimal result (``15 um`` is ``1.5e-05``,
not ``1.4999999999999999e-05``), any other factor (``rpm``, ``Hz``, ``rad``) the product
itself, so ``"2000 rpm"`` in a scene and ``rpm(2000)`` in Python are the same double.
"""

from __future__ import annotations

import math
import re

__all__ = ["UNITS", "SI_LABEL", "convert", "rpm", "to_si"]

_TWO_PI = 2.0 * math.pi

#: dimension -> {unit: factor to the SI unit}
UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9},
    "area": {"m2": 1.0, "m^2": 1.0, "cm2": 1e-4, "cm^2": 1e-4, "mm2": 1e-6, "mm^2": 1e-6},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6, "ns": 1e-9},
    "angular_speed": {"rad/s": 1.0, "rpm": _TWO_PI / 60.0, "Hz": _TWO_PI, "rev/s": _TWO_PI},
    "angle": {"deg": 1.0, "rad": 180.0 / math.pi},
    "force": {"N": 1.0, "kN": 1e3, "mN": 1e-3},
    "mass": {"kg": 1.0, "g": 1e-3},
    "pressure": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9},
    "density": {"kg/m3": 1.0, "kg/m^3": 1.0, "g/cm3": 1e3, "g/cm^3": 1e3},
    "temperature": {"K": 1.0},
    "specific_heat": {"J/(kg K)": 1.0, "J/kg/K": 1.0},
    "conductivity": {"W/(m K)": 1.0, "W/m/K": 1.0},
    "expansion": {"1/K": 1.0},
    "velocity": {"m/s": 1.0},
    "length_per_K": {"m/K": 1.0},
    "stiffness": {"N/m": 1.0, "N/mm": 1e3, "N/um": 1e6},
    "damping": {"N s/m": 1.0},
    "rate": {"1/s": 1.0},
    "none": {},
}

#: dimension -> the unit of plain numbers (for messages and docs)
SI_LABEL = {
    "length": "m",
    "area": "m^2",
    "time": "s",
    "angular_speed": "rad/s",
    "angle": "deg",
    "force": "N",
    "mass": "kg",
    "pressure": "Pa",
    "density": "kg/m^3",
    "temperature": "K",
    "specific_heat": "J/(kg K)",
    "conductivity": "W/(m K)",
    "expansion": "1/K",
    "velocity": "m/s",
    "length_per_K": "m/K",
    "stiffness": "N/m",
    "damping": "N s/m",
    "rate": "1/s",
    "none": "-",
}

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf|nan"
_QUANTITY = re.compile(rf"^\s*({_NUMBER})\s*(.*?)\s*$")


def to_si(value, dim: str) -> float:
    """Return the SI value of a quantity of dimension ``dim``.

    Parameters
    ----------
    value : int, float or str
        A plain number (SI unit of ``dim``; degrees for angles) or ``"<number> <unit>"``.
    dim : str
        A key of :data:`UNITS`.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        One line: wrong type, unparsable string or a unit of another dimension.
    """
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ValueError(f"expected a number in {SI_LABEL[dim]}, got {type(value).__name__}")
    if not isinstance(value, str):
        return float(value)
    match = _QUANTITY.match(value)
    units = UNITS[dim]
    allowed = ", ".join(units) if units else "none (a plain number)"
    if match is None:
        raise ValueError(f"expected a number or '<number> <unit>' with unit in {allowed}")
    number, unit = float(match.group(1)), match.group(2)
    if not unit:
        if units and dim != "angle":  # "15" in quotes is a unit slip, not 15 m
            si = SI_LABEL[dim]
            raise ValueError(
                f"{value!r} is a string without a unit: write '{match.group(1)} {si}' with "
                f"the intended unit ({allowed}) or a plain number in {si}"
            )
        return number
    if unit not in units:
        raise ValueError(f"unit {unit!r} is not a unit of {dim.replace('_', ' ')}; use {allowed}")
    return convert(number, unit, dim)


def _is_decimal(factor: float) -> bool:
    """Whether ``factor`` is a decimal number of at most 15 significant digits."""
    return float(f"{factor:.15g}") == factor


def convert(number: float, unit: str, dim: str) -> float:
    """``number`` in ``unit`` (a unit of dimension ``dim``) in SI (module docstring)."""
    factor = UNITS[dim][unit]
    value = float(number) * factor
    if _is_decimal(factor) and math.isfinite(value):
        return float(f"{value:.15g}")
    return value


def rpm(value: float) -> float:
    """Revolutions per minute in rad/s (the scene's ``"<value> rpm"``).

    ``Ω = 2π value / 60``: ``rpm(2000.0)`` is the paper's rotation speed, 209.44 rad/s.

    Parameters
    ----------
    value : float
        Speed (rev/min).

    Returns
    -------
    float
        Angular speed (rad/s).
    """
    return convert(value, "rpm", "angular_speed")
