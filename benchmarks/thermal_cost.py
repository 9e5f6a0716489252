"""What the coated, heated Rotor 37 rub costs against the mechanical one, in one run.

Each command in its own process, with the model cache off (every build from the deck):

1. ``femrub run rotor37 --no-cache`` (50 revolutions at 1000 steps per revolution, the
   reduction error estimate on);
2. ``femrub run rotor37-thermal --no-cache`` (50 revolutions at 16,000 steps per revolution,
   frictional heat, thermal stresses, the abradable coating, the reduction error estimate and
   the time-step check on).

Records the wall time and peak resident memory of each, their ratio (targets: the thermal
run ≤ 4 times the mechanical one, ≤ 3 GB peak), each run's status and the seconds of its
stages (``summary.json["timings"]``), the error estimates and whether each check needed its
round-off twin, and the coated run's hottest tip, deepest wear and worn volume. Writes
``docs/performance/thermal_cost.json`` and the section between the ``thermal_cost`` markers
of ``docs/performance/rotor37-costs.md`` (``--render-only``: from the JSON, no run). Skips
with a message when the shared data is absent.

Run: ``python benchmarks/thermal_cost.py [--render-only]`` (about 4 minutes on a quiet
2-core machine; run it alone).
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

JSON = C.OUT / "thermal_cost.json"
PAGE = C.ROOT / "docs" / "performance" / "rotor37-costs.md"
SCENES = ("rotor37", "rotor37-thermal")
RATIO_TARGET = 4.0
PEAK_TARGET_MIB = 3e9 / 2**20
#: what each run's ``summary.json`` gives the table
SUMMARY_KEYS = (
    "status",
    "message",
    "steps",
    "revolutions",
    "n_dofs",
    "timings",
    "max_contact_temperature",
    "max_wear_depth",
    "worn_volume",
    "max_incursion",
)


def _checks(summary: dict) -> dict:
    """The error estimates of a run and whether each stepped its round-off twin."""
    out = {}
    for key in ("reduction_error", "time_step_error"):
        err = summary.get(key) or {}
        if "estimate" in err:
            out[key] = {"estimate": err["estimate"], "twin": "sensitivity" in err}
    return out


def measure() -> dict:
    machine, runs = C.machine(), {}  # where and when it starts
    with tempfile.TemporaryDirectory(prefix="femrub-thermal-cost-") as tmp:
        for name in SCENES:
            out = Path(tmp) / name
            row = C.femrub_process("run", name, "--no-cache", "-q", "-o", str(out))
            summary = json.loads((out / "summary.json").read_text())
            row.update({k: summary[k] for k in SUMMARY_KEYS if k in summary})
            row["checks"] = _checks(summary)
            runs[name] = row
    a, b = (runs[s] for s in SCENES)
    return {
        "machine": machine,
        "runs": runs,
        "ratio": b["wall_s"] / a["wall_s"],
        "ratio_target": RATIO_TARGET,
        "peak_target_mib": PEAK_TARGET_MIB,
    }


def _stages(timings: dict) -> str:
    return ", ".join(f"{k} {v:.1f}" for k, v in timings.items())


def _estimates(checks: dict) -> str:
    names = {"reduction_error": "reduction", "time_step_error": "time step"}
    parts = [
        f"{names[k]} {100 * v['estimate']:.2g} %{' (twin)' if v['twin'] else ''}"
        for k, v in checks.items()
    ]
    return ", ".join(parts) or "—"


def render(doc: dict) -> str:
    """The page's section: both runs, their ratio and the coated run's measures."""
    lines = [
        C.stamp("python benchmarks/thermal_cost.py", doc["machine"]),
        "",
        "| command | status | steps | wall (s) | peak (MiB) | stages (s) | error estimates |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in doc["runs"].values():
        lines.append(
            f"| `{r['command'].split(' -q')[0]}` | {r.get('status', '?')} | {r.get('steps', 0)} | "
            f"{r['wall_s']:.1f} | {r['peak_mib']:.0f} | {_stages(r.get('timings', {}))} | "
            f"{_estimates(r['checks'])} |"
        )
    thermal = doc["runs"][SCENES[1]]
    ratio_ok = doc["ratio"] <= doc["ratio_target"]
    peak_ok = thermal["peak_mib"] <= doc["peak_target_mib"]
    lines += [
        "",
        f"`{SCENES[1]}` took {doc['ratio']:.2f} times `{SCENES[0]}` (target ≤ "
        f"{doc['ratio_target']:g}: {'met' if ratio_ok else 'not met'}) and peaked at "
        f"{thermal['peak_mib'] / 1024:.2f} GiB (target ≤ 3 GB: {'met' if peak_ok else 'not met'}).",
    ]
    measures = [
        (key, label, scale)
        for key, label, scale in (
            ("max_contact_temperature", "hottest contact (K above ambient)", 1.0),
            ("max_wear_depth", "deepest wear (mm)", 1e3),
            ("worn_volume", "worn volume (mm³)", 1e9),
        )
        if thermal.get(key) is not None
    ]
    if measures:
        lines.append(
            "Its "
            + ", ".join(f"{label} {scale * thermal[key]:.4g}" for key, label, scale in measures)
            + "."
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    return C.rotor37_study(
        argv, __doc__.splitlines()[0], JSON, PAGE, "thermal_cost", measure, render
    )


if __name__ == "__main__":
    raise SystemExit(main())
