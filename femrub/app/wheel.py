"""A bladed-disk scene (``rotor.sectors``) as a runnable simulation: every blade against the casing.

The scene's disk sector (``rotor.*``, the blade of ``geometry.*``) is prestressed at
``loads.rotation_speed`` (``loads.centrifugal``) and reduced per nodal diameter with the
residual shapes of ``rotor.contacts`` contacts on each blade's tip; the casing ring
(``casing.ring.*``, when it has a ``thickness``; a rigid round casing otherwise) enters as
waves of the rotating frame (:mod:`femrub.model.wheel`); ``rotor.mistuning`` scales
blade ``s``'s elastic stiffness by ``1 + δ_s`` (:func:`~femrub.model.wheel.mistuning_stiffness`
on each model's disk basis: the run's and the reference's alike); ``contact.abradable`` and
``contact.casing_heat`` put a coating and a wall heat model on the casing
(:class:`~femrub.model.wheel.CasingSurface`); with frictional heat for the blades
(``physics.thermal``) the blades' temperature is reduced per nodal diameter too
(:mod:`femrub.model.cyclic_thermal`, ``rotor.thermal_families`` modes and the contacts'
static heat shapes) and the disk's bases gain the static responses to its thermal stresses.
The model is its own full model: its coordinates are mass-normalised (heat-capacity
normalised for the temperature), so the mass norm of the wheel's displacement is the norm
of its displacement coordinates.

Checks, as for a single blade, stepping the scene's scheme to ``scheme.t_end``:

* the *reduction error estimate*: the run against the same wheel with richer bases
  (``rotor.families + 2`` modes per nodal diameter on the disk, ``casing.ring.families + 1``
  on the casing, ``rotor.thermal_families + 1`` on the temperature). The richer disk basis
  spans the run's (modes and residual shapes of the same contacts), so the run's states are
  carried into the richer coordinates exactly
  (:func:`transfer`) and compared there by :func:`~femrub.reduction.estimate.estimate`
  (contact impulses per lobe passage, the wheel's displacement in the mass norm; with the
  round-off twin of the richer model when the response is sensitive);
* the *time-step check* (:func:`~femrub.analysis.step_check.check_step`), when
  ``scheme.step_check`` asks for it (as for a single blade).

``timings``: ``assembly``, ``reduction`` (the bases and the estimate's runs other than the
run itself) and ``step_check``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from ..analysis.reduction_check import lobe_passage
from ..analysis.step_check import check_step
from ..geometry.rotation_direction import ROTATION_DIRECTIONS, derive_rotation_direction
from ..model.builder import casing_heat_of, coating_of, heat_choice
from ..model.casing_waves import casing_harmonics, ring_line_loads, waves_of
from ..model.cyclic import cyclic_structure
from ..model.cyclic_thermal import (
    ThermalSector,
    expansion_rows,
    heat_rows_with_content,
    thermal_sector,
)
from ..model.wheel import (
    CasingSurface,
    WheelConfig,
    contact_heat_rows,
    contact_rows_of_sector,
    mistuning_stiffness,
    tip_contacts,
    wheel_casing_grid,
    wheel_model,
    wheel_thermal,
)
from ..output.wheel_vtk import WheelFields
from ..reduction.cyclic_ritz import CyclicBasis, cross_matrix, cyclic_bases
from ..reduction.estimate import HORIZON_SHARE, estimate, perturbed
from ..scene.spec import fail
from . import translate as tr
from .build_warnings import warn
from .casing import footprint_warning
from .modes import casing_sector, ring_material, rotor_sector
from .probes import probe_points, wheel_probes
from .scheme import bare_stepper, stepper_of

__all__ = ["WheelParts", "build_wheel", "transfer", "wheel_parts"]

#: Modes per nodal diameter the reference model adds on the disk, on the casing and on the
#: blades' temperature.
REFERENCE_EXTRA = (2, 1, 1)
#: States stored per run for the field comparison.
CHECKPOINTS = 5


@dataclass(frozen=True)
class WheelParts:
    """What every wheel model of a scene shares: the sectors, the contacts, the configuration."""

    disk: object  # CyclicStructure at Ω
    contacts: object
    rows: sp.csr_matrix
    ring: object  # CyclicStructure of the casing ring, or None
    bore: float
    tip_radius: float
    config: WheelConfig
    mistuning: tuple | None = None  # δ_s per blade (rotor.mistuning); None: tuned
    material: object = None  # the blades' material (their stiffness scaled by 1 + δ_s)
    probes: tuple = ()  # WheelProbe per outputs.probes (femrub.model.wheel_probes)
    probe_report: tuple = ()  # (report entries, warnings) of the probes (app.probes)
    surface: CasingSurface | None = None  # the casing's coating and wall heat, the heat law
    thermal: ThermalSector | None = None  # the blades' temperature (physics.thermal)


def _direction(scene, sector) -> float:
    given = scene["loads"]["rotation_direction"]
    if given == "auto":
        return derive_rotation_direction(sector.mesh).sign
    return ROTATION_DIRECTIONS[given]


def _config(scene, sector) -> WheelConfig:
    ring, rotor = scene["casing"]["ring"], scene["rotor"]
    omega = float(scene["loads"]["rotation_speed"])
    ramp = ring.get("ramp")
    if ramp is None:
        ramp = 2.0 * 2.0 * math.pi / omega if omega > 0 else 0.0
    return WheelConfig(
        rotation_speed=omega,
        clearance=ring["clearance"],
        lobes=ring["lobes"],
        distortion=ring["distortion"],
        distortion_phase=math.radians(ring["phase"]),
        direction=_direction(scene, sector),
        friction=scene["contact"]["friction"],
        restitution=scene["contact"]["restitution"],
        disk_damping=rotor["damping_ratio"],
        casing_damping=ring["damping_ratio"],
        ramp=ramp,
    )


def wheel_parts(scene, log=None) -> WheelParts:
    """Mesh and assemble the scene's sectors, prestress the disk, place the contacts."""
    sector = rotor_sector(scene)
    probe_at = probe_points(scene, sector.mesh)  # node numbers checked before any assembly
    material = tr.material_of(scene)
    method = tr.centrifugal_of(scene) or "off"
    omega = float(scene["loads"]["rotation_speed"])
    if log:
        log(f"bladed disk: sector of {sector.n_sectors}, prestress {method} at {omega:g} rad/s")
    disk = cyclic_structure(sector, material, omega=omega, prestress=method)
    contacts = tip_contacts(disk, scene["rotor"]["contacts"])
    normal, tangent = contact_rows_of_sector(disk, contacts)
    tip_radius = float(sector.info["tip_radius"])
    ring = None
    bore = tip_radius + scene["casing"]["ring"]["clearance"]
    if scene["casing"]["ring"].get("thickness") is not None:
        ring = cyclic_structure(casing_sector(scene, tip_radius), ring_material(scene))
    _check_start(scene, disk, contacts, tip_radius)
    probes, entries, warnings = wheel_probes(scene, disk, probe_at)
    config = _config(scene, sector)
    thermal = _thermal(scene, disk, material)
    return WheelParts(
        disk,
        contacts,
        sp.vstack([normal, tangent]).tocsr(),
        ring,
        bore,
        tip_radius,
        config,
        _mistuning(scene),
        material,
        probes,
        (entries, warnings),
        _surface(scene, config, disk, contacts, thermal is not None),
        thermal,
    )


