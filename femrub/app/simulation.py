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
are the run's (``ran``, with the wear map and casing heat its contact carried), and
:func:`femrub.app.run.run_scene` writes them instead of stepping the model a second time
(unless the run writes VTK frames and is checked whole: then the run is stepped again and the
checks' runs are only compared; a run checked on windows stores its frames' states). The
paper's bar and a 3D blade go through the same path.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from .. import progress
from ..analysis.step_check import check_step
from ..contact import jit
from ..model.builder import RubBuild, build_rub, length_scale
from ..model.modes import damped_modes
from ..output.limits import MAX_DISPLACEMENT_RATIO, MAX_TEMPERATURE_RISE, default_limits
from ..output.results import PROBE_PREFIX
from ..scene.run_checks import check_run
from ..scene.spec import SceneError, fail
from . import translate as tr
from .blade import load_blade
from .build_warnings import initial_penetration, warn
from .cached import Kept, Stages
from .casing import footprint_warning
from .explain import explain
from .probes import probe_observations, probe_points
from .scheme import bare_stepper, stepper_of

__all__ = [
    "MAX_CLEARANCE_RATIO",
    "MAX_DISPLACEMENT_RATIO",
    "MAX_TEMPERATURE_RISE",
    "SceneBuilds",
    "Simulation",
    "blade_size",
    "build",
    "default_limits",
]

#: largest casing clearance (or lobe depth) relative to the blade's size
MAX_CLEARANCE_RATIO = 0.05


def blade_size(scene, blade) -> float:
    """Characteristic size of the blade (m): the bar's length, else the mesh's largest extent
    (:func:`femrub.model.builder.length_scale`, the model's ``length_scale``)."""
    return length_scale(blade)


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
    """A built scene (immutable): the model that runs, the full model, the stepper, the report.

    Built by :meth:`from_scene` (or :func:`build`) through the one pipeline: scene → mesh →
    Eq. (2) blocks → contact points → first-order model (Eqs. 8-9) → reduced model
    (Eqs. 10-15, when ``reduction`` asks) → stepper.

    Attributes
    ----------
    scene : Scene
        The scene it was built from.
    model : FirstOrderModel
        The model the stepper runs (reduced, or the full one).
    full : FirstOrderModel
        The full model.
    fields : object
        What maps the model's state back to the mesh (VTK output).
    reductor : ThermoelasticCraigBampton or None
        The reductor of a reduced run.
    stepper : Stepper or None
        The stepper of ``scheme.*`` on ``model`` (``run(t_end)`` runs it).
    limits : dict
        Physical stop limits of the run (K for temperatures, m for displacements).
    report : dict
        What was built and why (:meth:`explain`; ``summary.json["inputs"]["build"]``).
    timings : dict
        Seconds spent in each stage of the build.
    """

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
    #: by the reduction error estimate or the time-step check (:func:`reused_run`: not with
    #: VTK frames, which the run writes as it steps, unless it stored their states:
    #: :func:`holds_frames`), else ``None``
    ran: tuple | None = None
    #: the probes' observation rows on the full model, ``{probe_<name>: (1, n) rows}``
    probes: dict = field(default_factory=dict)

    def released(self) -> Simulation:
        """This simulation without its full model and reductor (both ``None``): what a run
        writing its results folder reads (the reduced model, its stepper, its map to the
        mesh, the run the checks stepped). A build keeps them for its checks and for the
        next speed of a sweep; on Rotor 37 they take over a gigabyte."""
        return replace(self, full=None, reductor=None)

    def explain(self) -> str:
        """What was built and why, as text (``femrub run SCENE --explain``)."""
        return explain(self.report)

    @classmethod
    def from_scene(
        cls,
        scene,
        *,
        log=None,
        modes: int = 0,
        cache=None,
        stepper: bool = True,
        kept: Kept | None = None,
    ) -> Simulation:
        """Build ``scene``; ``modes``: natural frequencies to report; ``cache``: a
        :class:`~femrub.app.cache.ModelCache` for the assembled and reduced models
        (:mod:`femrub.app.cached`), ``None`` to build everything; ``stepper=False``: no
        stepper (``None``; e.g. a full Rotor 37 model to reduce, whose iteration matrix
        would not be factorised on a small machine); ``kept``: a
        :class:`~femrub.app.cached.Kept` shared by builds of one blade in a row
        (:class:`SceneBuilds`).

        Raises
        ------
        SceneError
            A one-line message naming the key at fault (missing file or group, step above
            the stability limit, ...).
        """
        with progress.reporting(log):  # factorisations, eigen-solves, reduction phases
            return _build(scene, log, modes, Stages(cache, log, kept, modes), stepper)


