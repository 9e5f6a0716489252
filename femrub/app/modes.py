"""``femrub modes SCENE -o DIR``: the modes of a bladed disk and its casing ring by nodal diameter.

A scene with ``rotor.sectors = N`` (:mod:`femrub.scene.schema_rotor`) is meshed as one
cyclic sector (:func:`~femrub.geometry.bladed_disk.bladed_disk_sector`: the disk sector and
the scene's NACA blade; :func:`~femrub.geometry.sections_disk.sections_disk_sector`: the
blade lofted through the scene's section files), assembled with P2 tetrahedra and the
centrifugal prestress at ``loads.rotation_speed`` (``loads.centrifugal``: ``auto`` is
nonlinear above rest, ``off`` none), and solved per nodal diameter ``k = 0 .. ⌊N/2⌋``
(:mod:`femrub.model.cyclic`), ``rotor.families`` modes each. With ``casing.ring.thickness``,
the casing ring around the tips (bore radius: the blades' largest tip radius +
``casing.ring.clearance``) is meshed as a sector of the same ``N`` and solved likewise, at
rest; the rotation speeds of ``k Ω = ω_disk + ω_casing`` follow (:mod:`femrub.model.coincidence`).

With ``speeds`` (``femrub modes --speeds A:B:STEP``, rad/s) the disk's modes are solved at
every listed speed, the sector assembled once and its prestress solved speed after speed
from the previous state (:func:`~femrub.model.cyclic.mode_tables_over_speeds`), the casing's
once; the coincidence speeds are then the roots of ``k Ω − ω_disk,k(Ω) − ω_casing,k``
between listed speeds (:func:`~femrub.model.coincidence.coincidences_over_speeds`) and the
folder gains ``campbell.png``.

A single-blade scene (no ``rotor.sectors``) gets its blade's ``rotor.families`` lowest
modes at the scene's speed with the same prestress (``structure = blade``, no nodal
diameter): the blade clamped at its root is the bladed disk of a rigid disk.

Files (:mod:`femrub.output.modes`): ``modes.csv``, ``modes.png``, ``coincidences.csv``
(with a casing ring), ``campbell.png`` (with ``speeds``) and ``summary.json`` (``status``
``ok``, or ``failed`` / ``interrupted`` with the stages finished kept, ``message``,
``timings`` per stage, sizes, the sector's geometry).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..fem.material import Material
from ..model.cyclic import ModeTable, cyclic_structure, mode_table, mode_tables_over_speeds
from ..scene.spec import SceneError, fail
from . import translate as tr

__all__ = [
    "ModesResult",
    "casing_sector",
    "compute_modes",
    "modes_speeds",
    "modes_to_folder",
    "rotor_sector",
    "write_modes_folder",
]


@dataclass
class ModesResult:
    """The mode tables of a scene (``{"disk" | "casing" | "blade": ModeTable}``; the disk's
    at the top speed of a sweep), the disk's tables at every speed of a sweep (``sweep``,
    empty without one), the coincidence speeds, and what the computation reports (``info``:
    sizes, timings)."""

    tables: dict
    coincidences: list = field(default_factory=list)
    info: dict = field(default_factory=dict)
    sweep: list = field(default_factory=list)


def modes_speeds(text: str, scene) -> np.ndarray:
    """The speeds (rad/s) of ``femrub modes --speeds TEXT`` for ``scene``, refused in one line
    unless two or more, increasing, not negative, and the scene a bladed disk."""
    from .campbell import parse_speeds

    speeds = parse_speeds(text)
    if speeds.size < 2 or np.any(np.diff(speeds) <= 0.0) or speeds[0] < 0.0:
        raise SceneError(
            f"--speeds {text!r}: give two or more increasing speeds >= 0 (rad/s), "
            "e.g. --speeds 0:3000:500"
        )
    if scene["rotor"].get("sectors") is None:
        raise SceneError(
            f"--speeds {text!r}: speeds are for a bladed disk (rotor.sectors); "
            f"for a single blade use femrub campbell {scene.name} --speeds {text}"
        )
    return speeds


def _blade_of(scene) -> dict:
    g = scene["geometry"]
    keys = ("code", "span", "root_chord", "tip_chord", "twist", "n_sections", "stacking")
    return {k: g[k] for k in keys} | {"n_points": g["n_points"]}


def _sections_sector(scene, h: float):
    """The sector of a bladed disk whose blade is lofted through the scene's section files;
    a blade that does not fit the disk sector is refused by the ``rotor`` key at fault
    before meshing (:func:`~femrub.geometry.sections_disk.fit_problem`)."""
    from ..geometry.errors import GeometryError
    from ..geometry.sections import read_sections
    from ..geometry.sections_disk import fit_problem, place_sections, sections_disk_sector

    r, g = scene["rotor"], scene["geometry"]
    files = g.get("files")
    paths = [scene.path(f) for f in files] if files else scene.path(g["path"])
    try:
        sections = read_sections(paths, g["length_unit"], g["pattern"])
        blade = place_sections(sections, g["axis"])
    except GeometryError as exc:
        fail("geometry.files" if files else "geometry.path", files or g["path"], str(exc))
    disk = (r["sectors"], r["hub_radius"], r["rim_radius"], r["thickness"])
    problem = fit_problem(blade, *disk)
    if problem is not None:
        name, value, reason = problem
        fail(f"rotor.{name}", value, reason)
    return sections_disk_sector(
        *disk, blade, h=h, h_min=g.get("h_min"), interpolate=g["interpolate"], ruled=g["ruled"]
    )


def rotor_sector(scene):
    """The meshed sector of the scene's bladed disk (``rotor`` and ``geometry`` keys): the
    NACA blade's (:func:`~femrub.geometry.bladed_disk.bladed_disk_sector`) or the section
    files' (:func:`~femrub.geometry.sections_disk.sections_disk_sector`)."""
    from ..geometry.bladed_disk import bladed_disk_sector
    from ..geometry.errors import GeometryError

    r, g = scene["rotor"], scene["geometry"]
    h = r.get("h") or g.get("h") or r["thickness"] / 3
    try:
        if g["kind"] == "sections":
            return _sections_sector(scene, h)
        return bladed_disk_sector(
            r["sectors"],
            r["hub_radius"],
            r["rim_radius"],
            r["thickness"],
            _blade_of(scene),
            h=h,
            h_min=g.get("h_min"),
        )
    except GeometryError as exc:
        raise SceneError(f"rotor: {exc}") from None