def _heated(scene) -> bool:
    """Whether the scene's frictional heat enters the blades: a share ``η > 0`` of a power
    (Coulomb μ > 0 under the ``"power"`` law, α > 0 under ``"alpha"``)."""
    c = scene["contact"]
    if tr.heat_partition_of(scene) <= 0.0:
        return False
    return c["friction"] > 0.0 if tr.heat_law_of(scene) == "power" else c["heat_coefficient"] > 0


def _thermal(scene, disk, material):
    """The blades' temperature (:func:`~femrub.model.cyclic_thermal.thermal_sector`) when
    ``physics.thermal`` keeps it (``"auto"``: when frictional heat enters the blades)."""
    mode = scene["physics"]["thermal"]
    if mode == "off" or (mode == "auto" and not _heated(scene)):
        return None
    coupling = "none" if scene["physics"]["coupling"] == "none" else "physical"
    return thermal_sector(disk, material, coupling)


def _surface(scene, config: WheelConfig, disk, contacts, thermal: bool) -> CasingSurface | None:
    """The casing's abradable coating (``contact.abradable``) and wall heat
    (``contact.casing_heat``) on the cells the blades sweep, and the heat law; ``None``
    without either and without the blades' temperature (``thermal``)."""
    contact = tr.contact_config(scene)
    cells = contact.abradable or contact.casing_heat
    if cells is None and not thermal:
        return None
    n_blades = disk.n_sectors
    heat = heat_choice(contact, contacts, 3)
    heat = replace(heat, alpha=np.tile(heat.alpha, n_blades))
    if cells is None:
        return CasingSurface(None, None, heat.law, heat.eta, heat.alpha)
    footprint = contact.abradable.footprint if contact.abradable is not None else 0.0
    grid = wheel_casing_grid(config, disk, contacts, n_blades, cells, footprint)
    casing_heat = casing_heat_of(contact, grid, heat)  # its inputs checked by check_run
    return CasingSurface(coating_of(contact, grid), casing_heat, heat.law, heat.eta, heat.alpha)


