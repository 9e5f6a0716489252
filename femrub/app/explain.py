"""Text of ``femrub run SCENE --explain``: what was built and why, from a build report."""

from __future__ import annotations

import math

from ..reduction.estimate import QUANTITIES

__all__ = ["explain", "format_timings"]


def format_timings(timings: dict) -> str:
    """``mesh 0.12 s, assembly 1.30 s, ...`` in pipeline order."""
    return ", ".join(f"{k} {v:.2f} s" for k, v in timings.items())


def _um(x: float) -> str:
    if not math.isfinite(x):
        return "inf"
    return f"{x * 1e3:.3g} mm" if abs(x) >= 1e-3 else f"{x * 1e6:.3g} µm"


def _dofs(d: dict) -> str:
    parts = f"u {d['n_u']} + v {d['n_v']}" + (f" + θ {d['n_theta']}" if d["n_theta"] else "")
    return f"{d['n_dofs']} state dofs ({parts}), {d['n_contacts']} contact(s)"


def _contacts(c: dict, reach_key) -> list[str]:
    n, kept, dropped = c["candidates"], c["kept"], c["dropped"]
    if not n:
        return ["no contact points"]
    if reach_key == "auto":
        rule = (
            f"reach {_um(c['reach'])} = 2 × tip-force deflection {_um(c['deflection'])}"
            f" + casing intrusion {_um(c['intrusion'])} (+ margin)"
        )
    elif reach_key == "all":
        rule = "contact.reach = 'all'"
    else:
        rule = f"contact.reach = {_um(c['reach'])}"
    lines = [f"{len(kept)} of {n} kept ({rule})"]
    if c["min_gap_kept"]:
        lines.append(
            f"smallest gap over a revolution of the kept ones: "
            f"{_um(min(c['min_gap_kept']))} .. {_um(max(c['min_gap_kept']))}"
        )
    if dropped:
        shown = ", ".join(f"{d['name']} ({_um(d['min_gap'])})" for d in dropped[:6])
        more = f" and {len(dropped) - 6} more" if len(dropped) > 6 else ""
        lines.append(f"dropped {len(dropped)}: never within reach, smallest gap {shown}{more}")
    return lines


def _thermal_word(r: dict) -> str:
    return "input shapes" if r.get("thermal") == "inputs" else "dofs"


def _centrifugal(c: dict | None) -> list[str]:
    if not c:
        return []
    if c["method"] == "off":
        return [f"off ({c['why']})"]
    head = (
        f"{c['method']} prestress at {c['rotation_speed']:g} rad/s "
        f"({c['newton_iterations']} Newton iterations, {c['load_increments']} load "
        f"increment(s), residual {c['residual']:.1e}); geometric stiffness and spin "
        "softening in K"
    )
    grow = (
        f"radial tip growth at the contacts {_um(c['tip_growth_min'])} .. "
        f"{_um(c['tip_growth_max'])} (mean {_um(c['tip_growth_mean'])})"
    )
    if c["clearance"] == "running":
        gaps = "running clearances (contact.clearance = 'running'): the growth closes nothing"
    else:
        gaps = "cold clearances (contact.clearance = 'cold'): the growth closes the gaps"
    gaps += f"; smallest gap over a revolution {_um(c['min_gap'])} .. {_um(c['max_min_gap'])}"
    return [head, grow, gaps]