def casing_sector(scene, tip_radius: float):
    """The meshed sector of the scene's casing ring around blades reaching ``tip_radius`` (m)."""
    from ..geometry.casing_ring import RingDistortion, casing_ring_sector
    from ..geometry.errors import GeometryError

    c = scene["casing"]["ring"]
    distortion = RingDistortion(c["lobes"], c["distortion"])
    try:
        return casing_ring_sector(
            scene["rotor"]["sectors"],
            tip_radius + c["clearance"],
            c["thickness"],
            c["axial_length"],
            distortion=distortion,
            h=c.get("h"),
        )
    except GeometryError as exc:
        raise SceneError(f"casing.ring: {exc}") from None


def ring_material(scene) -> Material:
    """The casing ring's material (``casing.ring.young``, ``poisson``, ``density``)."""
    c = scene["casing"]["ring"]
    return Material(young=c["young"], rho=c["density"], poisson=c["poisson"])


def _solve(sector, material, omega, prestress, families, timings, stage, log):
    t0 = time.perf_counter()
    structure = cyclic_structure(sector, material, omega=omega, prestress=prestress)
    t1 = time.perf_counter()
    if log:
        log(f"{stage}: {structure.free.size} free dofs per sector; modes by nodal diameter ...")
    table = mode_table(structure, families)
    timings[f"{stage}_assembly"] = t1 - t0
    timings[f"{stage}_eigen"] = time.perf_counter() - t1
    return structure, table