def build(scene, *, log=None, modes: int = 0, cache=None, stepper: bool = True) -> Simulation:
    """Build ``scene`` into a :class:`Simulation` (:meth:`Simulation.from_scene`).

    Parameters
    ----------
    scene : Scene
        A scene from :func:`~femrub.scene.load_scene`.
    log : callable, optional
        Receives progress messages (factorisations, eigen-solves, reduction).
    modes : int
        Natural frequencies (Hz) to compute and report.
    cache : ModelCache, optional
        A cache of assembled and reduced models (``None``: build everything).
    stepper : bool
        Build the stepper (``False``: ``Simulation.stepper`` is ``None``).

    Returns
    -------
    Simulation
    """
    return Simulation.from_scene(scene, log=log, modes=modes, cache=cache, stepper=stepper)


class SceneBuilds:
    """Builds of scenes on one blade in a row (the points of a sweep in one worker).

    Each build shares a :class:`~femrub.app.cached.Kept` with the others (the mesh's
    bases, the assembled blocks, the reductor and the map to the mesh: the last of each).
    A scene that differs from the previous one only in the rotation speed (both above 0,
    no centrifugal prestress, no coating or casing heat, no tip force at an engine order)
    is not built again: the previous full model at the new speed
    (:meth:`~femrub.model.first_order.FirstOrderModel.with_parameters`, its matrices,
    contacts and reach filter shared) is reduced with the kept reductor and checked
    (reduction error estimate, time-step check) like any build. A refused scene is built
    in full (``report["parametric"]`` says which).

    Parameters
    ----------
    cache : a :class:`~femrub.app.cache.ModelCache` or ``None``.
    """

    def __init__(self, cache=None):
        self.cache, self.kept, self._last = cache, Kept(), None

    def build(self, scene, *, log=None, modes: int = 0) -> Simulation:
        """The :class:`Simulation` of ``scene`` (the class docstring says what is reused)."""
        sim = None
        if self._last is not None and _differs_only_in_speed(self._last.scene, scene):
            with progress.reporting(log):
                stages = Stages(self.cache, log, self.kept, modes)
                sim = _at_speed(self._last, scene, stages, log, modes)
        if sim is None:
            sim = Simulation.from_scene(
                scene, log=log, modes=modes, cache=self.cache, kept=self.kept
            )
        # what the next build may take: the models, not this run's stepper or results
        self._last = replace(sim, stepper=None, ran=None)
        return sim

    __call__ = build


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
    check_run(scene)
    if scene.get("rotor.sectors") is not None:  # every blade of a wheel: its own pipeline
        from .wheel import build_wheel

        return build_wheel(scene, log)
    # the first run on this machine: the kernels it needs, compiled beside the build
    if jit.compile_in_background(tr.kernel_kinds(scene)) and log:
        log("compiling the contact kernels in a background process (first run here) ...")
    clock = _Clock(log)
    report = {
        "scene": scene.name,
        "source": scene.source,
        "kind": scene["geometry"]["kind"],
        "dropped": [],
        "reach_key": scene["contact"]["reach"],
    }
    blade = load_blade(scene, log)
    size = length_scale(blade)
    _check_scale(scene, size)
    probe_at = probe_points(scene, blade)  # node numbers checked before any assembly
    report["geometry"] = blade.summary()
    report["blade_size"] = size
    clock.done("mesh", f"{blade.n_vertices} vertices")
    full = _assembled(scene, blade, stages, log, report, clock, probe_at)
    return _runnable(scene, full, stages, log, modes, report, clock, with_stepper)


def _assembled(scene, blade, stages, log, report, clock, probe_at) -> _Full:
    """The full model, its fields and probes, reported; what only the assembly needed (the
    finite-element bases) is released when this returns, before the reduction."""
    built = _full_model(scene, blade, stages, log, report)
    clock.done("assembly", f"{built.model.n_dofs} state dofs")
    _report_full(scene, built, report)
    probes = _probes(scene, built, probe_at, report, log)
    return _Full(built.model, built.fields, probes)