def _reduction(r: dict) -> list[str]:
    if r["method"] == "none":
        return ["none (reduction.method = 'none'): the full model runs"]
    head = (
        f"{r['method']}: n_uv = {r['n_uv']}, n_theta = {r['n_theta']} -> {r['n_reduced']}"
        f" dofs (from {r['n_full']}; boundary {r['n_boundary_u']} u + "
        f"{r['n_boundary_theta']} θ {_thermal_word(r)}, {r['projection']})"
    )
    lines = [head]
    if r["method"] == "auto":
        f = r.get("natural_frequencies_hz", [])
        ok = "meets" if r.get("frequency_target_met") else "MISSES"
        lines.append(
            f"first {len(f)} natural frequencies within {100 * r['frequency_error']:.2g} %"
            f" ({ok} target {100 * r['target']:.2g} %): " + ", ".join(f"{x:.4g}" for x in f) + " Hz"
        )
        if "thermal_error" in r:
            ok = "meets" if r.get("thermal_target_met") else "MISSES"
            lines.append(
                f"contact-temperature response within {100 * r['thermal_error']:.2g} %"
                f" ({ok} the target)"
            )
    err = r.get("error")
    if err:
        q = ", ".join(f"{k.replace('_', ' ')} {100 * err[k]:.2g} %" for k in QUANTITIES if k in err)
        verdict = "within" if err["estimate"] <= err["tolerance"] else "EXCEEDS"
        lines.append(
            f"estimated error {100 * err['estimate']:.2g} % ({verdict} tolerance "
            f"{100 * err['tolerance']:.2g} %; {q}) against sizes {err.get('reference_sizes')}"
            f", {err['seconds']:.1f} s"
        )
        if err.get("tried") and r["method"] == "auto":
            lines.append(
                "tried "
                + ", ".join(f"{t['sizes']}: {100 * t['estimate']:.2g} %" for t in err["tried"])
            )
    if r.get("note"):
        lines.append(r["note"])
    return lines


def _model_rows(report: dict) -> list[tuple[str, str]]:
    """The model's size, material notes, thermal choice and what was dropped."""
    full, model = report["full"], report["model"]
    line = _dofs(model)
    if model["n_dofs"] != full["n_dofs"] or model["n_contacts"] != full["n_contacts"]:
        line += f"; full model {_dofs(full)}"
    if "fe_dofs" in full:
        line += f"; {full['fe_dofs']} FE dofs"
    rows = [("model", line)]
    rows += [("material", note) for note in report.get("material", [])]
    rows.append(("thermal", report["thermal"]))
    rows += [("damping", x) for x in _damping(report.get("damping"))]
    rows += [("dropped", d) for d in report["dropped"]]
    rows += [("prestress", x) for x in _centrifugal(report.get("centrifugal"))]
    return rows


#: modes listed one by one in the damping rows
N_DAMPING_MODES = 6


def _damping(d: dict | None) -> list[str]:
    """The damping each vibration mode of the run's model gets (:mod:`femrub.model.modes`)."""
    if not d:
        return []
    f, z = d["frequency_hz"], d["ratio"]
    if not f:
        return ["no vibration mode"]
    rows = []
    if d.get("rayleigh") and any(d["rayleigh"]):
        a, b = d["rayleigh"]
        rows.append(
            f"Rayleigh C = a M + b K, a = {a:.4g} 1/s, b = {b:.4g} s: each mode its own ratio "
            "ζ(ω) = a / 2ω + b ω / 2"
        )
    first = ", ".join(f"{fi:.5g} Hz {100 * zi:.3g} %" for fi, zi in zip(f, z[:N_DAMPING_MODES]))
    rows.append(f"modes of the run's model (contacts open): {first}")
    if len(f) > N_DAMPING_MODES:
        rows.append(
            f"{len(f)} modes up to {f[-1]:.5g} Hz: ratio {100 * min(z):.3g} % to "
            f"{100 * max(z):.3g} % ({100 * z[-1]:.3g} % at the highest)"
        )
    return rows


def _casing_rows(report: dict) -> list[tuple[str, str]]:
    """The abradable coating and the casing heat model, when there are."""
    rows = []
    a = report.get("abradable")
    if a:
        rows.append(
            (
                "abradable",
                f"coating {_um(a['thickness'])} thick, yields at {a['yield']:g} N per contact; "
                f"wear map {a['n_angle']} angles × {a['n_axial']} axial cells",
            )
        )
    ch = report.get("casing_heat")
    if ch:
        rows.append(
            (
                "casing",
                f"lumped wall {_um(ch['thickness'])} thick (τ = {ch['tau']:.3g} s) takes "
                f"{100 * (1 - ch['partition']):.3g} % of the frictional power; its expansion "
                "closes the gaps",
            )
        )
    return rows


