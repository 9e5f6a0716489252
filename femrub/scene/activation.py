"""The θ-method's activation rule against the scene's friction (``scheme.activation``).

Only the rules of :data:`femrub.contact.activation.FRICTIONAL_RULES` choose the contacts of
the frictional solve; a scene asking for another one with ``contact.friction > 0`` is
refused before anything is built. Without the key the stepper takes the default of its
contacts (``"position"``, or ``"paper"`` with friction), which ``femrub run --explain``
prints.
"""

from __future__ import annotations

from ..contact.activation import frictionless_only
from .spec import fail

__all__ = ["check_activation"]


def check_activation(d: dict) -> None:
    """Raise a one-line :class:`~femrub.scene.spec.SceneError` naming ``scheme.activation``
    when the normalised scene ``d`` asks the θ-method for a rule without a frictional form
    on frictional contacts."""
    scheme, friction = d["scheme"], d["contact"]["friction"]
    rule = scheme.get("activation") if scheme["name"] == "theta" else None
    why = frictionless_only(rule) if rule is not None and friction > 0.0 else None
    if why:
        fail("scheme.activation", rule, f"{why}, or contact.friction = 0 (now {friction:g})")