def _mistuning(scene) -> tuple | None:
    """``rotor.mistuning`` as a tuple, ``None`` for a tuned wheel (no factor or all zero)."""
    factors = scene["rotor"].get("mistuning")
    return tuple(factors) if factors and any(factors) else None


def _check_start(scene, disk, contacts, tip_radius: float) -> None:
    """Refuse a clearance the blades' centrifugal growth closes before the first step (the
    out-of-roundness ramps in from zero, so only the round clearance counts at the start)."""
    ring = scene["casing"]["ring"]
    growth = contacts.normal_displacement(disk.static)
    start = ring["clearance"] + tip_radius - contacts.radii - growth
    if ring.get("ramp") == 0.0:
        start = start - ring["distortion"]
    if start.min() < 0.0:
        need = ring["clearance"] - start.min()
        fail(
            "casing.ring.clearance",
            ring["clearance"],
            f"the blades start {-start.min():.3g} m inside the casing (their centrifugal "
            f"growth at Ω is {growth.max():.3g} m); use casing.ring.clearance >= {need:.3g} m",
        )


def _bases(parts: WheelParts, sizes) -> list:
    """``(disk basis, casing waves, temperature basis)`` for each ``(disk modes, casing
    modes[, temperature modes])`` of ``sizes`` (one factorisation and eigen-solve per nodal
    diameter for them all). With the blades' temperature the disk's bases hold the static
    responses to the thermal stresses of the richest temperature basis, so the thermal
    expansion of every temperature basis is exact."""
    thermal = [None] * len(sizes)
    rows = parts.rows
    if parts.thermal is not None:
        heat = contact_heat_rows(parts.thermal, parts.contacts)
        loads = heat_rows_with_content(parts.thermal, heat)
        thermal = cyclic_bases(parts.thermal.structure, [s[2] for s in sizes], loads)
        richest = thermal[int(np.argmax([s[2] for s in sizes]))]
        expansion = expansion_rows(parts.thermal, richest)
        rows = lambda k: sp.vstack([parts.rows, expansion(k)]).tocsr()  # noqa: E731
    disks = cyclic_bases(parts.disk, [s[0] for s in sizes], rows)
    waves = _casing_bases(parts, [s[1] for s in sizes])
    return list(zip(disks, waves, thermal, strict=True))


def _casing_bases(parts: WheelParts, sizes) -> list:
    """The casing's waves (:func:`~femrub.model.casing_waves.waves_of`) for each number of
    ring modes of ``sizes``; ``None`` each for a rigid casing."""
    if parts.ring is None:
        return [None] * len(sizes)
    harmonics = casing_harmonics(parts.ring.n_sectors)
    reading = parts.bore * (1.0 + 1e-6)  # just inside the ring's bore
    axial = parts.contacts.points[0]
    positions = np.unique(axial)
    loads = ring_line_loads(parts.ring, positions, reading, _band(positions))
    rings = cyclic_bases(parts.ring, sizes, loads, harmonics=harmonics)
    return [waves_of(parts.ring, r, axial, reading) for r in rings]


def _band(positions: np.ndarray) -> float:
    """The axial width (m) a contact's load on the ring is spread over: the mean spacing of
    the contacts' distinct axial ``positions`` (0 for a single one)."""
    return 0.0 if positions.size < 2 else float(np.ptp(positions)) / (positions.size - 1)


