"""The typed configuration of a rub model: what :func:`femrub.model.builder.build_rub` builds.

A scene (:func:`femrub.app.translate.rub_config`), the paper's bar
(:func:`femrub.cases.bar.bar_model`) and a blade built in Python
(:func:`femrub.model.rub.solid_model`) are each turned once into a :class:`RubConfig`:
frozen, SI units only (rotation speeds in rad/s, lengths in m, angles in rad), every choice
the scene leaves to ``"auto"`` resolved except the ones that need the mesh (the element
order of a bar, the lumping of an element order). The same configuration on the same mesh
gives the same model whichever door it came in by.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from ..contact.casing import SLIP_DIRECTIONS, CasingProfile, Concentric
from ..fem.material import Material
from ..geometry.rotation_direction import ROTATION_DIRECTIONS

__all__ = [
    "CasingHeatConfig",
    "CoatingConfig",
    "ContactConfig",
    "ForceConfig",
    "ForceLaw",
    "HEAT_LAWS",
    "RubConfig",
]

#: frictional heat laws of a contact: ``α λ`` (the bar) or ``η`` × friction power (blades)
HEAT_LAWS = ("alpha", "power")


class ForceLaw:
    """Time signal of the tip force per unit amplitude: ``"sin"`` (``sin(ω t + phase)``, ω in
    rad/s, phase in rad), ``"ramp"`` (``min(t / ramp_time, 1)``) or ``"constant"`` (1).

    ``engine_order`` k: ω is k Ω, and :meth:`at_rotation_speed` follows a new Ω
    (:meth:`femrub.model.first_order.FirstOrderModel.with_parameters`).
    """

    def __init__(
        self,
        law: str,
        omega: float = 0.0,
        phase: float = 0.0,
        ramp_time: float = 1.0,
        engine_order: int | None = None,
    ):
        self.law, self.omega, self.phase, self.ramp_time = law, omega, phase, ramp_time
        self.engine_order = engine_order

    def at_rotation_speed(self, omega: float) -> ForceLaw:
        """This signal at the rotation speed ``omega`` (rad/s): itself unless ω = k Ω."""
        if self.engine_order is None:
            return self
        return ForceLaw(
            self.law, self.engine_order * omega, self.phase, self.ramp_time, self.engine_order
        )

    def __call__(self, t):
        if self.law == "sin":
            return np.sin(self.omega * t + self.phase)
        if self.law == "ramp":
            return np.minimum(np.asarray(t, dtype=float) / self.ramp_time, 1.0)
        return np.ones_like(np.asarray(t, dtype=float))


@dataclass(frozen=True)
class ForceConfig:
    """The tip force ``amplitude × signal(t)`` (N) along ``direction``.

    ``direction``: ``"radial"`` (the mean normal of the contact candidates; the bar's axis)
    or a vector of the blade's dimension; ``frequency``: ω (rad/s) of a harmonic signal, or
    ``None`` (the reach filter's harmonic deflection).
    """

    amplitude: float
    signal: Callable
    frequency: float | None = None
    direction: str | tuple = "radial"


@dataclass(frozen=True)
class CoatingConfig:
    """An abradable coating (:class:`~femrub.contact.abradable.Abradable`): thickness (m),
    yield force per contact (N), wear-map cells, footprint (m)."""

    thickness: float
    yield_force: float
    n_angle: int = 360
    n_axial: int = 16
    footprint: float = 0.0


@dataclass(frozen=True)
class CasingHeatConfig:
    """The lumped casing thermal model (:class:`~femrub.contact.casing_heat.CasingHeat`):
    wall thickness (m), density (kg/m³), specific heat (J/(kg K)), conductivity (W/(m K)),
    expansion (1/K), casing cells."""

    thickness: float
    density: float = 7800.0
    specific_heat: float = 460.0
    conductivity: float = 15.0
    expansion: float = 12e-6
    n_angle: int = 360
    n_axial: int = 16


@dataclass(frozen=True)
class ContactConfig:
    """The contacts of a rub model.

    Parameters
    ----------
    casing : the rigid casing profile swept at the rotation speed.
    friction : Coulomb μ (3D blades; the bar has no tangent plane).
    heat_law : ``"alpha"`` (heat ``η α λ``) or ``"power"`` (``η`` × friction power).
    heat_coefficient : α (m/s) of the ``"alpha"`` law.
    heat_partition : η, the blade's share of the frictional heat.
    restitution : Newton's e.
    spread : ``"patch"`` or ``"node"`` (:func:`~femrub.contact.points.locate_contacts`).
    reach : a length (m), ``"auto"`` or ``"all"`` (keep every candidate): the reach filter
        (:func:`~femrub.contact.reach.contact_reach`), with ``reach_margin`` (m),
        ``gap_reference`` and ``clearance`` (``"running"`` or ``"cold"``).
    abradable, casing_heat : :class:`CoatingConfig`, :class:`CasingHeatConfig` or ``None``.
    slip_direction : ``"rotation"`` (the casing slides past the blade against its motion)
        or ``"reversed"`` (against the lobe phase: a verification device,
        :mod:`femrub.contact.casing`).
    """

    casing: CasingProfile = field(default_factory=lambda: Concentric(1e-4))
    friction: float = 0.0
    heat_law: str = "alpha"
    heat_coefficient: float = 0.0
    heat_partition: float = 1.0
    restitution: float = 0.0
    spread: str = "patch"
    reach: float | str = "auto"
    reach_margin: float = 0.0
    gap_reference: str = "per-node"
    clearance: str = "running"
    abradable: CoatingConfig | None = None
    casing_heat: CasingHeatConfig | None = None
    slip_direction: str = "rotation"

    def __post_init__(self):
        if self.slip_direction not in SLIP_DIRECTIONS:
            raise ValueError(
                f"slip_direction must be one of {tuple(SLIP_DIRECTIONS)}, got "
                f"{self.slip_direction!r}"
            )
        if self.heat_law not in HEAT_LAWS:
            raise ValueError(f"heat_law must be one of {HEAT_LAWS}, got {self.heat_law!r}")
        eta = float(self.heat_partition)
        if not 0.0 <= eta <= 1.0:
            raise ValueError(f"heat_partition must be in [0, 1], got {self.heat_partition!r}")
        if not (math.isfinite(float(self.friction)) and self.friction >= 0.0):
            raise ValueError(f"friction must be finite and >= 0, got {self.friction!r}")
        if isinstance(self.reach, str) and self.reach not in ("auto", "all"):
            raise ValueError(f"reach must be a length (m), 'auto' or 'all', got {self.reach!r}")


@dataclass(frozen=True)
class RubConfig:
    """Everything :func:`~femrub.model.builder.build_rub` needs besides the mesh (SI units).

    Parameters
    ----------
    material : the blade's :class:`~femrub.fem.material.Material`.
    contact : :class:`ContactConfig`.
    rotation_speed : Ω (rad/s).
    rotation_direction : ``"counterclockwise"`` or ``"clockwise"`` about the machine axis, or
        ``"auto"``: derived from the blade's tip section where it can be
        (:mod:`femrub.geometry.rotation_direction`), counterclockwise otherwise.
    order : displacement element order of a 3D blade (the bar is linear).
    clamped : clamp the root (the bar may be free).
    area : cross-section of the bar (m²); 1 for a solid.
    lumping, conduction, coupling, beta, strain_heating, rayleigh : the assembly's
        (:func:`~femrub.fem.discretisation.assemble`); ``coupling`` resolved
        (``"none"``, ``"paper"`` or ``"physical"``).
    damping_ratio, damping_modes : modal Rayleigh damping (0: off).
    thermal : ``"auto"`` (temperature dofs when something heats the blade), ``True`` or
        ``False``.
    centrifugal : prestress method at Ω (``"linear"``, ``"nonlinear"``) or ``None``.
    tip_force : :class:`ForceConfig` or ``None``.
    initial_velocity : uniform initial velocity of the displacement dofs (m/s; the bar's
        impact benchmark).
    """

    material: Material
    contact: ContactConfig = field(default_factory=ContactConfig)
    rotation_speed: float = 0.0
    rotation_direction: str = "auto"
    order: int = 2
    clamped: bool = True
    area: float = 1.0
    lumping: str = "auto"
    conduction: str = "galerkin"
    coupling: str = "physical"
    beta: float | None = None
    strain_heating: bool = False
    rayleigh: tuple = (0.0, 0.0)
    damping_ratio: float = 0.0
    damping_modes: tuple = (1, 5)
    thermal: str | bool = "auto"
    centrifugal: str | None = None
    tip_force: ForceConfig | None = None
    initial_velocity: float = 0.0

    def __post_init__(self):
        if not math.isfinite(float(self.rotation_speed)):
            raise ValueError(f"rotation_speed must be finite (rad/s), got {self.rotation_speed!r}")
        if self.rotation_direction not in ("auto", *ROTATION_DIRECTIONS):
            raise ValueError(
                "rotation_direction must be 'auto', 'counterclockwise' or 'clockwise', got "
                f"{self.rotation_direction!r}"
            )
        if self.order not in (1, 2):
            raise ValueError(f"order must be 1 or 2, got {self.order!r}")
        if self.centrifugal not in (None, "linear", "nonlinear"):
            raise ValueError(
                f"centrifugal must be 'linear', 'nonlinear' or None, got {self.centrifugal!r}"
            )

    def with_(self, **changes) -> RubConfig:
        """A copy with some fields changed."""
        return replace(self, **changes)

    def with_contact(self, **changes) -> RubConfig:
        """A copy with some fields of :attr:`contact` changed."""
        return replace(self, contact=replace(self.contact, **changes))
