"""Which way Rotor 37 turns, read off the deck: the numbers behind docs/rotor37.md.

Reads the ``rotor37`` scene's blade (the CalculiX deck of the shared data) and measures what
the section "Direction of rotation" of ``docs/rotor37.md`` argues from: the annulus (root and
tip radius against the axial coordinate ``z``, least-squares slopes), the tip section
unrolled on ``(z, s = e_φ · p)`` (:func:`femrub.geometry.rotation_direction.tip_section`:
its chord, how far its points lie on either side of the chord, the area centroid's offset),
where its leading and trailing edges sit in ``s``, and the direction femrub derives
(:func:`~femrub.geometry.rotation_direction.derive_rotation_direction`). Lengths in mm.

Stores the numbers with where they were measured in ``docs/rotor37/direction.json`` and
renders the bullets between the ``rotor37-direction`` markers of ``docs/rotor37.md``
(``--render-only``: from the JSON, without the deck).

Run: ``python benchmarks/rotor37_direction.py [--render-only]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from _common import cli_scene, machine, read_json, render_sections, stamp, write_json

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "rotor37.md"
JSON = ROOT / "docs" / "rotor37" / "direction.json"
COMMAND = "python benchmarks/rotor37_direction.py"


def _slope(z: np.ndarray, r: np.ndarray) -> float:
    """Least-squares ``dr/dz`` (mm per mm)."""
    return float(np.polyfit(z, r, 1)[0])


def measure(blade) -> dict:
    """The annulus, the tip section and the derived direction of ``blade`` (mm)."""
    from femrub.geometry.rotation_direction import derive_rotation_direction, tip_section

    a = blade.axis
    p = 1e3 * blade.mesh.p
    z = a @ p
    r = np.linalg.norm(p - np.outer(a, z), axis=0)
    tip, root = blade.node_sets["tip"], blade.node_sets["root"]
    first, last = tip[np.argmin(z[tip])], tip[np.argmax(z[tip])]
    sec = tip_section(blade)
    ends = np.array([sec.start, sec.start + sec.chord * sec.tangent]) * 1e3
    leading, trailing = ends[np.argsort(ends[:, 0])]
    return {
        "tip_nodes": int(tip.size),
        "root_slope": _slope(z[root], r[root]),
        "tip_slope": _slope(z[tip], r[tip]),
        "tip_first": [float(r[first]), float(z[first])],
        "tip_last": [float(r[last]), float(z[last])],
        "chord_mm": 1e3 * sec.chord,
        "offsets_mm": [1e3 * float(sec.offsets.max()), 1e3 * float(-sec.offsets.min())],
        "centroid_percent": 100 * abs(sec.centroid_offset) / sec.chord,
        "leading_edge": leading.tolist(),
        "trailing_edge": trailing.tolist(),
        "direction": derive_rotation_direction(blade).direction,
    }


def bullets(m: dict) -> str:
    """The section's three reasons, with the measured numbers."""
    (r0, z0), (r1, z1) = m["tip_first"], m["tip_last"]
    big, small = sorted(m["offsets_mm"], reverse=True)
    le, te = m["leading_edge"], m["trailing_edge"]
    about = "counterclockwise about +z" if m["direction"] == "counterclockwise" else "clockwise"
    return "\n".join(
        [
            "* **The flow goes towards +z.** The annulus of a compressor stage narrows "
            f"downstream, and the deck's does towards +z: the root radius changes by "
            f"{m['root_slope']:+.2f} mm and the tip radius by {m['tip_slope']:+.2f} mm per mm "
            f"of z (the tip runs from r = {r0:.1f} mm at z = {z0:.1f} mm to {r1:.1f} mm at "
            f"z = {z1:.1f} mm; {m['tip_nodes']} tip nodes). The leading edge is at small z.",
            "* **The blade moves towards its pressure side.** Unrolled on the plane "
            f"(z, s = e_φ · p), the tip section lies almost wholly on one side of its "
            f"{m['chord_mm']:.1f} mm chord (up to {big:.1f} mm away on one side, {small:.1f} mm "
            "on the other): that convex side is the suction side, and its area centroid is "
            f"{m['centroid_percent']:.2g} % of the chord off the chord line on it. The concave "
            "pressure side faces the direction of motion, so the blade turns "
            f"{about}. This is the rule `femrub/geometry/rotation_direction.py` applies to "
            "any blade with a cambered tip section.",
            "* **The leading edge leads** (cross-check by the stagger): at the tip the leading "
            f"edge (z = {le[0]:.1f} mm) sits at s = {le[1]:+.1f} mm and the trailing edge "
            f"(z = {te[0]:.1f} mm) at s = {te[1]:+.1f} mm, so the leading edge is ahead in "
            f"{'+' if le[1] > te[1] else '−'}φ, as on a compressor rotor, whose relative inflow "
            "comes from the direction of rotation.",
        ]
    )


def render(doc: dict) -> dict[str, str]:
    """``marker -> text``: the stamp, then the bullets."""
    return {"rotor37-direction": stamp(COMMAND, doc["machine"]) + "\n\n" + bullets(doc["geometry"])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--render-only", action="store_true")
    a = ap.parse_args(argv)
    if not a.render_only:
        scene = cli_scene("rotor37", [])
        if scene is None:
            return 0
        from femrub.app.blade import load_blade

        where = machine()
        write_json(JSON, {"machine": where, "geometry": measure(load_blade(scene))})
    render_sections(PAGE, render(read_json(JSON)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
