"""The set-up table of ``docs/rotor37.md``, read from the two built-in Rotor 37 scenes.

Every value in the table is the scene's own (``femrub.scene.load_scene``, SI units, the
defaults filled in), so the page cannot drift from the scenes; a value the two scenes share
is written once ("same"). The deck is not needed.

Run: ``python benchmarks/rotor37_setup.py`` renders the table between the ``rotor37-setup``
markers of ``docs/rotor37.md``.
"""

from __future__ import annotations

import math
from pathlib import Path

from _common import render_sections

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "rotor37.md"
SCENES = ("rotor37", "rotor37-thermal")
MARKER = "rotor37-setup"


def _mesh(s) -> str:
    g = s["geometry"]
    return (
        f"CalculiX deck `{Path(g['path']).name}` ({g['length_unit']}, axis {g['axis']}; C3D15 "
        "wedges split into tetrahedra, vector P2 displacement), root clamped at the deck's "
        "`*BOUNDARY` nodes"
    )


def _material(s) -> str:
    m = s["material"]
    text = f"E = {m['young'] / 1e9:g} GPa, ν = {m['poisson']:g}, ρ = {m['density']:g} kg/m³"
    if s["physics"]["thermal"] == "on":
        text += (
            f"; c = {m['specific_heat']:g} J/(kg K), k = {m['conductivity']:g} W/(m K), "
            f"α = {m['expansion']:g} 1/K"
        )
    return text


def _damping(s) -> str:
    p = s["physics"]
    i, j = p["damping_modes"]
    return (
        f"Rayleigh `C = a M + b K`, ratio {100 * p['damping_ratio']:g} % at clamped modes {i} "
        f"and {j}; every other mode its own ratio `a / 2ω + b ω / 2` (`--explain` lists them)"
    )


def _casing(s) -> str:
    c = s["contact"]
    k = c["casing"]
    text = (
        f"rigid, {k['kind']}, mean gap g_m = {1e3 * k['mean_gap']:g} mm, lobe width "
        f"{k['width']:g}; clearance `{c['gap_reference']}`"
    )
    a = c.get("abradable")
    if a and a["thickness"] > 0:
        text += (
            f"; abradable coating {1e3 * a['thickness']:g} mm thick, yield {a['yield']:g} N per "
            f"contact, wear map {a['n_angle']} × {a['n_axial']} cells, footprint "
            f"{1e3 * a['footprint']:g} mm"
        )
    return text


def _contacts(s) -> str:
    c = s["contact"]
    nodes = " ".join(map(str, c["nodes"]))
    text = f'deck nodes {nodes} (`spread = "{c["spread"]}"`'
    if c["spread"] == "node":  # point contacts: their stiffness against the deck's element
        text += (
            "; point contacts, stiffer at these nodes than the deck's own C3D15 element: "
            "[contact flexibility against CalculiX](validation/rotor37-tip-flexibility.md)"
        )
    return text + ")"


def _law(s) -> str:
    c = s["contact"]
    return (
        f"Signorini + Newton (e = {c['restitution']:g}) + Coulomb μ = {c['friction']:g}, "
        f"set-valued; sliding `{c['slip_direction']}`"
    )


def _speed(s) -> str:
    lo = s["loads"]
    return (
        f"Ω = {lo['rotation_speed']:g} rad/s, direction `{lo['rotation_direction']}`, "
        f"centrifugal prestress `{lo['centrifugal']}`"
    )


def _time(s) -> str:
    sc, omega = s["scheme"], s["loads"]["rotation_speed"]
    revolution = 2 * math.pi / omega
    text = (
        f"θ-method γ = {sc['gamma']:g}, h = {sc['h']:.6g} s ({revolution / sc['h']:.0f} steps "
        f"per revolution), {sc['t_end'] / revolution:.3g} revolutions "
        f"({sc['t_end'] / sc['h']:.0f} steps)"
    )
    if s["physics"]["thermal"] == "on":
        text += f", γ_θ = {sc['gamma_thermal']:g} on the heat rows"
    return text + ("; time-step check at h/2" if sc["step_check"] else "")


def _heat(s) -> str:
    if s["physics"]["thermal"] != "on":
        return "none (mechanical)"
    c = s["contact"]
    return (
        f"`{c['heat_law']}`: {c['heat_partition']:g} of the friction power into the blade, "
        "the rest reported as `heat_to_casing`; thermal stresses on"
    )


def _model(s) -> str:
    r = s["reduction"]
    text = f"Craig–Bampton, projection `{r['projection']}`, n_uv = {r['n_uv']}"
    if s["physics"]["thermal"] == "on":
        text += f", n_θ = {r['n_theta']}, thermal basis `{r['thermal']}`"
    return text + f"; estimate tolerance {100 * r['tolerance']:g} %"


def _stop(s) -> str:
    limits = {k: v for k, v in s.get("limits", {}).items() if v is not None}
    unit = {"tip_temperature": " K rise"}
    items = (f"{k.replace('_', ' ')} {v:g}{unit.get(k, '')}" for k, v in limits.items())
    return ", ".join(items) or "—"


ROWS = (
    ("mesh", _mesh),
    ("material", _material),
    ("damping", _damping),
    ("casing", _casing),
    ("contacts", _contacts),
    ("contact law", _law),
    ("speed", _speed),
    ("time", _time),
    ("heat", _heat),
    ("model", _model),
    ("stop", _stop),
)


def table(scenes=None) -> str:
    """The set-up table of the scenes ``SCENES`` (``scenes``: loaded ones, for tests)."""
    if scenes is None:
        from femrub.scene import load_scene

        scenes = [load_scene(name) for name in SCENES]
    lines = ["| | " + " | ".join(f"`{s['name']}`" for s in scenes) + " |", "|---|---|---|"]
    for label, value in ROWS:
        first, *others = (value(s) for s in scenes)
        cells = [first] + ["same" if v == first else v for v in others]
        lines.append(f"| {label} | " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines)


def main() -> int:
    render_sections(PAGE, {MARKER: table()})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