def _model(parts: WheelParts, disk, waves, temperature=None):
    """The wheel's model on the bases ``disk``, ``waves`` and ``temperature``, the blades'
    mistuning projected on ``disk`` (the run's model and the reference's alike)."""
    rim = parts.disk.sector.info["rim_radius"]
    blade = parts.tip_radius - rim
    extra = None
    if parts.mistuning is not None:
        extra = mistuning_stiffness(parts.disk, disk, parts.mistuning, parts.material, rim)
    return wheel_model(
        parts.config,
        parts.disk,
        disk,
        parts.contacts,
        waves,
        tip_radius=parts.tip_radius,
        blade_size=blade,
        mistuning=extra,
        probes=parts.probes,
        surface=parts.surface,
        thermal=None
        if temperature is None
        else wheel_thermal(parts.thermal, temperature, disk, parts.contacts),
    )


def transfer(small: CyclicBasis, rich: CyclicBasis, mass) -> np.ndarray:
    """``(rich.size, small.size)``: the coordinates in ``rich`` of the fields of ``small``'s
    coordinates, ``W_richᴴ M W_small`` per nodal diameter (exact when ``rich``'s span holds
    ``small``'s), as real coordinates (:func:`~femrub.reduction.cyclic_ritz.cross_matrix`)."""
    return cross_matrix(rich, small, mass)


def _state_transfer(parts, small, rich) -> np.ndarray:
    """States ``[u, v(, θ)]`` of the small wheel into the rich wheel's (displacement and
    velocity alike; the temperature by its own basis)."""
    (disk_s, waves_s, temp_s), (disk_r, waves_r, temp_r) = small, rich
    T = transfer(disk_s, disk_r, parts.disk.M)
    if waves_s is not None:
        T = sp.block_diag([T, transfer(waves_s.basis, waves_r.basis, parts.ring.M)]).toarray()
    T = np.kron(np.eye(2), T)
    if temp_s is not None:
        Tt = transfer(temp_s, temp_r, parts.thermal.structure.M)
        T = sp.block_diag([T, Tt]).toarray()
    return T


