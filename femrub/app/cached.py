"""The model-building stages of :mod:`femrub.app.simulation` through a :class:`ModelCache`.

:class:`Stages` wraps the three expensive, deterministic stages of the pipeline; with no
cache it only calls them:

* ``assemble``: the Eq. (2) blocks (:func:`femrub.fem.discretisation.assemble`) without
  modal damping; key: the mesh itself (vertices, cells, curved mid-side node positions,
  element, clamped dofs: the content of the mesh file as read) and every argument of the
  assembly (material, lumping, coupling, Rayleigh coefficients, ...);
* ``damping``: the modal Rayleigh damping (:func:`femrub.reduction.modal_damping.modal_rayleigh`),
  set once the contacts' boundary is known, its frequencies taken through the interior
  factorisation that the reduction then reuses (``reduce`` hands it on); key: the assembly
  key, the boundary, ζ and the two modes; stored: ``(a, b)`` and the frequencies (on a hit
  ``C = a M + b K`` is formed, nothing is factorised);
* ``reduce``: the reduced model
  (:func:`femrub.analysis.reduction_check.reduce_checked`) and its
  report; key: the assembly key, every state-space array of the full model the reduction
  projects (``A``, ``B``, contact rows, load vectors, observations, energy forms, map to the
  mesh, boundary dofs, initial state), the ``reduction`` options and, for ``"auto"``, the
  end time that sets its thermal frequencies; the map to the mesh of the reductor's largest
  model (dense, a few hundred MB on a blade; a smaller size uses its leading columns) is not
  stored with it: a reduced model refers by its columns to the basis of the ``bases`` entry
  when the map is that basis (its constrained rows put back as it is read), else to its own
  entry ``map`` (key: the same without what the run depends on), stored once for every
  speed of a sweep; a hit whose basis or ``map`` is missing or corrupt is rebuilt like a
  miss;
* ``frequencies``: the natural frequencies of the full model (sweeps, ``--modes``), taken
  from the damping's eigen-solve when the build damps (one solve finds both);
* ``prestress``: the centrifugal prestress (:func:`femrub.fem.prestress.centrifugal_prestress`,
  a Newton solve on the full mesh); key: the mesh, the material, Ω and the method. The
  prestressed tangent then enters the assembly key (a prestressed model is per speed).

What a rotation speed changes without changing a matrix (the casing gap swept at Ω, the
heat coefficients, the restitution, the load signals) is not in the assembly key: every
point of a speed sweep on one blade shares the assembled model (unless a centrifugal
prestress, which depends on Ω, changes the stiffness). The reduction error
estimate (``docs/reduction.md``) steps the run itself, so a reduced model is keyed by the
scene's ``scheme``, ``loads`` and ``contact`` too; a cached reduced model takes the gap
functions and signals from the full model built in this run. Every key also holds
:func:`~femrub.app.cache.code_version`.
On a hit ``Simulation.reductor`` is ``None`` (the reduced model carries what the run needs,
including its map to the mesh).

Builds of one blade in a row (the points of a sweep in one worker,
:class:`femrub.app.simulation.SceneBuilds`) share a :class:`Kept`: the last discretisation
(the finite-element bases of the mesh), assembly, reductor and map to the mesh built or
loaded, so the next build takes them from memory instead of the cache folder. A
:class:`Stages` without one keeps nothing beyond its own build.

A reduced model missing from the cache whose bases the :class:`Kept` holds (same matrices,
same ``reduction`` options, given sizes) reuses that reductor with the reduced operators it
projected (:mod:`femrub.reduction.truncation`): only the reduction error estimate runs
again; the static shapes, modes and projection do not. The reductor is also stored in the
cache (stage ``bases``, without its full model; key: the reduced model's key without what
only the run depends on), so that another process (the other sweep worker, a later sweep or
run at another speed) loads it instead of building it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time

import numpy as np

from ..analysis.reduction_check import reduce_checked
from ..fem.discretisation import assemble, discretise
from ..fem.prestress import centrifugal_prestress
from ..reduction.modal_damping import modal_rayleigh
from ..reduction.sizes import natural_frequencies
from ..reduction.truncation import ColumnMap
from .cache import content_key

__all__ = ["Kept", "Stages"]


@dataclasses.dataclass
class Kept:
    """What builds of one blade in a row keep in memory, the last of each, ``{key: value}``.

    ``discretisation``: the finite-element bases of the mesh; ``assembly``: the Eq. (2)
    blocks (``assembly_key``: its key); ``reductor``: the last reductor
    built or loaded, detached from its full model (its bases are speed-free); ``map``: the
    map to the mesh of the largest reduced model (the same for every speed); ``model_key``:
    the last full model's hashed arrays and their key (``(parts, key)``).
    """

    discretisation: dict = dataclasses.field(default_factory=dict)
    assembly: dict = dataclasses.field(default_factory=dict)
    reductor: dict = dataclasses.field(default_factory=dict)
    map: dict = dataclasses.field(default_factory=dict)
    assembly_key: str | None = None
    model_key: tuple | None = None

    @staticmethod
    def last(memo: dict, key, value) -> None:
        """Keep ``value`` under ``key`` in ``memo``, in place of what it held."""
        memo.clear()
        memo[key] = value


class Stages:
    """The cached stages; ``cache``: a :class:`~femrub.app.cache.ModelCache` or ``None``;
    ``kept``: a :class:`Kept` shared with the builds before and after this one (``None``:
    this build keeps nothing for another)."""

    def __init__(self, cache=None, log=None, kept: Kept | None = None, modes: int = 0):
        self.cache, self.log = cache, log
        self.in_a_row = kept is not None
        self.kept = kept if kept is not None else Kept()
        self.hits: dict[str, bool] = {}
        self._mats_key = self.kept.assembly_key if self.in_a_row else None
        self._stiffness = None  # the interior factorisation of the damping, for ``reduce``
        #: natural frequencies the build reports: the damping's eigen-solve finds them too
        self.modes = int(modes)
        self._omega = None  # (K, ω) of that solve, for :meth:`frequencies`
        if cache is not None and log is not None and cache.log is None:
            cache.log = log

    def _say(self, text: str) -> None:
        if self.log:
            self.log(text)

    def _fetch(self, stage: str, key: str):
        t0 = time.perf_counter()
        obj = self.cache.load(key)
        self.hits[stage] = obj is not None
        if obj is not None:
            self._say(f"cache: {stage} loaded in {time.perf_counter() - t0:.2f} s ({key[:12]})")
        return obj

    @contextlib.contextmanager
    def _building(self, stage: str, key: str):
        """The cache's entry ``key`` of ``stage``, or ``None`` with the right to build it
        held for the block (:meth:`ModelCache.building <femrub.app.cache.ModelCache.building>`:
        a process that needs it while another builds it waits and loads it)."""
        hit = self._fetch(stage, key)
        if hit is not None:
            yield hit
            return
        with self.cache.building(key, stage):
            yield self._fetch(stage, key)  # stored meanwhile by the process waited for

    def _keep(self, stage: str, key: str, obj, describe: str) -> None:
        t0 = time.perf_counter()
        if self.cache.store(key, obj, stage=stage, describe=describe):
            self._say(f"cache: {stage} stored in {time.perf_counter() - t0:.2f} s ({key[:12]})")

    def discretise(self, blade, order: int, clamped: bool = True):
        """:func:`~femrub.fem.discretisation.discretise` of ``blade``; builds in a row
        (:class:`Kept`) keep the last one and hand its bases to the next build on the same
        mesh (key: vertices, cells, node sets, curved edge midpoints, order)."""
        if not self.in_a_row:
            return discretise(blade, order, clamped=clamped)
        mesh = blade.mesh
        key = content_key(
            "discretisation",
            type(mesh).__name__,
            mesh.p,
            mesh.t,
            blade.node_sets,
            blade.info.get("edge_midpoints"),
            order,
            clamped,
        )
        kept = self.kept.discretisation.get(key)
        if kept is not None:
            self._say(f"discretisation kept by this process ({key[:12]})")
            return dataclasses.replace(kept, blade=blade)
        disc = discretise(blade, order, clamped=clamped)
        Kept.last(self.kept.discretisation, key, disc)
        return disc

    def assemble(self, disc, material, **kw):
        """:func:`~femrub.fem.discretisation.assemble` of ``disc``, through the cache."""
        if self.cache is None:
            return assemble(disc, material, **kw)
        key = content_key(
            "assembly",
            *_mesh_parts(disc),
            disc.order,
            type(disc.dofs_u.elem).__name__,
            type(disc.dofs_t.elem).__name__,
            disc.fixed_u,
            disc.fixed_t,
            material,
            kw,
        )
        self._mats_key = key
        mats = self.kept.assembly.get(key) if self.in_a_row else None
        if mats is not None:
            self.hits["assembly"] = True
            self._say(f"cache: assembly kept by this process ({key[:12]})")
        else:
            with self._building("assembly", key) as mats:
                if mats is None:
                    mats = assemble(disc, material, **kw)
                    self._keep("assembly", key, mats, f"{mats.n_u} + {mats.n_t} FE dofs")
        if self.in_a_row:  # the next build on this blade: the same blocks
            Kept.last(self.kept.assembly, key, mats)
            self.kept.assembly_key = key
        return mats

    def damping(self, zeta: float, modes: tuple[int, int]):
        """``(mats, boundary) -> mats`` with the modal Rayleigh damping of ratio ``zeta`` at
        ``modes`` (``rub_model``'s ``damping``), through the cache; keeps the interior
        factorisation it makes for :meth:`reduce`."""

        def damp(mats, boundary):
            if self.cache is None or self._mats_key is None:
                return made(mats, boundary, None)
            key = content_key(self._mats_key, "damping", boundary, float(zeta), modes)
            with self._building("damping", key) as hit:
                if hit is None:
                    return made(mats, boundary, key)
            a, b = hit["rayleigh"]
            C = (a * mats.M + b * mats.K).tocsr()
            damped = dataclasses.replace(mats, C=C, info=dict(mats.info))
            damped.info["rayleigh"] = (a, b)
            if "omega" in hit:  # the frequencies a build reports, from the same solve
                self._omega = (mats.K, np.asarray(hit["omega"]))
            return damped

        def made(mats, boundary, key):
            t0 = time.perf_counter()
            damped, self._stiffness, omega = modal_rayleigh(
                mats, zeta, modes, boundary, at_least=self.modes
            )
            self._omega = (mats.K, omega)
            a, b = damped.info["rayleigh"]
            self._say(
                f"modal damping {zeta:g} at modes {modes[0]}, {modes[1]} ("
                f"{omega[modes[0] - 1] / (2 * np.pi):.6g} Hz, "
                f"{omega[modes[1] - 1] / (2 * np.pi):.6g} Hz) in {time.perf_counter() - t0:.2f} s"
            )
            if key is not None:
                value = {"rayleigh": (a, b), "omega": np.asarray(omega)}
                self._keep("damping", key, value, f"Rayleigh ({a:.4g}, {b:.4g})")
            return damped

        return damp

    def prestress(self, disc, material, omega: float, method: str):
        """:func:`~femrub.fem.prestress.centrifugal_prestress` of ``disc``, through the cache."""
        if self.cache is None:
            return centrifugal_prestress(disc, material, omega, method, log=self.log)
        key = content_key(
            "prestress",
            *_mesh_parts(disc),
            disc.order,
            type(disc.dofs_u.elem).__name__,
            disc.fixed_u,
            material,
            float(omega),
            method,
        )
        with self._building("prestress", key) as ps:
            if ps is None:
                ps = centrifugal_prestress(disc, material, omega, method, log=self.log)
                self._keep("prestress", key, ps, f"{method} at {omega:g} rad/s")
        return ps

    def _model_key(self, model) -> str:
        """The key of every state-space array the reduction projects; builds in a row take
        the last one's again when those arrays are the very same objects (a model at
        another speed shares them:
        :meth:`~femrub.model.first_order.FirstOrderModel.with_parameters`)."""
        n = model.n_dofs
        parts = (
            self._mats_key,
            model.layout,
            model.boundary,
            model.x0,
            model.A,
            model.B,
            _state_arrays(model.contact, n),
            [_state_arrays(t, n) for t in model.loads],
            model.observations,
            model.energy,
            model.to_full,
        )
        last = self.kept.model_key
        if last is not None and _same_objects(last[0], parts):
            return last[1]
        key = content_key(*parts)
        self.kept.model_key = (parts, key)
        return key

    def reduce(
        self, model, scene, log=None, make_stepper=None, limits=None, on_run=None, reuse_run=True
    ):
        """:func:`~femrub.analysis.reduction_check.reduce_checked`: ``(reduced, reductor,
        report)``.

        ``make_stepper`` (for the reduction error estimate, which steps the run itself)
        puts the scene's ``scheme``, ``loads`` and ``contact`` and the stop ``limits`` it
        applies to its runs into the key. ``on_run``, ``reuse_run``: see ``reduce_checked``
        (``on_run`` is not called on a cache hit: nothing is stepped). Builds in a row reuse
        the kept reductor of the same matrices, with or without a cache.
        """
        stiffness, self._stiffness = self._stiffness, None
        kw = {"limits": limits, "on_run": on_run, "stiffness": stiffness, "reuse_run": reuse_run}
        opts = dict(scene["reduction"])
        stored = self.cache is not None and self._mats_key is not None
        if opts["method"] == "none" or not (stored or self.in_a_row):
            out = reduce_checked(model, scene, log, make_stepper, **kw)  # nothing stored
            _say_phases(self._say, out[0].info.get("timings", {}))
            return out
        model_key = self._model_key(model)  # hashed once: the keys below derive from it
        map_key = content_key(model_key, "map", opts)  # the largest model's map: speed-free
        key = content_key(model_key, "reduction", opts, _run_key(scene, make_stepper, limits))
        bases = content_key(model_key, "bases", opts) if opts["method"] != "auto" else None
        if stored:
            hit = self._fetch("reduction", key)
            hit = None if hit is None else self._with_map(hit, map_key, bases)
            if hit is not None:
                if stiffness is not None:
                    stiffness.free()
                return _attach(hit, model), None, dict(hit["report"], cache="hit")
        with contextlib.ExitStack() as building:
            # the bases kept by this process, or built by another one (the cache), waited
            # for while another process builds them
            kept = self._loaded("bases", bases) if stored else self.kept.reductor.get(bases)
            if kept is None and stored and bases is not None:
                building.enter_context(self.cache.building(bases, "bases"))
                kept = self._loaded("bases", bases)

            def keep_bases(reductor) -> None:  # before the estimate's runs (they may free it)
                if bases is None:
                    return
                detached = reductor.detached()  # not the model of this point
                if self.in_a_row:
                    Kept.last(self.kept.reductor, bases, detached)
                if kept is None and stored:
                    shapes = f"{reductor.n_uv} + {reductor.n_theta} shapes on {model.n_dofs} dofs"
                    self._keep("bases", bases, detached, shapes)
                building.close()  # stored: a process waiting for them loads them now

            reduced, reductor, report = reduce_checked(
                model, scene, log, make_stepper, reductor=kept, on_bases=keep_bases, **kw
            )
        _say_phases(self._say, reduced.info.get("timings", {}))
        if stored:
            self._store_reduction(key, map_key, bases, reduced, reductor, report)
        return reduced, reductor, report

    def _store_reduction(self, key, map_key, bases, reduced, reductor, report) -> None:
        """Store ``reduced`` (entry ``reduction``) and its largest model's map: the basis of
        the ``bases`` entry when the map is that basis with the constrained rows put back (it
        is not stored twice), else its own entry ``map``."""
        entry, shared = _detach(reduced, report, reductor.R.shape[1])
        if shared is not None and bases is not None and shared is reductor.R:
            entry["map"]["basis"] = True  # the bases entry's basis (``_with_map``)
        elif shared is not None and self.kept.map.get(map_key) is not shared:
            if not self.cache.holds(map_key):  # stored by another point, process or run
                self._keep("map", map_key, shared, f"map to the mesh {shared.shape}")
            Kept.last(self.kept.map, map_key, shared)
        self._keep("reduction", key, entry, f"{reduced.n_dofs} dofs")

    def _with_map(self, hit: dict, map_key: str, bases: str | None):
        """A stored reduction with its map to the mesh (the basis of the ``bases`` entry, or
        the ``map`` entry; kept by this process or loaded); ``None`` when that entry is
        missing or corrupt: the caller rebuilds."""
        if hit.get("map") is None:  # stored with its own map
            return hit
        if hit["map"].get("basis"):
            reductor = self._loaded("bases", bases)
            full = None if reductor is None else reductor.R
        else:
            full = self._loaded("map", map_key)
        if full is None:
            self.hits["reduction"] = False
            self._say("cache: the reduction's map to the mesh is not in the cache; rebuilding")
            return None
        cols, rows = hit["map"]["columns"], hit["map"].get("rows")
        to_full = full if cols is None else ColumnMap(full, cols, rows)
        return dict(hit, model=hit["model"].with_(to_full=to_full))

    def _loaded(self, stage: str, key: str | None):
        """What this process keeps of ``stage`` (``"bases"``: the reductor, ``"map"``) under
        ``key``, else the cache's entry loaded and then kept; ``None`` without either."""
        memo = self.kept.reductor if stage == "bases" else self.kept.map
        value = memo.get(key)
        if value is None and key is not None:
            value = self._fetch(stage, key)
            if value is not None:
                Kept.last(memo, key, value)
        return value

    def frequencies(self, model, k: int) -> np.ndarray:
        """:func:`~femrub.reduction.sizes.natural_frequencies` (Hz), through the cache; the
        damping's eigen-solve when it found them (on the same ``K``)."""
        key = None
        if self.cache is not None and self._mats_key is not None:
            key = content_key(self._mats_key, "frequencies", model.layout.n_u, k)
            f = self._fetch("frequencies", key)
            if f is not None:
                return f
        f = None
        if self._omega is not None and self._omega[0] is model.blocks.K:
            omega = self._omega[1]
            f = omega[:k] / (2.0 * np.pi) if omega.size >= k else None
        if f is None:
            f = natural_frequencies(model, k)
        if key is not None:
            self._keep("frequencies", key, np.asarray(f), f"{k} frequencies")
        return f


