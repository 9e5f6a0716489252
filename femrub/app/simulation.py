"""The single pipeline from a scene to a runnable simulation, each object built once.

::

    Scene -> BladeMesh -> Discretisation -> Eq. 2 blocks -> ContactPoints (reach-filtered)
          -> FirstOrderModel -> reductor.reduce(dims) -> stepper

:meth:`Simulation.from_scene` builds what a scene needs and only that: temperature dofs only
when something heats the blade, only the contacts the casing can reach, only the requested
signals; it checks the step against Carpenter's stability limit, all before any time step.
It also refuses a casing clearance out of scale with the blade (a unit slip: a clearance
above :data:`MAX_CLEARANCE_RATIO` times the blade's size), and turns on physical stop limits
for the signals the scene does not limit (:func:`default_limits`: a temperature rise of
:data:`MAX_TEMPERATURE_RISE` K, a displacement of :data:`MAX_DISPLACEMENT_RATIO` times the
blade's size), so a runaway is reported as ``diverged-physically``, never as ``ok``.
``report`` says what was built and why (``femrub run SCENE --explain``); ``timings`` holds
the seconds spent meshing, assembling and reducing. The reduction error estimate steps the
reduced model of the chosen sizes to ``scheme.t_end`` with the scene's stepper: those results
are the run's (``ran``), and :func:`femrub.app.run.run_scene` writes them instead of stepping
the model a second time. The paper's bar and a 3D blade go through the same path.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .. import progress
from ..contact import jit
from ..contact.heat import heat_coefficients
from ..contact.points import locate_contacts
from ..contact.reach import contact_reach, normal_deflection
from ..model.rub import rub_model, tip_load
from ..output.limits import MAX_DISPLACEMENT_RATIO, MAX_TEMPERATURE_RISE, default_limits
from ..scene.spec import SceneError, fail
from . import translate as tr
from .blade import load_blade
from .build_warnings import initial_penetration, warn
from .cached import Stages
from .casing import abradable_of, casing_grid, casing_heat_of, footprint_warning
from .explain import explain
from .scheme import bare_stepper, stepper_of
from ..analysis.step_check import check_step

__all__ = [
    "MAX_CLEARANCE_RATIO",
    "MAX_DISPLACEMENT_RATIO",
    "MAX_TEMPERATURE_RISE",
    "Simulation",
    "blade_size",
    "build",
    "default_limits",
    "reusable_run",
]

#: largest casing clearance (or lobe depth) relative to the blade's size
MAX_CLEARANCE_RATIO = 0.05


def blade_size(scene, blade) -> float:
    """Characteristic size of the blade (m): the bar's length, else the mesh's largest extent."""
    if blade.dim == 1:
        return float(scene["geometry"]["length"])
    return float(np.ptp(blade.mesh.p, axis=1).max())


def _check_scale(scene, size: float) -> None:
    """Refuse a clearance out of scale with the blade (a unit slip, module docstring)."""
    casing = scene["contact"]["casing"]
    g = scene["geometry"]
    for key in ("clearance", "depth", "mean_gap"):
        value = casing.get(key)
        if value and value > MAX_CLEARANCE_RATIO * size:
            hint = (
                f"; check geometry.length_unit = {g.get('length_unit')!r}"
                if g["kind"] in ("mesh", "sections")
                else ""
            )
            fail(
                f"contact.casing.{key}",
                value,
                f"is {value / size:.3g} times the blade's size {size:.3g} m (at most "
                f"{MAX_CLEARANCE_RATIO:g}): a unit slip? e.g. write '{value:g} um'{hint}",
            )


@dataclass(frozen=True)
class Simulation:
    """A built scene (immutable): the model that runs, the full model, the stepper, the report."""

    scene: object
    model: object
    full: object
    fields: object
    reductor: object
    stepper: object
    limits: dict
    report: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    #: ``(results, wall seconds)`` of the scene's run of ``model`` to ``scheme.t_end``, stepped
    #: by the reduction error estimate (:func:`reusable_run`), else ``None``
    ran: tuple | None = None

    def explain(self) -> str:
        """What was built and why, as text (``femrub run SCENE --explain``)."""
        return explain(self.report)

    @classmethod
    def from_scene(
        cls, scene, *, log=None, modes: int = 0, cache=None, stepper: bool = True
    ) -> Simulation:
        """Build ``scene``; ``modes``: natural frequencies to report; ``cache``: a
        :class:`~femrub.app.cache.ModelCache` for the assembled and reduced models
        (:mod:`femrub.app.cached`), ``None`` to build everything; ``stepper=False``: no
        stepper (``None``; e.g. a full Rotor 37 model to reduce, whose iteration matrix
        would not be factorised on a small machine).

        Raises
        ------
        SceneError
            A one-line message naming the key at fault (missing file or group, step above
            the stability limit, ...).
        """
        with progress.reporting(log):  # factorisations, eigen-solves, reduction phases
            return _build(scene, log, modes, Stages(cache, log), stepper)


def build(scene, *, log=None, modes: int = 0, cache=None, stepper: bool = True) -> Simulation:
    """:meth:`Simulation.from_scene`."""
    return Simulation.from_scene(scene, log=log, modes=modes, cache=cache, stepper=stepper)


class _Clock:
    """Seconds per pipeline stage, with a log line when a stage ends."""

    def __init__(self, log):
        self.log, self.timings, self._t = log, {}, time.perf_counter()

    def exclude(self, seconds: float) -> None:
        """Leave ``seconds`` of the current stage out of its time (a run stepped inside it)."""
        self._t += seconds

    def done(self, stage: str, result: str) -> None:
        now = time.perf_counter()
        self.timings[stage] = self.timings.get(stage, 0.0) + now - self._t
        self._t = now
        if self.log:
            self.log(f"{stage} done in {self.timings[stage]:.2f} s: {result}")


def _build(scene, log, modes, stages, with_stepper=True) -> Simulation:
    scene.check_files()
    if jit.compile_in_background() and log:  # the first run on this machine: overlapped
        log("compiling the contact kernels in a background process (first run here) ...")
    clock = _Clock(log)
    c, p = scene["contact"], scene["physics"]
    report = {
        "scene": scene.name,
        "source": scene.source,
        "kind": scene["geometry"]["kind"],
        "dropped": [],
        "reach_key": c["reach"],
    }
    blade = load_blade(scene, log)
    size = blade_size(scene, blade)
    _check_scale(scene, size)
    report["geometry"] = blade.summary()
    report["blade_size"] = size
    clock.done("mesh", f"{blade.n_vertices} vertices")
    if log:
        log("assembling the full model ...")
    report["material"] = []
    material = tr.material_of(scene, blade.info.get("material"), report["material"])
    casing = tr.casing_of(scene)
    for note in report["material"] if log else ():
        log(f"notice: {note}")
    omega = scene["loads"]["rotation_speed"]
    try:
        disc = stages.discretise(
            blade, p["order"] if blade.dim == 3 else 1, clamped=scene["boundary"]["clamped"]
        )
        prestress = _prestress(scene, disc, material, omega, log, stages)
        mats = stages.assemble(
            disc,
            material,
            area=tr.area_of(scene),
            lumping=p["lumping"],
            conduction=p["conduction"],
            coupling=tr.coupling_of(scene),
            beta=p["beta"],
            strain_heating=p["strain_heating"],
            rayleigh=tuple(p["rayleigh"]),
            prestress=prestress,
        )
        # modal damping once the contacts' boundary is known: its frequencies come through
        # the interior factorisation the reduction reuses (femrub.reduction.modal_damping)
        damping = p["damping_ratio"] and stages.damping(
            p["damping_ratio"], tuple(p["damping_modes"])
        )
        candidates = locate_contacts(disc, spread=c["spread"])
        growth = prestress.growth(candidates) if prestress is not None else np.zeros(candidates.n)
        force = tr.force_law(scene)
        loads = []
        if force:
            amplitude, signal, _ = force
            vector = amplitude * tr.force_direction(scene, candidates)
            loads = [tip_load(disc, mats, vector, signal)]
        reach = contact_reach(
            candidates,
            casing,
            rotation_speed=omega,
            gap_reference=c["gap_reference"],
            reach=c["reach"],
            margin=c["reach_margin"],
            growth=growth,
            clearance=c["clearance"],
            deflection=normal_deflection(
                mats,
                candidates.normal_rows(mats),
                loads[0].vector if loads else None,
                force and force[2],
            ),
        )
        points = candidates.restrict(reach.keep)
        law = tr.heat_law_of(scene)
        mu = c["friction"] if blade.dim == 3 else 0.0
        eta = tr.heat_partition_of(scene)
        if law == "power":
            alpha = np.zeros(points.n)
            heated = mu > 0.0 and eta > 0.0
        else:
            alpha = heat_coefficients(
                points.radii, "alpha", alpha=c["heat_coefficient"], heat_partition=eta
            )
            heated = bool(np.any(alpha > 0))
        grid = casing_grid(scene, blade, points, omega, growth[reach.keep])
        keep_t, report["thermal"] = tr.thermal_choice(scene, heated, points.n > 0)
        full, fields = rub_model(
            disc,
            mats,
            points,
            material,
            casing=casing,
            rotation_speed=omega,
            alpha=alpha,
            restitution=c["restitution"],
            offset=reach.offset[reach.keep],
            loads=loads,
            thermal=keep_t,
            observe_at=points if points.n else candidates,
            friction=mu,
            heat_law="power" if law == "power" else "alpha",
            heat_partition=eta,
            wear=abradable_of(scene, grid),
            casing_heat=casing_heat_of(scene, grid, eta, alpha, mu if law == "power" else 0.0),
            damping=damping or None,
        )
        report["friction"] = {"mu": mu, "heat_law": law, "heat_partition": eta}
        warn(initial_penetration(full), report, log)
        warn(footprint_warning(scene, grid), report, log)
    except ValueError as exc:  # a value the schema cannot see (e.g. a singular clamp)
        if isinstance(exc, SceneError):
            raise
        raise SceneError(f"building the model of {scene.source}: {exc}") from None
    clock.done("assembly", f"{full.n_dofs} state dofs")
    report["dropped"] += [d for d in full.info.get("dropped", []) if "temperature" not in d]
    report["full"] = {"n_dofs": full.n_dofs, "fe_dofs": mats.n_u + mats.n_t, **_layout(full)}
    report["contacts"] = _contacts_report(candidates, reach)
    report["centrifugal"] = _centrifugal_report(scene, prestress, growth, reach)
    wear = full.contact.wear if full.contact is not None else None
    report["abradable"] = wear.as_dict() if wear is not None else None
    ch = full.contact.casing_heat if full.contact is not None else None
    report["casing_heat"] = (
        None
        if ch is None
        else {"thickness": ch.b, "tau": ch.tau, "partition": eta, "expansion": ch.expansion}
    )
    model, limits = _select_signals(scene, full, report, size)
    if modes:
        report["natural_frequencies_hz"] = stages.frequencies(model, modes).tolist()
    make = lambda m: bare_stepper(scene, m)  # noqa: E731  (the reduction error estimate)
    chosen = []  # (results, wall seconds, full states) of the estimate's run of the chosen sizes
    reduced, reductor, report["reduction"] = stages.reduce(
        model, scene, log, make, limits, on_run=lambda *run: chosen.append(run)
    )
    ran = chosen[0][:2] if chosen and reusable_run(model) else None
    if ran is not None:  # the run itself: its time is the run's ``stepping``
        clock.exclude(ran[1])
    clock.done("reduction", f"{reduced.n_dofs} dofs")
    if scene["scheme"]["step_check"]:
        given = None  # the estimate's run: compared only, unless it is the run (kept whole)
        if chosen:
            res, _, states = chosen.pop()
            given = (res if ran is not None else res.lean(), states)
        report["time_step"], run_h, wall_h = check_step(
            scene, reduced, full, lambda m, h: bare_stepper(scene, m, h), limits, run=given
        )
        if ran is None and wall_h is not None and reusable_run(model):
            ran = (run_h[0], wall_h)  # the check stepped the run itself
            clock.exclude(wall_h)
        clock.done("step_check", f"time-step error {100 * report['time_step']['estimate']:.2g} %")
    report["model"] = {"n_dofs": reduced.n_dofs, **_layout(reduced)}
    stepper = stepper_of(scene, reduced, report) if with_stepper else None
    report["outputs"] = {
        "vtk_stride": scene["outputs"]["vtk_stride"],
        "plots": scene["outputs"]["plots"],
    }
    report["timings"] = clock.timings
    return Simulation(
        scene, reduced, full, fields, reductor, stepper, limits, report, clock.timings, ran
    )


def reusable_run(model) -> bool:
    """Whether the reduction error estimate's run of the chosen sizes can be the run.

    It is the same model, stepper, initial state, end time and stop limits; its results are
    kept unless the contact carries state across runs that a later run of the estimate (its
    reference's twin) would overwrite: an abradable coating's wear or the casing's heat.
    """
    return model.contact is None or not model.contact.carried_state


def _prestress(scene, disc, material, omega, log, stages):
    """The scene's centrifugal prestress (:mod:`femrub.fem.prestress`), or ``None``."""
    method = tr.centrifugal_of(scene)
    if method is None:
        return None
    if log:
        log(f"centrifugal prestress ({method}) at {omega:g} rad/s ...")
    return stages.prestress(disc, material, omega, method)


def _centrifugal_report(scene, prestress, growth, reach) -> dict:
    if prestress is None:
        why = (
            "loads.centrifugal = 'off'"
            if scene["loads"]["centrifugal"] == "off"
            else ("the 1D bar" if tr.is_bar(scene) else "loads.rotation_speed = 0")
        )
        return {"method": "off", "why": why}
    g = np.asarray(growth, dtype=float)
    return {
        "method": prestress.method,
        "rotation_speed": prestress.omega,
        "newton_iterations": prestress.iterations,
        "load_increments": prestress.increments,
        "residual": prestress.residual,
        "clearance": scene["contact"]["clearance"],
        "tip_growth_min": float(g.min()) if g.size else 0.0,
        "tip_growth_max": float(g.max()) if g.size else 0.0,
        "tip_growth_mean": float(g.mean()) if g.size else 0.0,
        "min_gap": float(reach.min_gap.min()) if g.size else 0.0,
        "max_min_gap": float(reach.min_gap.max()) if g.size else 0.0,
    }


def _select_signals(scene, model, report, size):
    outputs, limits = scene["outputs"], scene["limits"]
    wanted = set(model.observations) if outputs["signals"] == "all" else set(outputs["signals"])
    wanted |= {k for k in limits if k != "contact_force"}
    absent = sorted(k for k in wanted if k not in model.observations)
    obs = {k: v for k, v in model.observations.items() if k in wanted}
    report["signals"] = sorted(obs)
    report["signals_not_observed"] = sorted(set(model.observations) - set(obs))
    kept_limits, ignored = {}, []
    for k, v in limits.items():
        if k == "contact_force" or k in obs:
            kept_limits[k] = v
        else:
            ignored.append(f"limits.{k}: no such signal in this model (no temperature dofs)")
    for k in absent:
        if k in (outputs["signals"] if outputs["signals"] != "all" else []):
            ignored.append(f"outputs.signals: {k} is not observed (no temperature dofs)")
    defaults = {k: v for k, v in default_limits(obs, size).items() if k not in kept_limits}
    kept_limits.update(defaults)
    report["limits"], report["ignored"] = kept_limits, ignored
    report["limits_default"] = sorted(defaults)
    return model.with_(observations=obs), kept_limits


def _contacts_report(points, reach) -> dict:
    keep = reach.keep
    return {
        "candidates": points.n,
        "kept": [n for n, k in zip(points.names, keep) if k],
        "dropped": [
            {"name": n, "min_gap": float(g)}
            for n, g, k in zip(points.names, reach.min_gap, keep)
            if not k
        ],
        "min_gap_kept": [float(g) for g, k in zip(reach.min_gap, keep) if k],
        "reach": reach.reach,
        "deflection": reach.deflection,
        "intrusion": reach.intrusion,
        "max_offset": float(np.max(reach.offset)) if points.n else 0.0,
    }


def _layout(model) -> dict:
    L = model.layout
    return {"n_u": L.n_u, "n_v": L.n_v, "n_theta": L.n_t, "n_contacts": model.n_contacts}