def _run(model, scene, limits, lean=0):
    stepper = bare_stepper(scene, model)
    t_end = scene["scheme"]["t_end"]
    every = max(1, stepper.steps_to(t_end) // CHECKPOINTS)
    t0 = time.perf_counter()
    res = stepper.run(t_end, store_every=every, limits=limits, lean=lean, compared=lean > 0)
    return res, time.perf_counter() - t0


def _sizes(scene, thermal: bool) -> tuple:
    """The run's ``(disk, casing[, temperature])`` modes per nodal diameter and the
    reference's (``thermal``: with the blades' temperature)."""
    r = scene["rotor"]
    sizes = (r["families"], scene["casing"]["ring"]["families"])
    sizes += (r["thermal_families"],) if thermal else ()
    return sizes, tuple(a + b for a, b in zip(sizes, REFERENCE_EXTRA[: len(sizes)], strict=True))


def _reduction_check(scene, parts, small, rich, model, limits, log):
    """The run and the estimate of its reduction error against the richer wheel."""
    sizes, rich_sizes = _sizes(scene, parts.thermal is not None)
    rich_model, _ = _model(parts, *rich)
    T = _state_transfer(parts, small, rich)
    if log:
        log(f"reduction error estimate: the run ({model.n_dofs} coordinates) ...")
    run, wall = _run(model, scene, limits)
    if log:
        log(f"reduction error estimate: the richer wheel ({rich_model.n_dofs} coordinates) ...")
    ref, _ = _run(rich_model, scene, limits, lean=1)
    window = lobe_passage(scene)
    a, b = (sizes, run, run.states @ T.T), (rich_sizes, ref, ref.states)
    tol = scene["reduction"]["tolerance"]
    err = estimate(a, b, rich_model, window=window)
    if err["estimate"] > HORIZON_SHARE * tol:  # a sensitive response? its twin says
        twin, _ = _run(perturbed(rich_model), scene, limits, lean=1)
        err = estimate(a, b, rich_model, window=window, twin=(twin, twin.states), tolerance=tol)
    err.update(tolerance=tol, method="cyclic: " + err["method"])
    return err, run, wall


def build_wheel(scene, log=None):
    """The :class:`~femrub.app.simulation.Simulation` of a bladed-disk scene (module
    docstring): the wheel's model (also its full model), its fields (the whole wheel's VTK
    frames, :class:`~femrub.output.wheel_vtk.WheelFields`), its stepper, its run (stepped by
    the reduction error estimate) and the report."""
    from .simulation import Simulation, holds_frames, reused_run

    timings, t0 = {}, time.perf_counter()
    parts = wheel_parts(scene, log)
    timings["assembly"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    small, rich = _bases(parts, _sizes(scene, parts.thermal is not None))
    model, wheel = _model(parts, *small)
    timings["reduction"] = time.perf_counter() - t1
    limits = {}
    report = _report(scene, parts, model)
    report["probes"], probe_warnings = parts.probe_report or ([], [])
    for msg in probe_warnings:
        warn(msg, report, log)
    if parts.surface is not None and parts.surface.wear is not None:
        warn(footprint_warning(scene, parts.surface.wear.grid, parts.contacts.n), report, log)
    t2 = time.perf_counter()
    err, run, wall = _reduction_check(scene, parts, small, rich, model, limits, log)
    estimate_seconds = time.perf_counter() - t2 - wall  # the estimate, without the run
    seconds = {"bases": timings["reduction"], "estimate": estimate_seconds}
    report["reduction"] = {"method": "cyclic", "error": err, "seconds": seconds}
    timings["reduction"] += estimate_seconds
    if scene["scheme"]["step_check"]:
        t3 = time.perf_counter()
        make = lambda m, h: bare_stepper(scene, m, h=h)  # noqa: E731
        report["time_step"], _, _ = check_step(scene, model, model, make, limits, (run, run.states))
        timings["step_check"] = time.perf_counter() - t3
    stepper = stepper_of(scene, model, report)
    report["timings"] = timings
    c = parts.config
    thermal = None if parts.thermal is None else parts.thermal.structure
    fields = WheelFields(wheel, parts.disk, parts.ring, c.rotation_speed, c.direction, thermal)
    # the run, with the history it carried (Results.contact_history), unless the run writes
    # VTK frames whose states it did not store: then it is stepped again, writing them
    ran = (run, wall) if reused_run(scene, model, fields) or holds_frames(run, scene) else None
    return Simulation(scene, model, model, fields, None, stepper, limits, report, timings, ran)


def _report(scene, parts: WheelParts, model) -> dict:
    c = parts.config
    return {
        "scene": scene.name,
        "source": scene.source,
        "kind": "bladed-disk",
        "dropped": [],
        "bladed_disk": {
            "blades": model.info["n_blades"],
            "contacts_per_blade": parts.contacts.n,
            "disk_coordinates": model.info["disk_coordinates"],
            "casing_coordinates": model.info["casing_coordinates"],
            "sector_free_dofs": int(parts.disk.free.size),
            "casing": "flexible ring" if parts.ring is not None else "rigid",
            "temperature_coordinates": model.info["temperature_coordinates"],
            "tip_radius": parts.tip_radius,
            "direction": c.direction,
            "ramp": c.ramp,
            "mistuning": _mistuning_report(parts.mistuning),
        },
        "model": {"n_dofs": model.n_dofs},
        "outputs": {"vtk_stride": scene["outputs"]["vtk_stride"]},
        **_surface_report(parts.surface),
    }


def _surface_report(surface: CasingSurface | None) -> dict:
    """The report's ``abradable`` and ``casing_heat`` entries (as a single blade's)."""
    wear = surface.wear if surface is not None else None
    heat = surface.casing_heat if surface is not None else None
    out = {"abradable": wear.as_dict() if wear is not None else None, "casing_heat": None}
    if heat is not None:
        out["casing_heat"] = {
            "thickness": heat.b,
            "tau": heat.tau,
            "partition": surface.heat_partition,
            "expansion": heat.expansion,
        }
    if surface is not None:
        out["friction"] = {"heat_law": surface.heat_law, "heat_partition": surface.heat_partition}
    return out


def _mistuning_report(factors) -> dict | None:
    """``None`` for a tuned wheel, else the factors δ_s and their largest magnitude."""
    if factors is None:
        return None
    return {"factors": list(factors), "max_abs": float(np.abs(factors).max())}
