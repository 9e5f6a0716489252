"""What a scene means for the builders: material, casing, heat law, tip force, coupling.

Pure functions of a :class:`~femrub.scene.Scene`, each used once by
:class:`~femrub.app.simulation.Simulation`; they hold the few choices that depend on the
geometry kind (the bar's coupling, heat law and lumped total mass).
"""

from __future__ import annotations

import math

import numpy as np

from ..contact.casing import casing_profile
from ..contact.casing_heat import effusivity_partition
from ..fem.material import Material

__all__ = [
    "ForceLaw",
    "area_of",
    "casing_of",
    "centrifugal_of",
    "coupling_of",
    "heat_partition_of",
    "force_law",
    "heat_law_of",
    "material_of",
    "thermal_choice",
]


class ForceLaw:
    """Time signal of the tip force, times its amplitude (``law`` of ``loads.tip_force``)."""

    def __init__(self, law: str, omega: float = 0.0, phase: float = 0.0, ramp_time: float = 1.0):
        self.law, self.omega, self.phase, self.ramp_time = law, omega, phase, ramp_time

    def __call__(self, t):
        if self.law == "sin":
            return np.sin(self.omega * t + self.phase)
        if self.law == "ramp":
            return np.minimum(np.asarray(t, dtype=float) / self.ramp_time, 1.0)
        return np.ones_like(np.asarray(t, dtype=float))


def force_law(scene):
    """``(amplitude N, ForceLaw, ω rad/s or None)`` of the tip force, or ``None``."""
    f = scene["loads"]["tip_force"]
    if f["law"] == "none" or f["amplitude"] == 0.0:
        return None
    omega = None
    if f["law"] == "sin":
        omega = f["frequency"]
        if omega == "rotation":
            omega = f["engine_order"] * scene["loads"]["rotation_speed"]
        law = ForceLaw("sin", omega, math.radians(f["phase"]))
    else:
        law = ForceLaw(f["law"], ramp_time=f.get("ramp_time", 1.0))
    return f["amplitude"], law, omega


def force_direction(scene, points) -> np.ndarray:
    """Unit direction of the tip force: given, or the mean radial direction of the contacts."""
    d = scene["loads"]["tip_force"]["direction"]
    d = points.normals.mean(axis=1) if d == "radial" else np.asarray(d, dtype=float)
    if not np.linalg.norm(d) > 0:
        raise ValueError("loads.tip_force.direction = [0, 0, 0]: give a non-zero vector")
    return d / np.linalg.norm(d)


def is_bar(scene) -> bool:
    return scene["geometry"]["kind"] == "bar"


def coupling_of(scene) -> str:
    c = scene["physics"]["coupling"]
    return c if c != "auto" else ("paper" if is_bar(scene) else "physical")


def heat_law_of(scene) -> str:
    """``"alpha"`` (α given; the bar's default) or ``"power"`` (η × friction power; blades)."""
    law = scene["contact"].get("heat_law", "auto")
    if law == "auto":
        return "alpha" if is_bar(scene) else "power"
    if law == "power" and is_bar(scene):
        from ..scene.spec import fail

        fail("contact.heat_law", law, "the bar has no tangential friction; use 'alpha'")
    return law


def centrifugal_of(scene) -> str | None:
    """Prestress method (``"linear"``/``"nonlinear"``) at the scene's speed, or ``None``."""
    mode = scene["loads"]["centrifugal"]
    if mode == "off" or is_bar(scene) or scene["loads"]["rotation_speed"] == 0.0:
        return None
    return "nonlinear" if mode == "auto" else mode


def heat_partition_of(scene) -> float:
    """Share η of the frictional power entering the blade (``contact.heat_partition``)."""
    c, m = scene["contact"], scene["material"]
    eta = c["heat_partition"]
    if eta == "auto":
        eta = "effusivity" if c["casing_heat"]["thickness"] > 0.0 else 1.0
    if eta == "effusivity":
        h = c["casing_heat"]
        return effusivity_partition(
            (m["conductivity"], m["density"], m["specific_heat"]),
            (h["conductivity"], h["density"], h["specific_heat"]),
        )
    return float(eta)


def area_of(scene) -> float:
    """Cross-section of the bar (m²); 1 for a solid."""
    return scene["geometry"]["area"] if is_bar(scene) else 1.0


def material_of(scene, deck: dict | None = None, notes: list | None = None) -> Material:
    """Material of the scene; a bar with ``total_mass`` spreads that mass along its length.

    ``deck``: material read from the mesh file (SI, keys of ``[material]``); it replaces the
    scene's defaults, while values the scene sets itself win, each with a line in ``notes``.
    """
    m, g = dict(scene["material"]), scene["geometry"]
    for key, value in (deck or {}).items():
        if f"material.{key}" not in scene.given:
            m[key] = value
        elif notes is not None and not math.isclose(m[key], value, rel_tol=1e-9):
            notes.append(f"material.{key} = {m[key]:.6g} (scene) overrides {value:.6g} (mesh file)")
    if deck and notes is not None:
        used = sorted(k for k in deck if f"material.{k}" not in scene.given)
        if used:
            notes.append(f"material from the mesh file: {', '.join(used)}")
    rho = m["density"]
    if is_bar(scene) and g["total_mass"] != "density":
        rho = g["total_mass"] / (g["area"] * g["length"])
    return Material(
        young=m["young"],
        rho=rho,
        poisson=m["poisson"],
        rho_c=m["density"] * m["specific_heat"],
        conductivity=m["conductivity"],
        expansion=m["expansion"],
        reference_temperature=m["reference_temperature"],
    )


def casing_of(scene):
    params = dict(scene["contact"]["casing"])
    kind = params.pop("kind")
    if "phase" in params:
        params["phase"] = math.radians(params["phase"])
    return casing_profile(kind, **params)


def thermal_choice(scene, heated: bool, reachable: bool = True) -> tuple[bool, str]:
    """Keep the temperature dofs? ``heated``: frictional heat on a reachable contact.

    ``reachable=False`` says that there is no contact the casing can reach.
    """
    mode = scene["physics"]["thermal"]
    coupling = coupling_of(scene)
    if mode == "on":
        return True, f"kept (physics.thermal = 'on'; coupling {coupling!r})"
    if mode == "off":
        return False, "dropped (physics.thermal = 'off': frictional heat and coupling ignored)"
    sources = ["frictional heat at the contacts"] if heated else []
    if scene["physics"]["strain_heating"] and coupling != "none":
        sources.append("strain-rate heating")
    if sources:
        return True, f"kept: {' and '.join(sources)} (coupling {coupling!r})"
    c = scene["contact"]
    if not reachable:
        why = "no contact the casing can reach"
    elif heat_partition_of(scene) == 0.0:
        why = "contact.heat_partition = 0"
    elif is_bar(scene):
        why = "contact.heat_coefficient = 0"
    elif c["friction"] == 0.0:
        why = "contact.friction = 0"
    else:
        why = "loads.rotation_speed = 0 (no sliding)"
    return False, f"dropped: no heat source ({why}); the coupling has nothing to act on"