def _disk(scene, log, result: ModesResult, speeds):
    """The disk's sector and its modes, at the scene's speed or at every one of ``speeds``."""
    timings, info = result.info.setdefault("timings", {}), result.info
    omega = float(scene["loads"]["rotation_speed"])
    method = tr.centrifugal_of(scene) or "off"
    material, families = tr.material_of(scene), scene["rotor"]["families"]
    t0 = time.perf_counter()
    if log:
        log(f"mesh: bladed disk sector of {scene['rotor']['sectors']} ...")
    disk = rotor_sector(scene)
    timings["disk_mesh"] = time.perf_counter() - t0
    if speeds is None:
        structure, table = _solve(disk, material, omega, method, families, timings, "disk", log)
    else:
        info["speeds"] = [float(w) for w in speeds]
        t1 = time.perf_counter()
        structure = cyclic_structure(disk, material, prestress=method)
        t2 = time.perf_counter()
        if log:
            log(f"disk: {structure.free.size} free dofs per sector; modes at {speeds.size} speeds")
        mode_tables_over_speeds(structure, material, speeds, families, done=result.sweep)
        timings["disk_assembly"] = t2 - t1
        timings["disk_speeds"] = time.perf_counter() - t2
        table = result.sweep[-1]
    result.tables["disk"] = table
    info["disk"] = {
        "sectors": disk.n_sectors,
        "tets": disk.mesh.n_tets,
        "free_dofs": int(structure.free.size),
        "prestress": method,
        **{k: v for k, v in disk.info.items()},
    }
    return disk


def _casing(scene, log, result: ModesResult, tip_radius: float) -> None:
    """The casing ring's sector and its modes at rest."""
    timings, tables = result.info["timings"], result.tables
    t0 = time.perf_counter()
    ring = casing_sector(scene, tip_radius)
    timings["casing_mesh"] = time.perf_counter() - t0
    families = scene["casing"]["ring"]["families"]
    rs, tables["casing"] = _solve(
        ring, ring_material(scene), 0.0, "off", families, timings, "casing", log
    )
    d = ring.info["distortion"]
    result.info["casing"] = {
        "sectors": ring.n_sectors,
        "tets": ring.mesh.n_tets,
        "free_dofs": int(rs.free.size),
        **{k: v for k, v in ring.info.items() if k != "distortion"},
        "lobes": d.lobes,
        "distortion": d.amplitude,
    }


def _bladed_disk(scene, log, result: ModesResult, speeds) -> ModesResult:
    from ..model.coincidence import coincidences, coincidences_over_speeds

    disk = _disk(scene, log, result, speeds)
    if scene["casing"]["ring"].get("thickness") is not None:
        _casing(scene, log, result, disk.info["tip_radius"])
        casing = result.tables["casing"]
        if speeds is None:
            result.coincidences = coincidences(result.tables["disk"], casing)
        else:
            result.coincidences = coincidences_over_speeds(result.sweep, casing)
    return result


def _single_blade(scene, log, result: ModesResult) -> ModesResult:
    from .campbell import campbell

    if tr.is_bar(scene):
        raise SceneError(
            "geometry.kind = 'bar': femrub modes needs a 3D blade or a bladed disk (rotor.sectors)"
        )
    omega = float(scene["loads"]["rotation_speed"])
    families = scene["rotor"]["families"]
    t0 = time.perf_counter()
    res = campbell(scene, np.array([omega]), modes=families, exact=True, log=log)
    f = np.asarray(res.frequencies[0], dtype=float)
    table = ModeTable(None, np.arange(1, f.size + 1), f, omega)
    result.tables["blade"] = table
    result.info["timings"] = {"blade": time.perf_counter() - t0}
    result.info["blade"] = {"prestress": res.method, "free_dofs": res.info.get("n_free_dofs")}
    return result


def compute_modes(scene, log=None, into: ModesResult | None = None, speeds=None) -> ModesResult:
    """The modes of ``scene`` (module docstring): a bladed disk and its casing ring, or the
    single blade. ``into``: the result filled stage by stage (what a failed or interrupted
    computation has finished stays in it). ``speeds``: the disk's rotation speeds (rad/s,
    increasing; :func:`modes_speeds`), ``None`` for the scene's speed only."""
    result = ModesResult({}) if into is None else into
    if scene["rotor"].get("sectors") is None:
        if speeds is not None:
            raise SceneError("speeds are for a bladed disk (rotor.sectors); use femrub campbell")
        return _single_blade(scene, log, result)
    return _bladed_disk(scene, log, result, None if speeds is None else np.asarray(speeds))


