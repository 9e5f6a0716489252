"""The Rotor 37 Campbell diagram against a cold run, and against exact solves it never saw.

In one run of this script, each command in its own process:

1. ``femrub run rotor37 --no-cache`` (a cold run: the model built from the deck);
2. ``femrub campbell rotor37 --speeds 0:1800:50`` (37 speeds, nonlinear prestress);
3. ``femrub campbell rotor37 --exact`` at held-out speeds of that list that are not among the
   diagram's modal samples: the full prestress and eigen-solve there.

It records the wall time and peak memory of each, the ratio of (2) to (1) (target ≤ 2), and
at the held-out speeds the largest relative difference of the diagram's frequencies from
the exact ones (target ≤ 0.5 %) against the diagram's own bound there. Writes
``docs/performance/campbell_speed.json`` and the section between the ``campbell_speed``
markers of ``docs/performance/prestress-campbell-costs.md`` (``--render-only``: from the
JSON, no run). Skips with a message when the shared data is absent.

Run: ``python benchmarks/campbell_speed.py [--render-only]``.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

JSON = C.OUT / "campbell_speed.json"
PAGE = C.ROOT / "docs" / "performance" / "prestress-campbell-costs.md"
SPEEDS = "0:1800:50"
#: held-out speeds (rad/s), in the list, away from the default samples (0 and 1800)
HELD_OUT = (350.0, 1050.0, 1550.0)
RATIO_TARGET = 2.0
ERROR_TARGET = 0.005


def measure() -> dict:
    machine = C.machine()  # where and when it starts
    with tempfile.TemporaryDirectory(prefix="femrub-campbell-") as tmp:
        tmp = Path(tmp)
        run = C.femrub_process("run", "rotor37", "--no-cache", "-q", "-o", str(tmp / "run"))
        diagram = C.femrub_process(
            "campbell", "rotor37", "--speeds", SPEEDS, "-q", "-o", str(tmp / "cb")
        )
        doc = json.loads((tmp / "cb" / "campbell.json").read_text())
        table = np.loadtxt(tmp / "cb" / "campbell.csv", delimiter=",", skiprows=1, ndmin=2)
        held = [w for w in HELD_OUT if w not in doc["sample_speeds"]]
        listed = ",".join(f"{w:g}" for w in held)
        exact = C.femrub_process(
            "campbell", "rotor37", "--speeds", listed, "--exact", "-q", "-o", str(tmp / "ex")
        )
        ex = np.loadtxt(tmp / "ex" / "campbell.csv", delimiter=",", skiprows=1, ndmin=2)
    rows = []
    for k, w in enumerate(held):
        i = int(np.flatnonzero(np.isclose(table[:, 0], w))[0])
        f, f_exact = np.sort(table[i, 2:]), np.sort(ex[k, 2:])
        rows.append(
            {
                "speed_rad_s": w,
                "max_relative_error": float(np.max(np.abs(f - f_exact) / f_exact)),
                "bound": float(doc["error_bounds"][i]),
                "exact_hz": f_exact.tolist(),
            }
        )
    return {
        "machine": machine,
        "run": run,
        "campbell": {**diagram, **{k: doc[k] for k in _KEYS if k in doc}},
        "exact": exact,
        "held_out": rows,
        "ratio": diagram["wall_s"] / run["wall_s"],
        "ratio_target": RATIO_TARGET,
        "error_target": ERROR_TARGET,
    }


_KEYS = (
    "status",
    "message",
    "n_speeds",
    "sample_speeds",
    "basis_size",
    "prestress_basis_size",
    "prestress_residual_max",
    "max_error_bound",
    "seconds",
)


def render(doc: dict) -> str:
    """The page's section: the three commands, the ratio and the held-out comparison."""
    cb, run, ex = doc["campbell"], doc["run"], doc["exact"]
    lines = [
        C.stamp("python benchmarks/campbell_speed.py", doc["machine"]),
        "",
        "| command | wall (s) | peak memory (MiB) | exit |",
        "|---|---|---|---|",
    ]
    for r in (run, cb, ex):
        lines.append(
            f"| `{r['command'].split(' -q')[0]}` | {r['wall_s']:.1f} | "
            f"{r['peak_mib']:.0f} | {r['exit']} |"
        )
    ok_ratio = doc["ratio"] <= doc["ratio_target"]
    worst = max(r["max_relative_error"] for r in doc["held_out"])
    lines += [
        "",
        f"The diagram ({cb['n_speeds']} speeds, status `{cb['status']}`: {cb['message']}) took "
        f"{doc['ratio']:.2f} times the cold run (target ≤ {doc['ratio_target']:g}: "
        f"{'met' if ok_ratio else 'not met'}). Prestress basis {cb['prestress_basis_size']} "
        f"vectors (largest certified residual {cb['prestress_residual_max']:.1e}), Ritz basis "
        f"{cb['basis_size']} vectors from the full modes at "
        f"{', '.join(f'{w:g}' for w in cb['sample_speeds'])} rad/s.",
        "",
        "At speeds of the list that are not modal samples, the full prestress and eigen-solve "
        "(`--exact`) against the diagram:",
        "",
        "| speed (rad/s) | largest relative difference | the diagram's bound |",
        "|---|---|---|",
    ]
    for r in doc["held_out"]:
        lines.append(
            f"| {r['speed_rad_s']:g} | {C.fmt(r['max_relative_error'])} | {C.fmt(r['bound'])} |"
        )
    lines += [
        "",
        f"Largest difference {C.fmt(worst)} (target ≤ {doc['error_target']:g}: "
        f"{'met' if worst <= doc['error_target'] else 'not met'}).",
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    return C.rotor37_study(
        argv, __doc__.splitlines()[0], JSON, PAGE, "campbell_speed", measure, render
    )


if __name__ == "__main__":
    raise SystemExit(main())
