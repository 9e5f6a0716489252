"""Validation of a scene document: per-key checks against the schema, then cross-checks.

:func:`normalize` turns a parsed TOML document into the normalised scene data (every
section present, defaults filled in, quantities as SI floats) or raises a one-line
:class:`~femrub.scene.spec.SceneError`. It does no heavy work and touches no file;
:func:`check_files` checks the paths a scene references.
"""

from __future__ import annotations

import copy
import os
import re
from pathlib import Path

from .activation import check_activation
from .bounds import check_physical
from .schema import SCHEMA, TOP
from .schema_rotor import check_rotor
from .schema_run import PROBE_COMPONENTS, probe_names
from .spec import REQUIRED, SceneError, Variant, fail, unknown_key

__all__ = ["normalize", "check_files", "signals_for", "MAX_STEPS"]

#: the characters of a probe name (a history.npz key and a CSV column)
_PROBE_NAME = re.compile(r"[A-Za-z0-9_-]+")

#: Largest number of time steps a scene may ask for (memory of the histories).
MAX_STEPS = 20_000_000

_BAR_SIGNALS = ("tip_displacement", "tip_velocity", "tip_temperature", "contact_force")
_SOLID_SIGNALS = (
    "tip_displacement",
    "tip_velocity",
    "tip_temperature",
    "contact_displacement",
    "contact_temperature",
    "contact_force",
)


def signals_for(kind: str) -> tuple[str, ...]:
    """Signals a geometry kind can observe (``contact_force`` is always in the history)."""
    return _BAR_SIGNALS if kind == "bar" else _SOLID_SIGNALS


def normalize(doc) -> dict:
    """Validate a parsed scene document; return the normalised data (SI, defaults filled)."""
    if not isinstance(doc, dict):
        raise SceneError(f"a scene must be a TOML table, got {type(doc).__name__}")
    allowed = {**TOP, **SCHEMA}
    for key in doc:
        if key not in allowed:
            raise unknown_key(str(key), allowed)
    out = {k: spec.check(k, doc[k]) if k in doc else spec.default for k, spec in TOP.items()}
    physics = doc.get("physics")
    if isinstance(physics, dict) and isinstance(physics.get("thermal"), bool):
        physics = {**physics, "thermal": "on" if physics["thermal"] else "off"}
        doc = {**doc, "physics": physics}
    for section, spec in SCHEMA.items():
        out[section] = _table(section, doc.get(section, {}), spec)
    _cross_check(out)
    check_rotor(out)
    check_activation(out)
    return out


def _table(prefix: str, value, spec) -> dict:
    if not isinstance(value, dict):
        fail(prefix, value, "must be a table")
    out, where = {}, ""
    if isinstance(spec, Variant):
        choice = value.get(spec.selector, spec.default)
        if not isinstance(choice, str) or choice not in spec.variants:
            fail(f"{prefix}.{spec.selector}", choice, f"use one of {', '.join(spec.variants)}")
        keys = spec.keys_for(choice)
        out[spec.selector] = choice
        where = f" ({prefix}.{spec.selector} = {choice!r})"
        allowed = [spec.selector, *keys]
    else:
        keys, allowed = spec, list(spec)
    for k in value:
        if k not in allowed:
            err = unknown_key(f"{prefix}.{k}", allowed)
            raise SceneError(str(err).replace("; allowed", f"{where}; allowed", 1))
    for k, s in keys.items():
        dotted = f"{prefix}.{k}"
        if isinstance(s, Variant | dict):
            out[k] = _table(dotted, value.get(k, {}), s)
        elif k in value:
            out[k] = s.check(dotted, value[k])
            check_physical(dotted, s, out[k])
        elif s.default is REQUIRED:
            unit = f" in {s.unit}" if s.unit != "-" else ""
            raise SceneError(f"{dotted} is required{where}: {s.doc}{unit}")
        elif s.default is not None:
            out[k] = copy.deepcopy(s.default)
    return out


