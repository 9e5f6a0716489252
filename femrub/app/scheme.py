"""The scene's time scheme: the stepper options of ``scheme.*`` and the stepper itself.

:func:`stepper_of` also checks the step against Carpenter's stability limit before any step
and records the scheme in the build report (``femrub run SCENE --explain``).
"""

from __future__ import annotations

import math

from ..analysis.steppers import make_stepper
from ..scene.spec import SceneError, fail

__all__ = ["bare_stepper", "scheme_options", "stepper_of"]


def scheme_options(scene) -> dict:
    s = scene["scheme"]
    if s["name"] == "theta":
        return {
            "gamma": s["gamma"],
            "gamma_thermal": s.get("gamma_thermal"),
            "activation": s.get("activation"),
        }
    if s["name"] == "penalty":
        return {"stiffness": s["stiffness"], "damping": s["damping"], "method": s["method"]}
    if s["name"] == "exponential":
        return {"events": s["events"]}
    return {}


def bare_stepper(scene, model, h=None):
    """The scene's stepper on ``model`` at ``scheme.h`` (or at the step ``h``)."""
    s = scene["scheme"]
    try:
        return make_stepper(s["name"], model, s["h"] if h is None else h, **scheme_options(scene))
    except ValueError as exc:
        if "Delassus" in str(exc):
            c = scene["contact"]
            where = c.get("nodes") if c.get("nodes") is not None else c["group"]
            raise SceneError(
                f"contact ({where!r}): the contact cannot take an impulse (its Delassus "
                "operator is not positive): a contact point that does not move (clamped, or "
                "on dofs the reduction removed); choose free contact nodes or "
                "reduction.method = 'none'"
            ) from None
        raise SceneError(f"scheme ({s['name']}): {exc}") from None


def stepper_of(scene, model, report):
    s = scene["scheme"]
    options = scheme_options(scene)
    stepper = bare_stepper(scene, model)
    report["scheme"] = {
        "name": s["name"],
        "h": s["h"],
        "t_end": s["t_end"],
        "steps": stepper.steps_to(s["t_end"]),
        **{k: v for k, v in options.items() if v is not None},
    }
    if hasattr(stepper, "activation"):  # the rule that runs (the default of the contacts)
        report["scheme"]["activation"] = stepper.activation
    if s["name"] == "carpenter":
        limit = stepper.stability_limit()
        report["scheme"]["stability_limit"] = limit
        if s["h"] > limit:
            fail(
                "scheme.h",
                s["h"],
                f"exceeds the stability limit {limit:.3g} s of Carpenter's "
                f"explicit scheme for this model; use scheme.h <= {_floor(limit)} or "
                "scheme.name = 'theta'",
            )
    return stepper


def _floor(x: float) -> str:
    """``x`` rounded down to 2 significant digits, as text."""
    e = math.floor(math.log10(x))
    return f"{math.floor(x / 10**e * 10) / 10 * 10**e:.2g}"
