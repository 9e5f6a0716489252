"""The one builder of a rub model: a blade mesh and a :class:`~femrub.model.config.RubConfig`.

::

    BladeMesh + RubConfig -> Discretisation -> (centrifugal prestress) -> Eq. 2 blocks
        -> contact candidates -> reach filter -> heat law -> rotation direction
        -> casing cells (coating, heat) -> FirstOrderModel (:func:`~femrub.model.rub.rub_model`)

:func:`build_rub` is what :meth:`femrub.app.simulation.Simulation.from_scene`,
:func:`femrub.model.rub.solid_model` and :func:`femrub.cases.bar.bar_model` call; they only
turn their inputs into a configuration. The expensive stages (discretisation, prestress,
assembly, modal damping) go through ``stages``: :class:`DirectStages` computes them; the
scene pipeline hands :class:`femrub.app.cached.Stages`, which keeps them in its cache.
:class:`RubBuild` holds the model and what was decided on the way (the candidates, the
reach, the heat law, the thermal choice and why), for the pipeline's report.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..contact.abradable import Abradable, CasingGrid
from ..contact.casing import SLIP_DIRECTIONS
from ..contact.casing_heat import CasingHeat
from ..contact.heat import heat_coefficients
from ..contact.points import ContactPoints, locate_contacts
from ..contact.reach import Reach, contact_reach, normal_deflection
from ..fem.damping import rayleigh_coefficients
from ..fem.discretisation import assemble, discretise
from ..fem.eigen import angular_frequencies
from ..fem.prestress import centrifugal_prestress
from ..geometry.rotation_direction import RotationDirection, derive_rotation_direction
from .config import ContactConfig, RubConfig
from .rub import FieldMap, rub_model, tip_load

__all__ = [
    "DirectStages",
    "HeatChoice",
    "RubBuild",
    "build_rub",
    "casing_heat_of",
    "coating_of",
    "heat_choice",
    "length_scale",
    "rotation_direction",
]


class DirectStages:
    """The expensive stages of a build, computed (no cache); ``log``: progress messages."""

    def __init__(self, log=None):
        self.log = log

    def discretise(self, blade, order: int, clamped: bool = True):
        return discretise(blade, order, clamped=clamped)

    def assemble(self, disc, material, **kw):
        return assemble(disc, material, **kw)

    def prestress(self, disc, material, omega: float, method: str):
        return centrifugal_prestress(disc, material, omega, method, log=self.log)

    def damping(self, zeta: float, modes: tuple[int, int]):
        """``(mats, boundary) -> mats`` with ``C = a M + b K`` of ratio ``zeta`` at the
        clamped ``modes`` (frequencies from a factorisation of ``K``)."""

        def damp(mats, boundary):
            i, j = modes
            w = angular_frequencies(mats.K, mats.M, max(i, j))
            a, b = rayleigh_coefficients(float(zeta), w[i - 1], w[j - 1])
            damped = replace(mats, C=(a * mats.M + b * mats.K).tocsr(), info=dict(mats.info))
            damped.info["rayleigh"] = (float(a), float(b))
            return damped

        return damp


@dataclass(frozen=True)
class HeatChoice:
    """The frictional heat of the kept contacts: law, μ, η, coefficients α_i (m/s) and
    whether anything heats the blade."""

    law: str
    mu: float
    eta: float
    alpha: np.ndarray
    heated: bool


@dataclass(frozen=True)
class RubBuild:
    """What :func:`build_rub` built and decided (the pipeline's report reads it)."""

    model: object
    fields: FieldMap
    mats: object
    #: the finite-element bases the model was assembled on (what later build stages read of
    #: the mesh: probes); the model and its field map do not keep them
    disc: object
    candidates: ContactPoints
    reach: Reach
    prestress: object
    growth: np.ndarray
    grid: CasingGrid | None
    heat: HeatChoice
    thermal: tuple[bool, str]
    rotation: RotationDirection


def length_scale(blade) -> float:
    """The blade's characteristic size (m): the largest extent of its mesh (the bar's length)."""
    return float(np.ptp(blade.mesh.p, axis=1).max())


def _assembly_options(config: RubConfig, prestress) -> dict:
    return dict(
        area=config.area,
        lumping=config.lumping,
        conduction=config.conduction,
        coupling=config.coupling,
        beta=config.beta,
        strain_heating=config.strain_heating,
        rayleigh=tuple(config.rayleigh),
        prestress=prestress,
    )


def _prestress(config: RubConfig, disc, stages, log):
    """The centrifugal prestress at Ω, or ``None`` (off, Ω = 0 or the 1D bar)."""
    omega = config.rotation_speed
    if config.centrifugal is None or omega == 0.0 or disc.dim == 1:
        return None
    if log:
        log(f"centrifugal prestress ({config.centrifugal}) at {omega:g} rad/s ...")
    return stages.prestress(disc, config.material, omega, config.centrifugal)


def _force_direction(direction, candidates: ContactPoints) -> np.ndarray:
    d = candidates.normals.mean(axis=1) if direction == "radial" else np.asarray(direction, float)
    if not np.linalg.norm(d) > 0:
        raise ValueError("loads.tip_force.direction = [0, 0, 0]: give a non-zero vector")
    return d / np.linalg.norm(d)


def _tip_loads(config: RubConfig, disc, mats, candidates) -> list:
    force = config.tip_force
    if force is None or force.amplitude == 0.0:
        return []
    vector = force.amplitude * _force_direction(force.direction, candidates)
    return [tip_load(disc, mats, vector, force.signal)]


def _reach(config: RubConfig, mats, candidates, loads, growth) -> Reach:
    c = config.contact
    force = config.tip_force
    deflection = normal_deflection(
        mats,
        candidates.normal_rows(mats),
        loads[0].vector if loads else None,
        force.frequency if loads else None,
    )
    return contact_reach(
        candidates,
        c.casing,
        rotation_speed=config.rotation_speed,
        gap_reference=c.gap_reference,
        reach=c.reach,
        margin=c.reach_margin,
        growth=growth,
        clearance=c.clearance,
        deflection=deflection,
    )


def heat_choice(contact: ContactConfig, points: ContactPoints, dim: int) -> HeatChoice:
    """The heat law of the kept ``points`` (Coulomb μ only on a 3D blade)."""
    c = contact
    mu = float(c.friction) if dim == 3 else 0.0
    eta = float(c.heat_partition)
    if c.heat_law == "power":
        return HeatChoice("power", mu, eta, np.zeros(points.n), mu > 0.0 and eta > 0.0)
    alpha = heat_coefficients(points.radii, "alpha", alpha=c.heat_coefficient, heat_partition=eta)
    return HeatChoice("alpha", mu, eta, alpha, bool(np.any(alpha > 0)))


def thermal_choice(config: RubConfig, heated: bool, reachable: bool, dim: int) -> tuple[bool, str]:
    """Keep the temperature dofs, and why (``physics.thermal``; ``heated``: frictional heat
    on a kept contact; ``reachable``: some contact is kept)."""
    mode, coupling = config.thermal, config.coupling
    if mode is True or mode == "on":
        return True, f"kept (physics.thermal = 'on'; coupling {coupling!r})"
    if mode is False or mode == "off":
        return False, "dropped (physics.thermal = 'off': frictional heat and coupling ignored)"
    sources = ["frictional heat at the contacts"] if heated else []
    if config.strain_heating and coupling != "none":
        sources.append("strain-rate heating")
    if sources:
        return True, f"kept: {' and '.join(sources)} (coupling {coupling!r})"
    why = _no_heat(config, reachable, dim)
    return False, f"dropped: no heat source ({why}); the coupling has nothing to act on"


def _no_heat(config: RubConfig, reachable: bool, dim: int) -> str:
    c = config.contact
    if not reachable:
        return "no contact the casing can reach"
    if c.heat_partition == 0.0:
        return "contact.heat_partition = 0"
    if dim == 1 or c.heat_law == "alpha":
        return "contact.heat_coefficient = 0"
    if c.friction == 0.0:
        return "contact.friction = 0"
    return "loads.rotation_speed = 0 (no sliding)"


def rotation_direction(config: RubConfig, blade) -> RotationDirection:
    """The direction the blade turns in: the configuration's, or with ``"auto"`` the one its
    tip section implies (:func:`~femrub.geometry.rotation_direction.derive_rotation_direction`)."""
    if config.rotation_direction == "auto":
        return derive_rotation_direction(blade)
    return RotationDirection(
        config.rotation_direction, "scene", f"{config.rotation_direction} (given)"
    )


def casing_grid(config: RubConfig, blade, points, growth, sign=1.0) -> CasingGrid | None:
    """Casing cells swept by the kept contacts (wear map, casing heat) at the casing angle
    ``σ Ω t + φ`` (``sign`` σ: the rotation direction), or ``None``."""
    a, h = config.contact.abradable, config.contact.casing_heat
    if points.n == 0 or (a is None and h is None):
        return None
    cells = a if a is not None else h
    axial = blade.axis @ points.points if blade.dim == 3 else np.zeros(points.n)
    return CasingGrid(
        points.angles,
        axial,
        float(np.max(points.radii + growth)),
        sign * config.rotation_speed,
        n_angle=cells.n_angle,
        n_axial=cells.n_axial,
        footprint=a.footprint if a is not None else 0.0,
    )


def coating_of(contact: ContactConfig, grid):
    """The abradable coating ``contact.abradable`` on the casing cells ``grid``, or ``None``."""
    a = contact.abradable
    return None if grid is None or a is None else Abradable(a.thickness, a.yield_force, grid)


def casing_heat_of(contact: ContactConfig, grid, heat: HeatChoice):
    """The casing wall's heat model ``contact.casing_heat`` on the casing cells ``grid``
    heated by the casing's share of ``heat``, or ``None``; refused when no frictional heat
    reaches the casing."""
    h = contact.casing_heat
    if grid is None or h is None:
        return None
    mu = heat.mu if heat.law == "power" else 0.0
    if not 0.0 < heat.eta < 1.0 or not (mu > 0.0 or np.any(heat.alpha > 0)):
        raise ValueError(
            f"contact.casing_heat.thickness = {h.thickness!r}: no frictional heat reaches the "
            f"casing (heat_partition {heat.eta:g}, no heat coefficient); set contact.friction "
            "/ heat_coefficient and heat_partition < 1"
        )
    return CasingHeat(
        grid,
        h.thickness,
        h.density,
        h.specific_heat,
        h.conductivity,
        h.expansion,
        heat.eta,
        heat.alpha,
    )


def _thermal_note(model, thermal: tuple[bool, str]):
    """``model`` whose ``info["dropped"]`` says why its temperature dofs were dropped."""
    dropped = list(model.info.get("dropped", []))
    if thermal[0] or any("temperature" in d for d in dropped):
        return model
    note = f"temperature dofs {thermal[1]}"
    return model.with_(info={**model.info, "dropped": [note, *dropped]})


def _initial_velocity(model, velocity: float):
    if not velocity:
        return model
    x0 = np.zeros(model.n_dofs)
    x0[model.layout.v] = velocity
    return model.with_(x0=x0)


def build_rub(blade, config: RubConfig, *, stages=None, log=None) -> RubBuild:
    """Build the rub model of ``blade`` (a :class:`~femrub.geometry.BladeMesh` with its
    candidate contact points) as ``config`` says (module docstring).

    ``stages``: the expensive stages (default :class:`DirectStages`); ``log``: progress
    messages. The model's ``length_scale`` is :func:`length_scale` of ``blade``.

    Mesh → Eq. (2) blocks (with the centrifugal prestress when asked) → contact points →
    reach filter → heat law → first-order model ``A Ẋ = B X + F + H λ`` (Eqs. 8-9).

    Parameters
    ----------
    blade : BladeMesh
        Linear tetrahedra (or the bar's line) in metres, with ``root``, ``tip`` and contacts.
    config : RubConfig
        Material, casing, contacts, loads and options (SI units).

    Returns
    -------
    RubBuild
        ``model`` (the :class:`~femrub.model.first_order.FirstOrderModel`), ``fields`` (the
        map back to the mesh), ``mats`` (the Eq. 2 blocks), ``candidates`` and ``reach``
        (the contact points and those kept), ``prestress``, ``growth`` (tip growth of the
        prestress, m), ``grid`` (casing cells), ``heat`` and ``thermal`` (the choices made
        and why).
    """
    stages = stages or DirectStages(log)
    disc = stages.discretise(blade, config.order if blade.dim == 3 else 1, config.clamped)
    prestress = _prestress(config, disc, stages, log)
    mats = stages.assemble(disc, config.material, **_assembly_options(config, prestress))
    damping = (
        stages.damping(config.damping_ratio, tuple(config.damping_modes))
        if config.damping_ratio
        else None
    )
    candidates = locate_contacts(disc, spread=config.contact.spread)
    growth = prestress.growth(candidates) if prestress is not None else np.zeros(candidates.n)
    loads = _tip_loads(config, disc, mats, candidates)
    reach = _reach(config, mats, candidates, loads, growth)
    points = candidates.restrict(reach.keep)
    heat = heat_choice(config.contact, points, blade.dim)
    thermal = thermal_choice(config, heat.heated, points.n > 0, blade.dim)
    rotation = rotation_direction(config, blade)
    grid = casing_grid(config, blade, points, growth[reach.keep], rotation.sign)
    model, fields = rub_model(
        disc,
        mats,
        points,
        config.material,
        casing=config.contact.casing,
        rotation_speed=config.rotation_speed,
        alpha=heat.alpha,
        restitution=config.contact.restitution,
        offset=reach.offset[reach.keep],
        loads=loads,
        thermal=thermal[0],
        observe_at=points if points.n else candidates,
        friction=heat.mu,
        heat_law=heat.law,
        heat_partition=heat.eta,
        wear=coating_of(config.contact, grid),
        casing_heat=casing_heat_of(config.contact, grid, heat),
        damping=damping,
        length_scale=length_scale(blade),
        direction=rotation.sign,
        slip=SLIP_DIRECTIONS[config.contact.slip_direction],
    )
    model = _initial_velocity(_thermal_note(model, thermal), config.initial_velocity)
    return RubBuild(
        model,
        fields,
        mats,
        disc,
        candidates,
        reach,
        prestress,
        growth,
        grid,
        heat,
        thermal,
        rotation,
    )