def _check_damping(physics: dict) -> None:
    modes = physics["damping_modes"]
    if len(modes) != 2 or not 1 <= modes[0] < modes[1]:
        fail("physics.damping_modes", modes, "give two mode numbers 1 <= i < j, e.g. [1, 5]")
    if physics["damping_ratio"] and any(physics["rayleigh"]):
        fail(
            "physics.damping_ratio",
            physics["damping_ratio"],
            "give either a modal damping ratio or physics.rayleigh, not both",
        )


def _check_coating(d: dict) -> None:
    """An abradable coating needs a yield force and the θ-method (bounded impulses)."""
    abr = d["contact"]["abradable"]
    if abr["thickness"] <= 0.0:
        return
    if abr["yield"] <= 0.0:
        fail("contact.abradable.yield", abr["yield"], "give the coating's yield force (N) > 0")
    if d["scheme"]["name"] != "theta":
        fail(
            "contact.abradable.thickness",
            abr["thickness"],
            "an abradable coating needs scheme.name = 'theta' (bounded impulses)",
        )


def _check_bar_contact(d: dict) -> None:
    """The bar's one contact: its tip, under a concentric casing, without friction."""
    contact = d["contact"]
    casing = contact["casing"]
    if casing["kind"] != "concentric":
        fail("contact.casing.kind", casing["kind"], "the 1D bar has a fixed gap; use 'concentric'")
    if contact["friction"] != 0.0:
        fail(
            "contact.friction",
            contact["friction"],
            "the 1D bar has no sliding speed; "
            "give its heat coefficient as contact.heat_coefficient (m/s)",
        )
    if contact["group"] != "contact" or contact.get("nodes") is not None:
        key = "contact.nodes" if contact.get("nodes") is not None else "contact.group"
        fail(
            key,
            contact.get("nodes") or contact["group"],
            "the 1D bar's only contact is its tip; remove the key",
        )


def _check_bar(d: dict) -> None:
    """Keys a 1D bar cannot honour (it has no mesh, no rotation axis, an axial force)."""
    _check_bar_contact(d)
    outputs, loads = d["outputs"], d["loads"]
    force = loads["tip_force"]
    if outputs["vtk_stride"]:
        fail(
            "outputs.vtk_stride",
            outputs["vtk_stride"],
            "VTK output needs a 3D geometry (geometry.kind = 'bar' has no mesh); use 0",
        )
    if force.get("direction", "radial") != "radial":
        fail(
            "loads.tip_force.direction",
            force["direction"],
            "the bar's tip force is axial; use 'radial'",
        )
    if d["boundary"].get("root") is not None:
        fail("boundary.root", d["boundary"]["root"], "the bar is clamped at x = 0; remove it")
    if loads["centrifugal"] in ("linear", "nonlinear"):
        fail(
            "loads.centrifugal",
            loads["centrifugal"],
            "the 1D bar has no rotation axis; use 'auto' or 'off'",
        )


def _check_blade_physics(d: dict) -> None:
    """A 3D blade: heat from friction, physical coupling, clamped root, node numbers of a mesh."""
    contact, kind = d["contact"], d["geometry"]["kind"]
    if contact["heat_coefficient"] != 0.0:
        fail(
            "contact.heat_coefficient",
            contact["heat_coefficient"],
            "3D contacts take their "
            "heat coefficient from contact.friction (α = friction Ω r); remove the key",
        )
    if d["physics"]["coupling"] == "paper":
        fail(
            "physics.coupling",
            "paper",
            "the paper coupling (β K^uu) is the 1D bar's; use 'physical', 'none' or 'auto' in 3D",
        )
    if not d["boundary"]["clamped"]:
        fail("boundary.clamped", False, "3D blades are clamped at boundary.root; use true")
    if contact.get("nodes") is not None and kind != "mesh":
        fail(
            "contact.nodes",
            contact["nodes"],
            "node numbers need geometry.kind = 'mesh'; use contact.group",
        )


