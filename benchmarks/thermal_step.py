"""The coated, heated Rotor 37 rub at its step and at half of it: what the step changes.

Runs ``femrub run rotor37-thermal`` at the scene's step (16,000 per revolution) and at half of
it (32,000), each in its own process with the model cache on (the second build loads the
first's model), and tables what a user reads of a coated rub, the hottest contact, the
deepest wear, the worn volume, the deepest incursion, with each run's time-step error
estimate: the change from one step to the other against the estimate. Writes
``docs/performance/thermal_step.json`` and the section between the ``thermal_step``
markers of ``docs/abradable.md`` (``--render-only``: from the JSON, no run). Skips with a
message when the shared data is absent.

Run: ``python benchmarks/thermal_step.py [--render-only]`` (about 7 minutes on a quiet
2-core machine).
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

JSON = C.OUT / "thermal_step.json"
PAGE = C.ROOT / "docs" / "abradable.md"
SCENE = "rotor37-thermal"
#: (key of summary.json, label, scale to the unit of the label)
MEASURES = (
    ("max_contact_temperature", "hottest contact (K)", 1.0),
    ("max_wear_depth", "deepest wear (mm)", 1e3),
    ("worn_volume", "worn volume (mm³)", 1e9),
    ("max_incursion", "deepest incursion (mm)", 1e3),
)


def measure() -> dict:
    from femrub.scene import load_scene

    machine, scene = C.machine(), load_scene(SCENE)
    h, stride = scene["scheme"]["h"], scene["outputs"]["vtk_stride"]
    runs = []
    with tempfile.TemporaryDirectory(prefix="femrub-thermal-step-") as tmp:
        for factor in (1, 2):
            out = Path(tmp) / f"h{factor}"
            sets = [f"scheme.h={h / factor!r}", f"outputs.vtk_stride={stride * factor}"]
            args = [a for s in sets for a in ("--set", s)]
            row = C.femrub_process("run", SCENE, *args, "-q", "-o", str(out))
            summary = json.loads((out / "summary.json").read_text())
            row.update({k: summary.get(k) for k, _, _ in MEASURES})
            row.update(status=summary["status"], steps=summary["steps"], h=h / factor)
            row["time_step_error"] = summary["time_step_error"]["estimate"]
            runs.append(row)
    return {"machine": machine, "scene": SCENE, "runs": runs}


def render(doc: dict) -> str:
    a, b = doc["runs"]
    lines = [
        C.stamp("python benchmarks/thermal_step.py", doc["machine"]),
        "",
        "| | " + " | ".join(label for _, label, _ in MEASURES) + " | time-step estimate | "
        "status | wall (s) |",
        "|---" * (len(MEASURES) + 4) + "|",
    ]
    for r in (a, b):
        values = " | ".join(f"{scale * r[k]:.5g}" for k, _, scale in MEASURES)
        lines.append(
            f"| h = {r['h']:.5g} s ({r['steps']} steps) | {values} | "
            f"{100 * r['time_step_error']:.2g} % | {r['status']} | {r['wall_s']:.0f} |"
        )
    change = " | ".join(
        f"{100 * (a[k] - b[k]) / abs(b[k]):+.2g} %" if b[k] else "—" for k, _, _ in MEASURES
    )
    lines.append(f"| change from h/2 to h | {change} | | | |")
    return "\n".join(lines)


def main(argv=None) -> int:
    return C.rotor37_study(
        argv, __doc__.splitlines()[0], JSON, PAGE, "thermal_step", measure, render
    )


if __name__ == "__main__":
    raise SystemExit(main())