def modes_to_folder(scene, out, *, overwrite: bool = False, log=None, speeds=None) -> dict:
    """Claim ``out`` (kind ``modes``), compute the modes (at ``speeds``, rad/s, when given)
    and write the folder; return the summary. A computation that fails or is interrupted
    writes what it finished with ``status`` ``failed`` or ``interrupted`` and its one-line
    ``message``, then raises."""
    from ..output.folder import claim

    result = ModesResult({})
    with claim(out, "modes", overwrite=overwrite):
        try:
            compute_modes(scene, log, into=result, speeds=speeds)
        except BaseException as exc:
            status = "interrupted" if isinstance(exc, KeyboardInterrupt) else "failed"
            text = str(exc).strip().splitlines()
            message = text[0] if text else type(exc).__name__
            write_modes_folder(result, out, scene, status=status, message=message)
            raise
        return write_modes_folder(result, out, scene)


def _message(result: ModesResult) -> str:
    parts = [f"{t.frequency_hz.size} {name} modes" for name, t in result.tables.items()]
    if result.sweep:
        parts[0] += f" at each of {len(result.sweep)} speeds"
    if "casing" in result.tables:
        parts.append(f"{len(result.coincidences)} coincidence speeds")
    return ", ".join(parts)


def write_modes_folder(
    result: ModesResult, out, scene, *, status: str = "ok", message: str | None = None
) -> dict:
    """Write the files of the module docstring into ``out`` (already claimed); return the
    summary (``status``, ``message``: those of a computation that did not finish)."""
    from ..output.jsonfile import write_json
    from ..output.modes import plot_campbell, plot_modes, write_coincidences, write_modes

    out = Path(out)
    t0 = time.perf_counter()
    files = ["modes.csv", "modes.png", "summary.json"]
    blocks = [("disk", t) for t in result.sweep]
    blocks += [(name, t) for name, t in result.tables.items() if not (blocks and name == "disk")]
    write_modes(out / "modes.csv", blocks)
    if "casing" in result.tables and "disk" in result.tables:
        write_coincidences(out / "coincidences.csv", result.coincidences)
        files.insert(2, "coincidences.csv")
    omega = float(scene["loads"]["rotation_speed"])
    speeds = [t.rotation_speed for t in result.sweep]
    title = f"{scene.name}: modes by nodal diameter"
    shown = {"disk": result.sweep[-1], **result.tables} if result.sweep else result.tables
    plot_modes(
        out / "modes.png",
        shown,
        result.coincidences,
        rotation_speed=speeds[-1] if speeds else omega,
        speed_range=(speeds[0], speeds[-1]) if speeds else None,
        title=title,
    )
    if speeds:
        title = f"{scene.name}: Campbell diagram by nodal diameter (rotating frame)"
        casing = result.tables.get("casing")
        plot_campbell(out / "campbell.png", result.sweep, casing, result.coincidences, title)
        files.insert(-1, "campbell.png")
    timings = dict(result.info.get("timings", {}), output=time.perf_counter() - t0)
    summary = {
        "status": status,
        "message": message or _message(result),
        "scene": scene.name,
        "structures": list(result.tables),
        "rotation_speed": omega,
        "rotation_speed_rpm": omega * 30.0 / math.pi,
        "files": files,
        **{k: v for k, v in result.info.items() if k != "timings"},
        "coincidence_rule": "k Ω = ω_disk,k + ω_casing,k (disk backward wave, casing forward)",
        "timings": timings,
    }
    if scene["rotor"].get("mistuning"):
        summary["mistuning"] = (
            "not applied: the modes by nodal diameter are the tuned wheel's (femrub run applies "
            "rotor.mistuning)"
        )
    write_json(out / "summary.json", summary)
    return summary
