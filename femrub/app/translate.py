"""What a scene means for the builder: the scene as a :class:`~femrub.model.config.RubConfig`.

:func:`rub_config` turns a :class:`~femrub.scene.Scene` once into the frozen, typed
configuration :func:`femrub.model.builder.build_rub` builds (SI units, the scene's ``auto``
choices resolved); the other functions are its parts, pure functions of the scene that hold
the few choices depending on the geometry kind (the bar's coupling, heat law and lumped
total mass).
"""

from __future__ import annotations

import math

from ..contact.casing import casing_profile
from ..contact.casing_heat import effusivity_partition
from ..fem.material import Material
from ..model.config import (
    CasingHeatConfig,
    CoatingConfig,
    ContactConfig,
    ForceConfig,
    ForceLaw,
    RubConfig,
)

__all__ = [
    "ForceLaw",
    "rub_config",
    "area_of",
    "casing_of",
    "centrifugal_of",
    "coupling_of",
    "heat_partition_of",
    "force_law",
    "heat_law_of",
    "material_of",
]


def force_law(scene):
    """``(amplitude N, ForceLaw, ω rad/s or None)`` of the tip force, or ``None``."""
    f = scene["loads"]["tip_force"]
    if f["law"] == "none" or f["amplitude"] == 0.0:
        return None
    omega = None
    if f["law"] == "sin":
        omega, order = f["frequency"], None
        if omega == "rotation":
            order = f["engine_order"]
            omega = order * scene["loads"]["rotation_speed"]
        law = ForceLaw("sin", omega, math.radians(f["phase"]), engine_order=order)
    else:
        law = ForceLaw(f["law"], ramp_time=f.get("ramp_time", 1.0))
    return f["amplitude"], law, omega


def is_bar(scene) -> bool:
    return scene["geometry"]["kind"] == "bar"


def coupling_of(scene) -> str:
    c = scene["physics"]["coupling"]
    return c if c != "auto" else ("paper" if is_bar(scene) else "physical")


def kernel_kinds(scene) -> tuple[str, ...]:
    """The contact kernel families a run of ``scene`` may step with
    (:data:`femrub.contact.activation.KERNEL_KINDS`): one frictionless contact (the bar and
    frictionless blades), Coulomb friction on a blade, and the rub block when the friction
    heats the blade by its power or cuts an abradable coating."""
    c = scene["contact"]
    if is_bar(scene) or not c["friction"]:
        return ("one",)
    coated = c["abradable"]["thickness"] > 0.0
    return ("friction", "rub") if coated or heat_law_of(scene) == "power" else ("friction",)


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


def force_config(scene) -> ForceConfig | None:
    """The tip force of ``loads.tip_force``, or ``None``."""
    force = force_law(scene)
    if force is None:
        return None
    amplitude, signal, omega = force
    d = scene["loads"]["tip_force"]["direction"]
    return ForceConfig(amplitude, signal, omega, d if d == "radial" else tuple(d))


def _coating(scene) -> CoatingConfig | None:
    a = scene["contact"]["abradable"]
    if a["thickness"] <= 0.0:
        return None
    return CoatingConfig(a["thickness"], a["yield"], a["n_angle"], a["n_axial"], a["footprint"])


def _casing_heat(scene) -> CasingHeatConfig | None:
    h = scene["contact"]["casing_heat"]
    if h["thickness"] <= 0.0:
        return None
    keys = ("density", "specific_heat", "conductivity", "expansion", "n_angle", "n_axial")
    return CasingHeatConfig(h["thickness"], **{k: h[k] for k in keys})


def contact_config(scene) -> ContactConfig:
    """The contacts of ``contact.*`` (Coulomb μ only on a 3D blade)."""
    c = scene["contact"]
    return ContactConfig(
        casing=casing_of(scene),
        friction=0.0 if is_bar(scene) else c["friction"],
        heat_law=heat_law_of(scene),
        heat_coefficient=c["heat_coefficient"],
        heat_partition=heat_partition_of(scene),
        restitution=c["restitution"],
        spread=c["spread"],
        reach=c["reach"],
        reach_margin=c["reach_margin"],
        gap_reference=c["gap_reference"],
        clearance=c["clearance"],
        abradable=_coating(scene),
        casing_heat=_casing_heat(scene),
        slip_direction=c["slip_direction"],
    )


def rub_config(scene, deck: dict | None = None, notes: list | None = None) -> RubConfig:
    """The scene as the builder's configuration (module docstring); ``deck``, ``notes``: the
    material read from the mesh file and the notes on it (:func:`material_of`)."""
    p = scene["physics"]
    thermal = {"on": True, "off": False}.get(p["thermal"], "auto")
    return RubConfig(
        material_of(scene, deck, notes),
        contact_config(scene),
        rotation_speed=scene["loads"]["rotation_speed"],
        rotation_direction=scene["loads"]["rotation_direction"],
        order=p["order"],
        clamped=scene["boundary"]["clamped"],
        area=area_of(scene),
        lumping=p["lumping"],
        conduction=p["conduction"],
        coupling=coupling_of(scene),
        beta=p["beta"],
        strain_heating=p["strain_heating"],
        rayleigh=tuple(p["rayleigh"]),
        damping_ratio=p["damping_ratio"],
        damping_modes=tuple(p["damping_modes"]),
        thermal=thermal,
        centrifugal=centrifugal_of(scene),
        tip_force=force_config(scene),
    )
