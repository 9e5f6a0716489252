"""Build what a scene needs, and only that: model, contacts, reduction, stepper.

:func:`build` validates the files, meshes or reads the blade, assembles the full model
(temperature dofs only when something heats the blade), keeps the contacts the casing can
reach, keeps the requested signals, reduces when asked, creates the stepper and checks the
step against Carpenter's stability limit, all before any time step. ``Built.report`` says
what was built and why (``femrub run SCENE --explain``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..reduction.sizes import natural_frequencies, reduce_model
from ..scene.spec import SceneError, fail
from ..steppers import make_stepper
from .blade import load_blade
from .explain import explain
from .full_model import build_full, contact_reach, heat_possible, restrict_contacts, thermal_choice

__all__ = ["Built", "build"]


@dataclass
class Built:
    """A built scene: the model that runs, the full model, the stepper and the report."""

    scene: object
    model: object
    full: object
    fields: object
    reductor: object
    stepper: object
    limits: dict
    report: dict = field(default_factory=dict)

    def explain(self) -> str:
        """What was built and why, as text (``femrub run SCENE --explain``)."""
        return explain(self.report)


def _scheme_options(scene) -> dict:
    s = scene["scheme"]
    if s["name"] == "theta":
        return {"gamma": s["gamma"], "activation": s["activation"]}
    if s["name"] == "penalty":
        return {"stiffness": s["stiffness"], "damping": s["damping"], "method": s["method"]}
    return {}


def _select_signals(scene, model, report):
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
    report["limits"], report["ignored"] = kept_limits, ignored
    return model.with_(observations=obs), kept_limits


def _contacts_report(full, reach, fields) -> dict:
    names = list(full.contact.names) if full.contact is not None else []
    keep = reach["keep"]
    return {
        "candidates": len(names),
        "kept": [n for n, k in zip(names, keep) if k],
        "dropped": [
            {"name": n, "min_gap": float(g)} for n, g, k in zip(names, reach["min_gap"], keep)
            if not k
        ],
        "min_gap_kept": [float(g) for g, k in zip(reach["min_gap"], keep) if k],
        "reach": reach["reach"],
        "deflection": reach["deflection"],
        "intrusion": reach["intrusion"],
        "max_offset": float(np.max(reach["offset"])) if len(names) else 0.0,
    }  # fmt: skip


def build(scene, *, log=None, modes: int = 0) -> Built:
    """Build ``scene`` (see the module docstring); ``modes``: natural frequencies to report.

    Raises
    ------
    SceneError
        A one-line message naming the key at fault (missing file or group, step above the
        stability limit, ...).
    """
    timings, t0 = {}, time.perf_counter()
    scene.check_files()
    kind = scene["geometry"]["kind"]
    report = {
        "scene": scene.name,
        "source": scene.source,
        "kind": kind,
        "dropped": [],
        "reach_key": scene["contact"]["reach"],
    }
    blade = None
    if kind != "bar":
        blade = load_blade(scene, log)
        report["geometry"] = blade.summary()
        timings["geometry"] = time.perf_counter() - t0
        _done(log, "geometry", timings["geometry"], f"{blade.n_tets} tetrahedra")
    else:
        g = scene["geometry"]
        report["geometry"] = f"1D bar, L = {g['length']:g} m, {g['n_elements']} elements"
    heated = heat_possible(scene)
    keep_t, why = thermal_choice(scene, heated)
    t1 = time.perf_counter()
    if log:
        log("assembling the full model ...")
    try:
        full, fields = build_full(scene, keep_t, blade)
        reach = contact_reach(scene, full, fields)
        if heated and keep_t and not reach["keep"].any():
            keep2, why2 = thermal_choice(scene, False, reachable=False)
            if keep2 != keep_t:
                keep_t, why = keep2, why2
                full, fields = build_full(scene, keep_t, blade)
    except SceneError:
        raise
    except ValueError as exc:  # a value the schema cannot see (e.g. a singular clamp)
        raise SceneError(f"building the model of {scene.source}: {exc}") from None
    timings["assembly"] = time.perf_counter() - t1
    _done(log, "assembly", timings["assembly"], f"{full.n_dofs} state dofs")
    report["thermal"] = why
    report["dropped"] += [d for d in full.info.get("dropped", []) if "temperature" not in d]
    report["full"] = {"n_dofs": full.n_dofs, **_layout(full)}
    if "fe_dofs" in full.info:
        report["full"]["fe_dofs"] = full.info["fe_dofs"]
    report["contacts"] = _contacts_report(full, reach, fields)
    model, fields = restrict_contacts(full, fields, reach["keep"], reach["offset"])
    model, limits = _select_signals(scene, model, report)
    if modes:
        report["natural_frequencies_hz"] = natural_frequencies(model, modes).tolist()
    t2 = time.perf_counter()
    reduced, reductor, red_report = reduce_model(model, scene, log)
    timings["reduction"] = time.perf_counter() - t2
    if reductor is not None:
        _done(log, "reduction", timings["reduction"], f"{reduced.n_dofs} dofs")
    report["reduction"] = red_report
    report["model"] = {"n_dofs": reduced.n_dofs, **_layout(reduced)}
    s = scene["scheme"]
    t3 = time.perf_counter()
    try:
        stepper = make_stepper(s["name"], reduced, s["h"], **_scheme_options(scene))
    except ValueError as exc:
        raise SceneError(f"scheme ({s['name']}): {exc}") from None
    report["scheme"] = {
        "name": s["name"],
        "h": s["h"],
        "t_end": s["t_end"],
        "steps": int(round(s["t_end"] / s["h"])),
        **_scheme_options(scene),
    }
    if s["name"] == "carpenter":
        limit = stepper.stability_limit()
        report["scheme"]["stability_limit"] = limit
        if s["h"] > limit:
            fail(
                "scheme.h",
                s["h"],
                f"exceeds the stability limit {limit:.3g} s of Carpenter's "
                f"explicit scheme for this model; use scheme.h <= {_floor(limit)} or "
                "scheme.name = 'theta'",
            )
    timings["stepper"] = time.perf_counter() - t3
    report["outputs"] = {
        "vtk_stride": scene["outputs"]["vtk_stride"],
        "plots": scene["outputs"]["plots"],
    }
    timings["total"] = time.perf_counter() - t0
    report["timings"] = timings
    return Built(scene, reduced, full, fields, reductor, stepper, limits, report)


def _done(log, what: str, seconds: float, result: str) -> None:
    if log:
        log(f"{what} done in {seconds:.2f} s: {result}")


def _layout(model) -> dict:
    L = model.layout
    return {"n_u": L.n_u, "n_v": L.n_v, "n_theta": L.n_t, "n_contacts": model.n_contacts}


def _floor(x: float) -> str:
    """``x`` rounded down to 2 significant digits, as text."""
    e = math.floor(math.log10(x))
    return f"{math.floor(x / 10**e * 10) / 10 * 10**e:.2g}"