def _rotation_rows(r: dict | None) -> list[tuple[str, str]]:
    """The direction of rotation, where it comes from, and a reversed sliding."""
    if not r:
        return []
    rows = [
        (
            "rotation",
            f"{r['reason']}: casing phase θ = σ Ω t + φ and sliding velocity −σ Ω r, "
            f"σ = {'+1' if r['direction'] == 'counterclockwise' else '-1'}",
        )
    ]
    if r["slip"] == "reversed":
        rows.append(
            (
                "warning",
                "contact.slip_direction = 'reversed': the casing slides against the lobe "
                "phase (a verification device, not a physical set-up)",
            )
        )
    return rows


def _contact_rows(report: dict, reach_key) -> list[tuple[str, str]]:
    """The contacts kept, the friction law and the build's warnings."""
    reach_key = reach_key or report.get("reach_key", "auto")
    rows = [("contacts", x) for x in _contacts(report["contacts"], reach_key)]
    rows += _rotation_rows(report.get("rotation"))
    f = report.get("friction")
    if f and f["mu"] > 0:
        rows.append(
            (
                "friction",
                f"Coulomb μ = {f['mu']:g} (stick/slip, casing frame); heat law "
                f"{f['heat_law']}, heat_partition {f['heat_partition']:g}",
            )
        )
    return rows + [("warning", w) for w in report.get("warnings", [])]


def _scheme_rows(report: dict) -> list[tuple[str, str]]:
    """The scheme and the time-step check."""
    s = report["scheme"]
    opts = ", ".join(f"{k} {v}" for k, v in s.items() if k not in ("name", "h", "t_end", "steps"))
    rows = [
        (
            "scheme",
            f"{s['name']}, h = {s['h']:g} s, t_end = {s['t_end']:g} s: "
            f"{s['steps']} steps" + (f" ({opts})" if opts else ""),
        )
    ]
    ts = report.get("time_step")
    if ts:
        verdict = "within" if ts["estimate"] <= ts["tolerance"] else "EXCEEDS"
        rows.append(
            (
                "time step",
                f"estimated error {100 * ts['estimate']:.2g} % ({verdict} scheme.step_tolerance "
                f"{100 * ts['tolerance']:.2g} %): twice the difference to the run at h/2 "
                f"({ts['decided_by']} {100 * ts['difference']:.2g} %), {ts['seconds']:.1f} s",
            )
        )
    return rows


def _probe_text(probe: dict) -> str:
    """One probe: what it reads, where it was asked, the node read and its distance."""
    what = " ".join(filter(None, (probe["component"], probe["quantity"])))
    asked = f"node {probe['node']}" if "node" in probe else "point (%.6g, %.6g, %.6g) m"
    if "point" in probe:
        asked %= tuple([*probe["point"], 0.0, 0.0][:3])
    at = ", ".join(f"{x:.6g}" for x in probe["position"])
    text = (
        f"probe_{probe['name']}: {what} ({probe['unit']}) at {asked}; "
        f"mesh node at ({at}) m, {probe['distance']:.3g} m away"
    )
    return text + _blade_text(probe)


def _blade_text(probe: dict) -> str:
    """Which blade of a bladed disk a probe reads (its node is the sector's: blade 0's)."""
    blade = probe.get("blade")
    if blade is None:
        return ""
    if blade == "all":
        keys = probe["keys"]
        return f"; read on every blade ({keys[0]} .. {keys[-1]})"
    return f"; read on blade {blade} (the sector's node turned by {blade} sectors)"


def _output_rows(report: dict) -> list[tuple[str, str]]:
    """Signals, stop limits, outputs, natural frequencies and timings."""
    rows = [("signals", ", ".join(report["signals"]) + " (+ gaps, contact forces, energy)")]
    if report["signals_not_observed"]:
        rows.append(("not kept", ", ".join(report["signals_not_observed"]) + " (outputs.signals)"))
    if report["limits"]:
        rows.append(("limits", ", ".join(f"{k} <= {v:g}" for k, v in report["limits"].items())))
    rows += [("ignored", note) for note in report.get("ignored", [])]
    rows += [("probe", _probe_text(p)) for p in report.get("probes", [])]
    rows.append(("outputs", _vtk_text(report["outputs"]["vtk_stride"])))
    if report.get("natural_frequencies_hz"):
        rows.append(
            ("modes", ", ".join(f"{x:.4g}" for x in report["natural_frequencies_hz"]) + " Hz")
        )
    rows.append(("timings", format_timings(report.get("timings", {}))))
    return rows