def _check_blade_geometry(geo: dict) -> None:
    """The geometry keys of a 3D blade that depend on each other."""
    kind = geo["kind"]
    if kind == "sections" and (geo.get("path") is None) == (geo.get("files") is None):
        raise SceneError(
            "geometry: give exactly one of geometry.path (a folder) and "
            "geometry.files (a list of section files)"
        )
    if kind == "naca":
        from ..geometry.errors import GeometryError
        from ..geometry.naca import naca4_parameters

        try:
            naca4_parameters(geo["code"])
        except GeometryError as exc:
            fail("geometry.code", geo["code"], str(exc))
    h, h_min = geo.get("h"), geo.get("h_min")
    if kind in ("box", "naca") and h_min is not None and h is not None and h_min > h:
        fail("geometry.h_min", h_min, f"must be <= geometry.h = {h:g} m")


def _check_signals(d: dict) -> None:
    """``outputs.signals`` and ``limits`` name signals the geometry kind observes."""
    kind = d["geometry"]["kind"]
    known = signals_for(kind)
    sig = d["outputs"]["signals"]
    for name in [] if sig == "all" else sig:
        if name not in known or name == "contact_force":
            fail(
                "outputs.signals",
                name,
                f"unknown signal for geometry.kind = {kind!r}; use "
                f"'all' or some of {', '.join(k for k in known if k != 'contact_force')}",
            )
    for name in d["limits"]:
        if name not in known:
            fail(
                f"limits.{name}",
                d["limits"][name],
                f"no such signal for geometry.kind = {kind!r}; limits apply to {', '.join(known)}",
            )


def _check_probe(key: str, probe: dict, d: dict) -> None:
    """One ``outputs.probes`` table: a safe name, a node or a point, a component as its
    quantity needs, temperature dofs that can exist, a direction the geometry has."""
    name, quantity, component = probe["name"], probe["quantity"], probe.get("component")
    if not _PROBE_NAME.fullmatch(name):
        fail(f"{key}.name", name, "use letters, digits, '-' and '_' only (e.g. 'le_tip')")
    if "node" in probe and "point" in probe:
        fail(f"{key}.point", probe["point"], f"{key}.node is given too; give node or point")
    if "node" not in probe and "point" not in probe:
        raise SceneError(f"{key} ({name!r}) needs node (a mesh node number) or point (coordinates)")
    if quantity == "temperature":
        if component is not None:
            fail(f"{key}.component", component, "a temperature has no component; remove the key")
        if d["physics"]["thermal"] == "off":
            fail(
                f"{key}.quantity",
                quantity,
                "physics.thermal = 'off' leaves the model no temperature dofs; "
                "probe a displacement or turn physics.thermal on",
            )
        return
    if component is None:
        raise SceneError(
            f"{key}.component is required for a {quantity} probe: "
            f"one of {', '.join(PROBE_COMPONENTS)}"
        )
    if d["geometry"]["kind"] == "bar" and component not in ("x", "radial"):
        fail(f"{key}.component", component, "the 1D bar moves along x only; use 'x' or 'radial'")


def _check_wheel_probe(key: str, probe: dict, d: dict) -> None:
    """``blade`` only on a bladed disk (``rotor.sectors``), one of its blades; no
    temperature probe there (the blades' temperatures are read at the contacts)."""
    n, blade = d["rotor"].get("sectors"), probe.get("blade")
    if n is None:
        if blade is not None:
            fail(
                f"{key}.blade",
                blade,
                "a single-blade scene has one blade; remove the key, or set rotor.sectors "
                "for a bladed disk",
            )
        return
    if probe["quantity"] == "temperature":
        fail(
            f"{key}.quantity",
            "temperature",
            "a bladed disk (rotor.sectors) probes displacements and velocities; its blades' "
            "temperatures are read at the tip contacts (history.npz contact_temperature)",
        )
    if blade != "all" and blade is not None and blade >= n:
        fail(
            f"{key}.blade",
            blade,
            f"the wheel has {n} blades (rotor.sectors = {n}); give 0 to {n - 1}, or 'all'",
        )