def _run_key(scene, make_stepper, limits) -> list:
    """What a reduction's estimate depends on beyond the model: for ``"auto"`` the end time
    that sets its thermal frequencies; with ``make_stepper`` the scene's ``scheme`` (without
    the time-step check's keys), ``loads`` and ``contact`` and the stop ``limits``."""
    opts = scene["reduction"]
    t_end = scene["scheme"]["t_end"] if opts["method"] == "auto" else None
    if not make_stepper:
        return [t_end, None]
    run = [dict(scene[k]) for k in ("scheme", "loads", "contact")] + [dict(limits or {})]
    for key in ("step_check", "step_tolerance"):
        run[0].pop(key, None)
    return [t_end, run]


def _same_objects(a, b) -> bool:
    """Whether ``a`` and ``b`` hold the very same objects, container by container (dicts in
    the same order, lists, tuples); equal strings count as the same, and so do arrays that
    view the same memory the same way (a dataclass's ``__post_init__`` may wrap an array it
    is handed in a new view of it)."""
    if isinstance(a, np.ndarray) and isinstance(b, np.ndarray):
        return a is b or _same_view(a, b)
    if isinstance(a, dict):
        return (
            isinstance(b, dict) and list(a) == list(b) and all(_same_objects(a[k], b[k]) for k in a)
        )
    if isinstance(a, list | tuple):
        return type(a) is type(b) and len(a) == len(b) and all(map(_same_objects, a, b))
    return a is b or (isinstance(a, str) and a == b)