def explain(report: dict, reach_key=None) -> str:
    """Format a build report (:func:`femrub.app.simulation.build`) as aligned text."""
    if report.get("kind") == "bladed-disk":
        return _aligned(_wheel_rows(report))
    rows = [("scene", f"{report['scene']} ({report['source']})"), ("geometry", report["geometry"])]
    p = report.get("parametric")
    if p:
        rows.append(
            (
                "model",
                f"the model built at {p['from_rotation_speed']:g} rad/s taken at "
                f"{p['rotation_speed']:g} rad/s (its parameter; matrices and contacts shared)",
            )
        )
    rows += _model_rows(report)
    rows += _casing_rows(report)
    rows += _contact_rows(report, reach_key)
    rows += [("reduction", x) for x in _reduction(report["reduction"])]
    rows += _scheme_rows(report)
    rows += _output_rows(report)
    return _aligned(rows)


def _aligned(rows) -> str:
    return "\n".join(f"  {k:<10} {v}" for k, v in rows)


def _wheel_rows(report: dict) -> list:
    """The rows of a bladed disk's build (:mod:`femrub.app.wheel`)."""
    w = report["bladed_disk"]
    err = report["reduction"]["error"]
    step = report.get("time_step", {})
    scheme = report.get("scheme", {})
    return [
        ("scene", f"{report['scene']} ({report['source']})"),
        (
            "wheel",
            f"{w['blades']} blades, {w['contacts_per_blade']} tip contacts each, "
            f"{w['sector_free_dofs']} free dofs per sector; casing: {w['casing']}; "
            f"direction {'counterclockwise' if w['direction'] > 0 else 'clockwise'}",
        ),
        ("blades", _mistuning_text(w.get("mistuning"))),
        (
            "model",
            f"{w['disk_coordinates']} disk and {w['casing_coordinates']} casing coordinates "
            "(per nodal diameter: modes and the tip contacts' residual shapes)",
        ),
        *_casing_rows(report),
        *_blade_heat_rows(report),
        (
            "reduction",
            f"estimated error {100 * err['estimate']:.3g} % against the richer wheel "
            f"{err['reference_sizes']} (tolerance {100 * err['tolerance']:.3g} %)",
        ),
        (
            "time step",
            f"estimated error {100 * step['estimate']:.3g} % "
            f"(tolerance {100 * step['tolerance']:.3g} %)"
            if step
            else "not checked (scheme.step_check = false)",
        ),
        ("scheme", f"{scheme.get('name')} h = {scheme.get('h'):g} s, {scheme.get('steps')} steps"),
        *[("probe", _probe_text(p)) for p in report.get("probes", [])],
        ("outputs", _vtk_text(report.get("outputs", {}).get("vtk_stride", 0))),
        ("timings", format_timings(report.get("timings", {}))),
    ]


def _blade_heat_rows(report: dict) -> list:
    """The blades' temperature, or where their share of the frictional heat goes without
    it."""
    ch, w = report.get("casing_heat"), report["bladed_disk"]
    if w.get("temperature_coordinates"):
        return [
            (
                "temperature",
                f"{w['temperature_coordinates']} coordinates of the blades' temperature (per "
                "nodal diameter: thermal modes and the tip contacts' static heat shapes)",
            )
        ]
    if not ch:
        return []
    share = f"{100 * ch['partition']:.3g} %"
    return [("blade heat", f"the blades' share ({share}) leaves the run: no temperature dofs")]


def _vtk_text(stride: int) -> str:
    return f"VTK every {stride} steps" if stride else "no VTK (outputs.vtk_stride = 0)"


def _mistuning_text(mistuning) -> str:
    """A bladed disk's blades: tuned, or mistuned by ``rotor.mistuning``."""
    if not mistuning:
        return "tuned (identical blades)"
    return (
        f"mistuned: blade s's stiffness times 1 + δ_s, max |δ_s| = "
        f"{100 * mistuning['max_abs']:.3g} % (rotor.mistuning)"
    )
