"""Rotor 37 modes and centrifugal prestress against CalculiX: runs, JSON and validation page.

``python benchmarks/campbell_rotor37.py [linear] [nonlinear]`` runs ``femrub campbell`` on the
CalculiX Rotor 37 mesh of the shared data with the deck's material (E = 210 GPa, ν = 0.3,
ρ = 9000 kg/m³) and a consistent mass (what the deck's frequency step uses), 0-1800 rad/s,
for each prestress method (minutes and about 5 GB each; skipped with a message when the
shared data is absent). It writes each diagram into ``docs/performance/campbell-rotor37-METHOD/``,
the numbers with where they were measured into ``docs/validation/rotor37_calculix.json`` and
renders ``docs/validation/rotor37-calculix.md`` from that JSON.

``--render-only`` renders the page from the JSON; ``--collect`` rebuilds the JSON from the
committed ``campbell.json`` files of the diagrams (stamped with the commit and date that
committed each of them), then renders.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import time
from pathlib import Path

from _common import DOCS, OUT, machine, write_json

DECK = {
    "material.young": 210e9,
    "material.poisson": 0.3,
    "material.density": 9000.0,
    "physics.lumping": "consistent",
}
SPEEDS = "0:1800:10"
METHODS = ("linear", "nonlinear")
DATA = DOCS / "validation" / "rotor37_calculix.json"
PAGE = DOCS / "validation" / "rotor37-calculix.md"
SCRIPT = "benchmarks/campbell_rotor37.py"


def _read(path: Path) -> dict:
    """A JSON document as written (nulls stay ``None``: a missing stamp is not NaN)."""
    return json.loads(path.read_text())


def _diagram_dir(method: str) -> Path:
    return OUT / f"campbell-rotor37-{method}"


def run(methods) -> dict | None:
    """Run the Campbell diagram for ``methods``; ``None`` when the mesh is absent."""
    from femrub.app.campbell import campbell, parse_speeds, write_campbell
    from femrub.geometry.rotor37 import shared_data_dir
    from femrub.scene import load_scene

    if not (shared_data_dir() / "rotor37-fe-mesh").is_dir():
        print(f"skipped: no Rotor 37 mesh under {shared_data_dir()} (set FEMRUB_SHARED_DATA)")
        return None
    data = _read(DATA) if DATA.exists() else _empty()
    for method in methods:
        stamp = machine()
        scene = load_scene("rotor37", {**DECK, "loads.centrifugal": method})
        t0 = time.perf_counter()

        def log(message, t0=t0):
            print(f"{time.perf_counter() - t0:7.1f} s  {message}", flush=True)

        res = campbell(scene, parse_speeds(SPEEDS), modes=6, log=log)
        doc = write_campbell(res, _diagram_dir(method))
        data["runs"][method] = {**doc, "wall_seconds": time.perf_counter() - t0, "machine": stamp}
    return data


def _empty() -> dict:
    """A document without runs; the CalculiX entry (``benchmarks/calculix_rotor37.py``) kept."""
    calculix = _read(DATA).get("calculix") if DATA.exists() else None
    return {"calculix": calculix, "deck": DECK, "speeds": SPEEDS, "runs": {}}


def _git(*args: str) -> str | None:
    try:
        done = subprocess.run(
            ["git", "-C", str(DOCS.parent), *args], capture_output=True, text=True, timeout=10
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() or None


def collect() -> dict:
    """The JSON from the committed ``campbell.json`` of each diagram (no run)."""
    data = _empty()
    for method in METHODS:
        path = _diagram_dir(method) / "campbell.json"
        if not path.exists():
            continue
        rel = path.relative_to(DOCS.parent).as_posix()
        commit, _, date = (
            _git("log", "-1", "--format=%h %ad", "--date=iso", "--", rel) or ""
        ).partition(" ")
        doc = _read(path)
        stamp = {"date": date or None, "commit": commit or None, "collected_from": rel}
        data["runs"][method] = {**doc, "wall_seconds": doc.get("seconds"), "machine": stamp}
    return data


def _stamp(run: dict) -> str:
    m = run.get("machine") or {}
    when = m.get("date") or "date not recorded"
    commit = f"commit {m['commit']}" if m.get("commit") else "commit not recorded"
    if m.get("collected_from"):
        return f"committed {when} in {commit} (`{m['collected_from']}`; machine not recorded)"
    where = (
        f"Python {m.get('python', '?')}, numpy {m.get('numpy', '?')}, {m.get('cores', '?')} "
        f"cores, load average {m.get('load_average', '?')} at its start"
    )
    return f"measured {when}, {commit}; {where}"


def _percent(value: float, reference: float) -> str:
    return f"{100 * (value / reference - 1):+.2f} %"


def _rest_table(data: dict) -> str:
    """Rest frequencies of each run and of today's model against CalculiX's frequency step."""
    ccx = data["calculix"]
    columns = {f"{method} run": run["rest_frequencies_hz"] for method, run in data["runs"].items()}
    columns[f"commit {ccx['machine']['commit']}"] = ccx["femrub_frequencies_hz"]
    n = min(len(ccx["frequencies_hz"]), *(len(f) for f in columns.values()))
    head = "| mode | CalculiX C3D15 (Hz) |"
    rule = "|---|---|"
    for name in columns:
        head += f" femrub, {name} (Hz) | difference |"
        rule += "---|---|"
    rows = [head, rule]
    for k, ref in enumerate(ccx["frequencies_hz"][:n]):
        row = f"| {k + 1} | {ref:.2f} |"
        for freqs in columns.values():
            row += f" {freqs[k]:.2f} | {_percent(freqs[k], ref)} |"
        rows.append(row)
    return "\n".join(rows)


def _calculix_stamp(data: dict) -> str:
    """Where the CalculiX frequencies (and today's femrub ones beside them) were measured."""
    ccx = data.get("calculix")
    if not ccx:
        return "* CalculiX: not run (`python benchmarks/calculix_rotor37.py`)."
    m = ccx["machine"]
    return (
        f"* CalculiX {ccx['ccx_version']} frequency step, and femrub's model at commit "
        f"{m.get('commit') or 'not recorded'}: measured {m['date']} by "
        f"`python benchmarks/calculix_rotor37.py`; {m['platform']}, Python {m['python']}, "
        f"{m['cores']} cores, load average {m['load_average']} at its start."
    )


def _check(run: dict) -> str:
    """The self-check's status, samples and worst bound or check (``campbell.json``)."""
    if run.get("max_error_bound") is not None:
        worst = f"{100 * run['max_error_bound']:.2g} % at {run['error_bound_speed']:.0f} rad/s"
        samples = len(run.get("sample_speeds", []))
        return f"{run['status']} ({samples} modal samples; largest frequency bound {worst})"
    if run.get("check_max_relative_error") is None:
        return run.get("status", "not checked")
    worst = f"{100 * run['check_max_relative_error']:.2g} % at {run['check_speed']:.0f} rad/s"
    if "status" not in run:  # collected from a diagram written before the status existed
        return worst
    return f"{run['status']} ({len(run.get('sample_speeds', []))} samples; worst {worst})"


def _prestress_table(data: dict) -> str:
    rows = [
        "| prestress | tip growth at the top speed, max / mean over the contacts (mm) "
        "| worst tracking MAC | self-check | wall time (s) |",
        "|---|---|---|---|---|",
    ]
    for method, run in data["runs"].items():
        grow_max, grow_mean = run["tip_growth_max_m"][-1], run["tip_growth_mean_m"][-1]
        wall = run.get("wall_seconds")
        rows.append(
            f"| {method} | {grow_max * 1e3:.3f} / {grow_mean * 1e3:.3f} | "
            f"{run['worst_tracking_mac']:.2f} | {_check(run)} | "
            f"{'not recorded' if wall is None else f'{wall:.0f}'} |"
        )
    return "\n".join(rows)


def _growth_ratio(data: dict) -> str:
    runs = data["runs"]
    if not {"linear", "nonlinear"} <= set(runs):
        return ""
    lin, non = runs["linear"], runs["nonlinear"]
    ratio_max = lin["tip_growth_max_m"][-1] / non["tip_growth_max_m"][-1]
    ratio_mean = lin["tip_growth_mean_m"][-1] / non["tip_growth_mean_m"][-1]
    return (
        f"The linear prestress gives {ratio_max:.1f}× the nonlinear tip growth at the "
        f"most exposed contact and {ratio_mean:.1f}× on average."
    )


def render(data: dict) -> str:
    """The validation page from the JSON ``data``."""
    runs = data["runs"]
    top = max((r["speeds_rad_s"][-1] for r in runs.values()), default=float("nan"))
    lines = [
        "# Rotor 37 modes and prestress against CalculiX",
        "Rendered by `python benchmarks/campbell_rotor37.py --render-only` from "
        "`docs/validation/rotor37_calculix.json`; `python benchmarks/campbell_rotor37.py` runs "
        "the diagrams again (needs the Rotor 37 deck of the shared data). The model is the "
        "CalculiX deck's blade (C3D15 wedges split into quadratic tetrahedra, root clamped at "
        "the deck's `*BOUNDARY` nodes) with the deck's material, E = 210 GPa, ν = 0.3, "
        "ρ = 9000 kg/m³, and a consistent mass (HRZ lumping, the default of runs, is not what "
        "the deck's frequency step uses). The command: `femrub campbell rotor37 --speeds "
        f"{data['speeds']} --set material.young=210e9 --set material.poisson=0.3 "
        "--set material.density=9000 --set physics.lumping=consistent --set "
        "loads.centrifugal=METHOD`.",
        "## Where the numbers come from",
        "\n".join(
            [
                _calculix_stamp(data),
                *(f"* {method} run: {_stamp(run)}." for method, run in runs.items()),
            ]
        ),
        "## Natural frequencies at rest",
        "Against the frequency step of the CalculiX C3D15 model of the same deck, run by "
        "`benchmarks/calculix_rotor37.py` (its first twenty modes and the contact "
        "flexibility: [Rotor 37 contact flexibility](rotor37-tip-flexibility.md)). At rest the "
        "prestress method plays no part: a difference between the runs comes from the code "
        "each was measured with.",
        _rest_table(data) if data.get("calculix") else "CalculiX not run.",
        "## Centrifugal prestress",
        f"The blade spun to {top:.0f} rad/s, its stiffness with the stress of the spin "
        "(`loads.centrifugal`: `linear`, exact to first order in Ω², or the geometrically "
        "`nonlinear` static solution). The deck holds no prestressed reference, so this "
        "section compares the methods with each other; each diagram bounds every frequency it "
        "gives by its residual (the self-check column: its largest bound; docs/campbell.md).",
        _prestress_table(data) if runs else "Not run.",
        _growth_ratio(data),
        "The mesh's radius runs from 0.45 to 0.64 m (about 2.5× the real Rotor 37), so the "
        "centrifugal stresses at the top speed are several times a real blade's; the published "
        "rub set-up on this mesh runs at 1344 rad/s. Use the nonlinear prestress (the default) "
        "on this leaned and swept blade: the linear one is for small prestress.",
        "## Diagrams",
        "\n\n".join(
            f"![{method}](../performance/campbell-rotor37-{method}/campbell.png)" for method in runs
        ),
    ]
    return "\n\n".join(line for line in lines if line) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("methods", nargs="*", help=f"prestress methods (default: {' '.join(METHODS)})")
    ap.add_argument("--render-only", action="store_true", help="render the page from the JSON")
    ap.add_argument("--collect", action="store_true", help="the JSON from the committed diagrams")
    args = ap.parse_args(argv)
    unknown = sorted(set(args.methods) - set(METHODS))
    if unknown:
        ap.error(f"unknown prestress method {unknown[0]!r}; use {' or '.join(METHODS)}")
    if args.collect:
        data = collect()
    elif args.render_only:
        data = _read(DATA)
    else:
        data = run(args.methods or METHODS)
        if data is None:
            return
    if not args.render_only:
        write_json(DATA, data)
    PAGE.write_text(render(data))
    print(f"wrote {PAGE}")


if __name__ == "__main__":
    main()