def _same_view(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether ``a`` and ``b`` read the same bytes as the same elements."""
    layout = (a.dtype, a.shape, a.strides, a.__array_interface__["data"][0])
    return layout == (b.dtype, b.shape, b.strides, b.__array_interface__["data"][0])


def _mesh_parts(disc) -> tuple:
    """What identifies a discretisation's mesh: its kind, vertices, cells and the curved
    position of every edge's midpoint read from the file (mid-side nodes of quadratic
    elements, ``blade.info["edge_midpoints"]``: they curve the P2 cells)."""
    mesh = disc.mesh
    midpoints = getattr(disc.blade, "info", {}).get("edge_midpoints")
    return type(mesh).__name__, mesh.p, mesh.t, midpoints


def _say_phases(say, timings: dict) -> None:
    """One line with the seconds of each phase of a reduction (static shapes, modes, ...)."""
    if timings:
        parts = ", ".join(f"{k.replace('_', ' ')} {v:.2f} s" for k, v in timings.items())
        say(f"reduction phases: {parts}")


def _state_arrays(obj, n: int) -> dict:
    """The fields of a dataclass that are state-space arrays (a first dimension ``n``).

    These are what a reduction projects (``Rᵀ G``, ``R̃ᵀ F``); the other fields (gap
    functions, heat coefficients, signals, names) pass through it unchanged.
    """
    if obj is None:
        return {}
    return {
        f.name: v
        for f in dataclasses.fields(obj)
        if isinstance(v := getattr(obj, f.name), np.ndarray) and v.ndim and v.shape[0] == n
    }


def _detach(reduced, report, largest: int) -> tuple[dict, np.ndarray | None]:
    """What to store of a reduced model: its arrays, without the run-specific functions, and
    the largest model's map to the mesh it uses (``largest``: that model's number of
    coordinates), stored once for every speed (the ``bases`` entry's basis, or the entry
    ``map``: :meth:`Stages._store_reduction`), or ``None`` (then the map is stored with the
    model)."""
    n, to_full, shared, ref = reduced.n_dofs, reduced.to_full, None, None
    if isinstance(to_full, ColumnMap):
        shared, ref = to_full.full, {"columns": to_full.cols, "rows": to_full.rows}
    elif isinstance(to_full, np.ndarray) and to_full.ndim == 2 and to_full.shape[1] == largest:
        shared, ref = to_full, {"columns": None}
    model = dataclasses.replace(reduced, contact=None, loads=[])
    if shared is not None:
        model = dataclasses.replace(model, to_full=None)
    entry = {
        "model": model,
        "contact": None if reduced.contact is None else _state_arrays(reduced.contact, n),
        "loads": [_state_arrays(t, n) for t in reduced.loads],
        "report": report,
        "map": ref,
    }
    return entry, shared


def _attach(hit: dict, full):
    """The stored reduced model with the gap, heat and load functions and the parameters
    (rotation speed) of ``full``."""
    model = hit["model"]
    contact = (
        None if hit["contact"] is None else dataclasses.replace(full.contact, **hit["contact"])
    )
    loads = [dataclasses.replace(t, **a) for t, a in zip(full.loads, hit["loads"], strict=True)]
    info = dict(model.info, full_info=dict(full.info))
    return model.with_(
        contact=contact, loads=loads, info=info, parameters=full.parameters, sweep=full.sweep
    )
