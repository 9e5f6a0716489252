"""The scene schema of a bladed disk (``rotor``) and a flexible casing ring (``casing.ring``).

Part of :data:`femrub.scene.schema.SCHEMA`. A scene with ``rotor.sectors = N`` is a bladed
disk of ``N`` blades: the blade is the scene's ``geometry`` (``kind = "naca"``, its
``hub_radius`` replaced by the disk's rim; or ``kind = "sections"``, the section files turned
about the axis onto the sector and extended into the rim), the disk an annulus clamped at
its bore.
``casing.ring.thickness`` adds a flexible casing ring around the blades' tips. Both feed
``femrub modes`` (:mod:`femrub.app.modes`) and ``femrub run`` (:mod:`femrub.app.wheel`,
which refuses what it does not model: :func:`femrub.scene.run_checks.check_run`).
:func:`check_rotor` is the cross-key check, made when the scene is loaded.
"""

from __future__ import annotations

from .spec import NONNEG, POS, Spec, fail
from .spec import float_spec as _f

__all__ = ["CASING_SECTION", "ROTOR", "check_rotor"]

I = "int"  # noqa: E741 (the schema's one-letter type names)

ROTOR = {
    "sectors": Spec(
        I, None, lo=3, hi=360, doc="number of blades N of a bladed disk (unset: a single blade)"
    ),
    "hub_radius": _f(0.05, "length", "radius of the disk's bore (clamped)", **POS),
    "rim_radius": _f(0.15, "length", "radius of the disk's rim, where the blades stand", **POS),
    "thickness": _f(0.04, "length", "axial thickness of the disk", **POS),
    "h": _f(
        None,
        "length",
        "element size of the sector mesh (default: geometry.h, else a third of the disk's "
        "thickness)",
        **POS,
    ),
    "families": Spec(I, 3, lo=1, hi=30, doc="mode families computed per nodal diameter"),
    "contacts": Spec(I, 3, lo=1, hi=20, doc="contacts on each blade's tip, along its chord"),
    "thermal_families": Spec(
        I,
        6,
        lo=1,
        hi=30,
        doc="thermal modes per nodal diameter of the blades' temperature (with the tip "
        "contacts' static heat shapes; a run with temperature dofs)",
    ),
    "damping_ratio": _f(
        0.01, "none", "modal damping ratio of the disk's modes (time integration)", lo=0.0, hi=1.0
    ),
    "mistuning": Spec(
        "floats",
        None,
        lo=-1.0,
        lo_open=True,
        doc="per-blade stiffness factors δ_s: blade s's elastic stiffness times 1 + δ_s "
        "(unset: tuned)",
    ),
}

CASING_RING = {
    "thickness": _f(
        None, "length", "radial wall thickness of a flexible casing ring (unset: no ring)", **POS
    ),
    "axial_length": _f(0.1, "length", "axial length between the clamped flanges", **POS),
    "clearance": _f(
        5e-4, "length", "radial gap from the blades' tip radius to the ring's bore", **NONNEG
    ),
    "lobes": Spec(
        I, 0, lo=0, hi=100, doc="order k of the ring's initial out-of-roundness (0: round)"
    ),
    "distortion": _f(0.0, "length", "radial amplitude of the k-lobed out-of-roundness", **NONNEG),
    "young": _f(200e9, "pressure", "Young's modulus of the ring", **POS),
    "poisson": _f(
        0.3, "none", "Poisson's ratio of the ring", lo=-1.0, hi=0.5, lo_open=True, hi_open=True
    ),
    "density": _f(7800.0, "density", "mass density of the ring", **POS),
    "h": _f(
        None, "length", "element size (default: the larger of thickness and axial_length/6)", **POS
    ),
    "families": Spec(I, 3, lo=1, hi=30, doc="mode families computed per nodal diameter"),
    "phase": _f(0.0, "angle", "angle of the first lobe's crest (the widest bore)"),
    "damping_ratio": _f(
        0.01, "none", "modal damping ratio of the ring's modes (time integration)", lo=0.0, hi=1.0
    ),
    "ramp": _f(
        None,
        "time",
        "time over which the out-of-roundness grows from zero (default: two revolutions)",
        **NONNEG,
    ),
}

CASING_SECTION = {"ring": CASING_RING}


def check_rotor(d: dict) -> None:
    """Refuse a bladed disk or casing ring whose keys contradict each other (one line)."""
    rotor, ring = d["rotor"], d["casing"]["ring"]
    _check_mistuning(rotor)
    if rotor.get("sectors") is None:
        if ring.get("thickness") is not None:
            fail(
                "casing.ring.thickness",
                ring["thickness"],
                "a casing ring surrounds a bladed disk; set rotor.sectors (the number of "
                "blades) or remove casing.ring",
            )
        return
    if d["geometry"]["kind"] not in ("naca", "sections"):
        fail(
            "geometry.kind",
            d["geometry"]["kind"],
            "the blades of a bladed disk (rotor.sectors) are NACA blades or lofted through "
            "section files; use geometry.kind = 'naca' or 'sections'",
        )
    if not rotor["rim_radius"] > rotor["hub_radius"]:
        fail(
            "rotor.rim_radius",
            rotor["rim_radius"],
            f"must exceed rotor.hub_radius = {rotor['hub_radius']:g} m",
        )
    if ring.get("thickness") is not None and ring["distortion"] > 0 and ring["lobes"] == 0:
        fail(
            "casing.ring.distortion",
            ring["distortion"],
            "an out-of-roundness needs its order: set casing.ring.lobes >= 1",
        )


def _check_mistuning(rotor: dict) -> None:
    """``rotor.mistuning``: one factor per blade of a bladed disk."""
    factors, n = rotor.get("mistuning"), rotor.get("sectors")
    if factors is None:
        return
    if n is None:
        fail(
            "rotor.mistuning",
            factors,
            "per-blade stiffness factors need a bladed disk; set rotor.sectors (the number of "
            "blades) or remove rotor.mistuning",
        )
    if len(factors) != n:
        fail(
            "rotor.mistuning",
            factors,
            f"give one factor δ_s per blade: {n} numbers (rotor.sectors = {n}), not "
            f"{len(factors)}; 0 for a blade as designed",
        )