def _check_probes(d: dict) -> None:
    """``outputs.probes``: each table (:func:`_check_wheel_probe`, :func:`_check_probe`),
    the names each records under (``blade = "all"``: one per blade) used once."""
    seen = {}
    for i, probe in enumerate(d["outputs"]["probes"]):
        key = f"outputs.probes[{i}]"
        _check_wheel_probe(key, probe, d)
        _check_probe(key, probe, d)
        for name in probe_names(probe, d["rotor"].get("sectors")):
            if name in seen:
                fail(
                    f"{key}.name",
                    probe["name"],
                    f"another probe ({seen[name]}) records probe_{name}; name each probe once",
                )
            seen[name] = key


def _check_scheme(d: dict) -> None:
    """The scheme against the contact law, its number of steps and the forcing."""
    scheme, contact, loads = d["scheme"], d["contact"], d["loads"]
    if scheme["name"] in ("carpenter", "penalty") and contact["restitution"] > 0.0:
        fail(
            "contact.restitution",
            contact["restitution"],
            f"scheme.name = {scheme['name']!r} models perfectly plastic impacts only; "
            "use scheme.name = 'theta' or contact.restitution = 0",
        )
    h, t_end = scheme["h"], scheme["t_end"]
    if t_end < h:
        fail("scheme.t_end", t_end, f"must be >= scheme.h = {h:g} s")
    if t_end / h > MAX_STEPS:
        fail(
            "scheme.h",
            h,
            f"gives {t_end / h:.3g} steps to t_end = {t_end:g} s; at most "
            f"{MAX_STEPS:.0e} allowed (raise h or lower t_end)",
        )
    force = loads["tip_force"]
    if force["law"] == "sin" and force["frequency"] == "rotation" and loads["rotation_speed"] == 0:
        fail(
            "loads.tip_force.frequency",
            "rotation",
            "with loads.rotation_speed = 0 the force "
            "would vanish; give a frequency in rad/s or a rotation speed",
        )


def _cross_check(d: dict) -> None:
    """The checks that involve several keys, one concept each."""
    _check_coating(d)
    if d["geometry"]["kind"] == "bar":
        _check_bar(d)
    else:
        _check_blade_physics(d)
        _check_blade_geometry(d["geometry"])
    _check_signals(d)
    _check_probes(d)
    _check_damping(d["physics"])
    _check_scheme(d)


def resolve_path(text: str, base_dir: Path) -> Path:
    """A scene path: ``{shared}/...`` in the reference-data folder, else from ``base_dir``."""
    if text.startswith("{shared}"):
        from ..geometry.rotor37 import shared_data_dir  # the one data-path lookup

        return shared_data_dir() / text[len("{shared}") :].lstrip("/\\")
    path = Path(os.path.expanduser(text))
    return path if path.is_absolute() else Path(base_dir) / path


def check_files(data: dict, base_dir: Path) -> None:
    """Raise a one-line :class:`SceneError` when a file the scene needs is missing."""
    geo = data["geometry"]
    entries = []
    if geo["kind"] == "mesh":
        entries.append(("geometry.path", geo["path"], "file"))
    elif geo["kind"] == "sections":
        if geo.get("path") is not None:
            entries.append(("geometry.path", geo["path"], "folder"))
        for i, f in enumerate(geo.get("files") or []):
            entries.append((f"geometry.files[{i}]", f, "file"))
    for key, text, what in entries:
        path = resolve_path(text, base_dir)
        ok = path.is_file() if what == "file" else path.is_dir()
        if not ok:
            hint = ""
            if text.startswith("{shared}"):
                hint = (
                    "; the reference data folder is absent or incomplete (set FEMRUB_SHARED_DATA)"
                )
            fail(key, text, f"{what} {path} not found{hint}")
