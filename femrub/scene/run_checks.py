"""Checks of a whole scene that the runs need, made before any expensive work.

* :func:`check_steps`: ``scheme.t_end`` is a whole number of steps ``scheme.h`` (a stepper
  takes ``round(t_end / h)`` steps: otherwise the run would end short of ``t_end``, or
  past it, and still say ``ok``); the message gives both fixes;
* :func:`check_friction`: the Coulomb coefficient μ (``contact.friction``) is at most
  :data:`MAX_FRICTION` (a percentage or a typing slip, not a material pair);
* :func:`check_bladed_disk`: what a bladed-disk run (``rotor.sectors``) does not model.

:func:`check_run` applies them all; ``femrub run``, ``check`` and ``sweep`` call it on every
scene (every point of a sweep) before building anything.
"""

from __future__ import annotations

import math

from .spec import fail

__all__ = [
    "MAX_FRICTION",
    "check_bladed_disk",
    "check_friction",
    "check_run",
    "check_steps",
    "fractional_steps",
]

#: the largest Coulomb coefficient taken (metals on abradable coatings: about 0.1 to 1)
MAX_FRICTION = 2.0
#: relative tolerance on a whole number of steps (round-off of ``t_end / h``)
WHOLE_STEPS_TOLERANCE = 1e-6


def fractional_steps(span: float, h: float):
    """``None`` when ``span`` (s) is a whole number of steps ``h`` (to
    :data:`WHOLE_STEPS_TOLERANCE`), else ``(n, whole, up)``: the steps ``span / h``, the
    whole number a stepper takes (``round``, at least 1) and the next whole number above.
    A span of zero or less is no step at all: ``None``."""
    if span <= 0:
        return None
    n = span / h
    whole = max(round(n), 1)
    if abs(n - whole) <= WHOLE_STEPS_TOLERANCE * max(n, 1.0):
        return None
    return n, whole, math.ceil(n)


def check_steps(scene) -> None:
    """Refuse a ``scheme.t_end`` that is not a whole number of steps ``scheme.h``."""
    h, t_end = scene.get("scheme.h"), scene.get("scheme.t_end")
    if not all(isinstance(x, int | float) and not isinstance(x, bool) for x in (h, t_end)):
        return
    if h <= 0 or t_end <= 0:
        return
    off = fractional_steps(t_end, h)
    if off is None:
        return
    n, whole, up = off
    fail(
        "scheme.t_end",
        t_end,
        f"{n:.6g} steps of scheme.h = {h:g} s, not a whole number (the run would end at "
        f"{whole * h:.6g} s); use scheme.t_end = {up * h:.6g} s ({up} steps) or "
        f"scheme.h = {t_end / up:.6g} s",
    )


def check_friction(scene) -> None:
    """Refuse a Coulomb coefficient above :data:`MAX_FRICTION`."""
    mu = scene.get("contact.friction")
    if isinstance(mu, int | float) and not isinstance(mu, bool) and mu > MAX_FRICTION:
        fail(
            "contact.friction",
            mu,
            f"a Coulomb coefficient above {MAX_FRICTION:g} is not a material pair (metal on "
            "an abradable coating: 0.1 to 1); give μ itself, not a percentage",
        )


#: what a bladed-disk run does not model, as ``(key, refused when, the value's meaning)``
_WHEEL_REFUSALS = (
    ("loads.tip_force.law", lambda v: v != "none", "no tip force on a bladed disk"),
    ("scheme.name", lambda v: v != "theta", "a bladed disk runs the θ-method"),
)


def check_bladed_disk(scene) -> None:
    """Refuse what a bladed-disk run (``rotor.sectors``, :mod:`femrub.app.wheel`) does not
    model, one key at a time."""
    if scene.get("rotor.sectors") is None:
        return
    for key, refused, why in _WHEEL_REFUSALS:
        value = scene.get(key)
        if value is not None and refused(value):
            fail(key, value, f"{why}; remove it, or remove rotor.sectors to run one blade")
    _check_casing_heat(scene)


def _check_casing_heat(scene) -> None:
    """A bladed disk's casing heat needs frictional heat that reaches the casing: Coulomb
    friction (heat law ``"power"``, a blade's default) or a heat coefficient (``"alpha"``),
    and a blade share ``contact.heat_partition`` below 1."""
    if not (scene.get("contact.casing_heat.thickness") or 0.0) > 0.0:
        return
    law = scene.get("contact.heat_law") or "auto"
    if law == "alpha" and not scene.get("contact.heat_coefficient"):
        fail(
            "contact.heat_coefficient",
            scene.get("contact.heat_coefficient"),
            "no frictional heat reaches the casing (contact.casing_heat); give α > 0",
        )
    if law != "alpha" and not scene.get("contact.friction"):
        fail(
            "contact.friction",
            scene.get("contact.friction"),
            "no frictional heat reaches the casing (contact.casing_heat); give μ > 0",
        )
    eta = scene.get("contact.heat_partition")
    if isinstance(eta, (int, float)) and eta >= 1.0:
        fail(
            "contact.heat_partition",
            eta,
            "the blades take all the frictional heat, none reaches contact.casing_heat; "
            "give a share below 1, or 'effusivity'",
        )


def check_run(scene) -> None:
    """Every check of this module."""
    check_bladed_disk(scene)
    check_steps(scene)
    check_friction(scene)