@dataclass(frozen=True)
class _Full:
    """The full model of a build (its ``length_scale``: the blade's size, m) and its fields
    on the mesh."""

    model: object
    fields: object
    #: the probes' observation rows on the full model (:mod:`femrub.app.probes`)
    probes: dict


def _runnable(scene, full: _Full, stages, log, modes, report, clock, with_stepper) -> Simulation:
    """The :class:`Simulation` of a full model: its signals and limits, natural frequencies,
    reduction (checked) and stepper."""
    model, limits = _select_signals(scene, full.model, report, full.model.length_scale, full.probes)
    if modes and len(report.get("natural_frequencies_hz", ())) != modes:
        report["natural_frequencies_hz"] = stages.frequencies(model, modes).tolist()
    reuse = reused_run(scene, model, full.fields)
    reduced, reductor, ran = _reduce(
        scene, model, full.model, stages, log, limits, report, clock, reuse
    )
    report["model"] = {"n_dofs": reduced.n_dofs, **_layout(reduced)}
    report["damping"] = damped_modes(reduced)
    stepper = stepper_of(scene, reduced, report) if with_stepper else None
    report["outputs"] = {
        "vtk_stride": scene["outputs"]["vtk_stride"],
        "plots": scene["outputs"]["plots"],
    }
    report["timings"] = clock.timings
    return Simulation(
        scene,
        reduced,
        full.model,
        full.fields,
        reductor,
        stepper,
        limits,
        report,
        clock.timings,
        ran,
        full.probes,
    )


#: what a build at another speed reports anew (the rest is the previous build's report)
_PER_BUILD = ("reduction", "time_step", "model", "timings", "scene", "source")


def _differs_only_in_speed(before, scene) -> bool:
    """Whether ``scene`` is ``before`` at another rotation speed that the model of
    ``before`` can take as its parameter (:class:`SceneBuilds`)."""
    speeds = (before["loads"]["rotation_speed"], scene["loads"]["rotation_speed"])
    force = scene["loads"]["tip_force"]
    if min(speeds) <= 0.0 or force.get("frequency") == "rotation":
        return False  # the reach filter depends on Ω: at rest, or the forcing frequency
    if (before.source, before.base_dir) != (scene.source, scene.base_dir):
        return False
    return _but_speed(before.data) == _but_speed(scene.data)


def _but_speed(data: dict) -> dict:
    """The scene's data without its rotation speed."""
    loads = {k: v for k, v in data["loads"].items() if k != "rotation_speed"}
    return {**data, "loads": loads}


def _at_speed(last: Simulation, scene, stages, log, modes) -> Simulation | None:
    """``last`` at the rotation speed of ``scene`` (:class:`SceneBuilds`); ``None`` when its
    model refuses the speed as a parameter (a prestress, a coating or casing heat)."""
    omega = scene["loads"]["rotation_speed"]
    try:
        model = last.full.with_parameters(rotation_speed=omega)
    except ValueError:
        return None
    check_run(scene)
    clock = _Clock(log)
    report = {k: v for k, v in last.report.items() if k not in _PER_BUILD}
    report.update(scene=scene.name, source=scene.source)
    before = last.full.parameters["rotation_speed"]
    report["parametric"] = {"from_rotation_speed": before, "rotation_speed": omega}
    clock.done("assembly", f"the model at {before:g} rad/s taken at {omega:g} rad/s")
    full = _Full(model, last.fields, last.probes)
    return _runnable(scene, full, stages, log, modes, report, clock, True)


def _full_model(scene, blade, stages, log, report) -> RubBuild:
    """The scene's configuration (:func:`~femrub.app.translate.rub_config`) built by the one
    builder; a value the schema cannot see (e.g. a singular clamp) is a :class:`SceneError`."""
    if log:
        log("assembling the full model ...")
    report["material"] = []
    config = tr.rub_config(scene, blade.info.get("material"), report["material"])
    for note in report["material"] if log else ():
        log(f"notice: {note}")
    try:
        built = build_rub(blade, config, stages=stages, log=log)
    except ValueError as exc:
        if isinstance(exc, SceneError):
            raise
        raise SceneError(f"building the model of {scene.source}: {exc}") from None
    heat = built.heat
    report["thermal"] = built.thermal[1]
    report["friction"] = {"mu": heat.mu, "heat_law": heat.law, "heat_partition": heat.eta}
    report["rotation"] = {**vars(built.rotation), "slip": config.contact.slip_direction}
    warn(initial_penetration(built.model), report, log)
    warn(footprint_warning(scene, built.grid), report, log)
    return built


def _report_full(scene, built: RubBuild, report: dict) -> None:
    """What the report says of the full model: sizes, contacts kept, prestress, casing."""
    full = built.model
    report["dropped"] += [d for d in full.info.get("dropped", []) if "temperature" not in d]
    report["full"] = {
        "n_dofs": full.n_dofs,
        "fe_dofs": built.mats.n_u + built.mats.n_t,
        **_layout(full),
    }
    report["contacts"] = _contacts_report(built.candidates, built.reach)
    report["centrifugal"] = _centrifugal_report(scene, built.prestress, built.growth, built.reach)
    contact = full.contact
    wear = contact.wear if contact is not None else None
    report["abradable"] = wear.as_dict() if wear is not None else None
    ch = contact.casing_heat if contact is not None else None
    report["casing_heat"] = (
        None
        if ch is None
        else {
            "thickness": ch.b,
            "tau": ch.tau,
            "partition": built.heat.eta,
            "expansion": ch.expansion,
        }
    )


def _reduce(scene, model, full, stages, log, limits, report, clock, reuse):
    """The reduced model, its reductor and the run the reduction estimate (or the time-step
    check) stepped when it is the scene's run (``reuse``: :func:`reused_run`), else
    ``None`` (then every run of the checks is only compared)."""
    make = lambda m: bare_stepper(scene, m)  # noqa: E731  (the reduction error estimate)
    chosen = []  # (results, wall seconds, full states) of the estimate's run of the chosen sizes
    reduced, reductor, report["reduction"] = stages.reduce(
        model, scene, log, make, limits, on_run=lambda *run: chosen.append(run), reuse_run=reuse
    )
    reductor = None if reductor is None else reductor.released()  # its models are made
    ran = chosen[0][:2] if chosen and (reuse or holds_frames(chosen[0][0], scene)) else None
    if ran is not None:  # the run itself: its time is the run's ``stepping``
        clock.exclude(ran[1])
    clock.done("reduction", f"{reduced.n_dofs} dofs")
    if not scene["scheme"]["step_check"]:
        return reduced, reductor, ran
    given = None  # the estimate's run: compared only, unless it is the run (kept whole)
    if chosen:
        res, _, states = chosen.pop()
        given = (res if ran is not None else res.lean(), states)
    report["time_step"], run_h, wall_h = check_step(
        scene, reduced, full, lambda m, h: bare_stepper(scene, m, h), limits, given, reuse
    )
    if ran is None and wall_h is not None and (reuse or holds_frames(run_h[0], scene)):
        ran = (run_h[0], wall_h)  # the check stepped the run itself
        clock.exclude(wall_h)
    clock.done("step_check", f"time-step error {100 * report['time_step']['estimate']:.2g} %")
    return reduced, reductor, ran


def holds_frames(res, scene) -> bool:
    """Whether a run recorded whole holds the states of the scene's VTK frames (every
    ``outputs.vtk_stride``-th step stored: a run checked on windows), so that it can be
    the scene's run, its frames written from them."""
    stride, t = scene["outputs"]["vtk_stride"], res.state_times
    if not stride or t is None or "lean" in res.info:
        return False
    return len(t) == res.steps // stride + 1 and np.allclose(np.diff(t), stride * res.h)


def reused_run(scene, model, fields) -> bool:
    """Whether the run the checks step of the chosen model is kept as the scene's run: the
    same model, stepper, initial state, end time and stop limits, and the history its
    contact carried outside ``X`` (wear map, casing heat: ``Results.contact_history``), unless
    the run writes VTK frames (:func:`~femrub.app.run.run_scene` steps it again, its frames
    written as it steps). Otherwise the checks record every run they step as a run only
    compared."""
    return not (scene["outputs"]["vtk_stride"] and fields is not None)


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


def _probes(scene, built, points, report, log) -> dict:
    """The probes' rows on the full model (:mod:`femrub.app.probes`), reported and warned."""
    obs, report["probes"], warnings = probe_observations(scene, built, points)
    for msg in warnings:
        warn(msg, report, log)
    return obs


def _select_signals(scene, model, report, size, probes):
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
    units = {PROBE_PREFIX + p["name"]: p["unit"] for p in report["probes"]}
    info = {**model.info, "signal_units": units} if units else model.info
    return model.with_(observations={**obs, **probes}, info=info), kept_limits


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
