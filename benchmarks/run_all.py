"""Run every speed/accuracy benchmark and regenerate the performance pages of the docs.

``python benchmarks/run_all.py`` runs ``work_precision.py``, ``siconos_compare.py``,
``hard_cases.py``, ``cost_3d.py`` and ``exponential.py`` (each in a fresh process, so timings
and peak memory do not mix), writes their tables, JSON and plots into ``docs/performance/``
and renders from the JSON files the overview ``docs/performance.md`` and one page per study
(``PAGES``, in ``docs/performance/``; about 20 min on the 2-core reference machine).
``--quick`` is a fast pass (about 2 min) that writes into ``build/performance-quick/``
unless ``--out`` is given, so the measured documentation is never overwritten by quick
numbers. ``--render-only`` rebuilds the Markdown from existing JSON; ``--skip NAME`` leaves
one study out.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

try:
    from . import _common as C
    from .performance_notes import COST_3D_NOTES, HARD_NOTES, MEASURES
except ImportError:  # run as a script
    import _common as C
    from performance_notes import COST_3D_NOTES, HARD_NOTES, MEASURES

STUDIES = ("work_precision", "siconos_compare", "hard_cases", "cost_3d", "exponential")
JSON = {
    "work_precision": "work_precision",
    "siconos_compare": "siconos",
    "hard_cases": "hard_cases",
    "cost_3d": "cost_3d",
    "exponential": "exponential",
}


def _load(out: Path, study: str):
    path = out / f"{JSON[study]}.json"
    return json.loads(path.read_text()) if path.exists() else None


def _pick(rows, **match):
    return [r for r in rows if all(r.get(k) == v for k, v in match.items())]


def _span(values, digits: int = 2) -> str:
    """``"a–b"`` of the finite ``values`` (``"—"`` without any)."""
    v = [float(x) for x in values if isinstance(x, (int, float)) and math.isfinite(x)]
    return f"{min(v):.{digits}g}–{max(v):.{digits}g}" if v else "—"


def _wp_numbers(rows, orders) -> dict:
    """The numbers the reading of the work–precision tables quotes, from its rows."""
    per_step = lambda rs: [1e6 * r["cpu"] / r["steps"] for r in rs if r["steps"]]  # noqa: E731
    theta, carpenter = (
        _pick(rows, case="paper", method="θ paper"),
        _pick(rows, case="paper", method="Carpenter"),
    )
    full = [o for o in orders if not o["method"].startswith(("RM", "CB"))]
    numeric = lambda case: [  # noqa: E731
        o["u_L2"] for o in full if o["case"] == case and isinstance(o["u_L2"], float)
    ]
    return {
        "penalty_cpu": _span(
            r["cpu"] for r in _pick(rows, case="paper-short", method="penalty BDF")
        ),
        "theta_short_cpu": _span(
            r["cpu"] for r in _pick(rows, case="paper-short", method="θ paper")
        ),
        "carpenter_h": C.fmt(max((r["h"] for r in carpenter), default=None)),
        "theta_h": C.fmt(max((r["h"] for r in theta), default=None)),
        "theta_us": C.fmt(float(np.median(per_step(theta))) if theta else None),
        "carpenter_us": C.fmt(float(np.median(per_step(carpenter))) if carpenter else None),
        "order_paper": _span(numeric("paper")),
        "order_impact": _span(numeric("impact")),
    }


def _wp_section(wp) -> str:
    if wp is None:
        return "Not run (`benchmarks/work_precision.py`)."
    chk, cfg = wp["check"], wp["settings"]
    wcols = [("case", "case"), ("measure", "error"), ("level", "≤"), ("winner", "cheapest")]
    wcols += [("h", "h (s)"), ("k", "k_p (N/m)"), ("cpu", "CPU (s)")]
    wcols += [("runner_up", "next method"), ("runner_up_cpu", "its CPU (s)")]
    ocols = [("case", "case"), ("method", "method"), ("u_L2", "u L2"), ("T_end", "T end")]
    ocols += [("P_phase", "P phase")]
    rows = wp["rows"]
    roms = [r for r in rows if r.get("offline") is not None and r["case"] == "paper"]
    best_rom = min((r["u_L2"] for r in roms), default=float("nan"))
    pen = _pick(rows, case="paper-short", method="penalty BDF")
    th = _pick(rows, case="paper-short", method="θ paper")
    said = _wp_numbers(rows, wp["orders"])
    lines = [
        f"Cases. **paper**: the paper's coupled bar (α = 3 m/s, 60 dofs) over {cfg['t_paper']} s "
        f"(four contact phases); reference: θ-method (paper rule) at h_ref = {cfg['h_ref']:g} s "
        f"({C.fmt(chk['cpu_ref'])} s CPU). Convergence check of the reference: the run at "
        f"2 h_ref differs from it by u L2 {C.fmt(chk['u_L2'])}, T end {C.fmt(chk['T_end'])}, "
        f"P phase {C.fmt(chk['P_phase'])}, t1 {C.fmt(chk['t1'])} s, so errors down to about "
        f"3 × these are meaningful (smaller ones are left out of the orders and the winners). "
        f"**paper-short**: the same over the first {cfg['t_short']} s, where the penalty "
        f"baseline (BDF, restarts at contact switches, output every {cfg['penalty_h']:g} s) can "
        f"be afforded (it takes {said['penalty_cpu']} s per run there, against "
        f"{said['theta_short_cpu']} s for the θ-method). "
        "**impact**: free bar hitting a rigid obstacle (`femrub.cases.analytic.bar_impact`), "
        "errors against the *exact* solution of the continuous bar; mesh and step are refined "
        "together at a fixed Courant number ν = c h / Δx (25 to 800 elements), so the error "
        "contains the spatial error and tends to zero.",
        "![error vs CPU time](performance/work_precision.png)\n\n"
        "![error vs h](performance/order.png)",
        "### Which method wins at which accuracy\n\nCheapest measured run reaching each level "
        "(CPU times carry about ±20 % noise on this shared machine: a runner-up within that "
        "margin is a tie).\n\n" + C.md_table(wp["winners"], wcols),
        "Reading the table:\n\n"
        "* **Coarse accuracy**: only the implicit θ-method takes steps above Carpenter's "
        f"stability limit (its largest stable step here is {said['carpenter_h']} s, the "
        f"θ-method's largest {said['theta_h']} s); it wins where coarse steps suffice.\n"
        "* **Per step** on the paper case with the energy balance on: θ-method (paper rule) "
        f"{said['theta_us']} µs, Carpenter {said['carpenter_us']} µs (medians over the "
        "steps listed).\n"
        "* **Impact (wave propagation)**: at the finest accuracy reached, Carpenter close to "
        "its Courant limit (ν = 0.9) is the cheapest, as expected of central differences on a "
        "1D wave; the θ-method (γ = 1/2) is dispersive at the same ν.\n"
        f"* **Reduced models** (RM1, RM2, CB(4,12), CB(8,19)) stop improving at a u L2 error "
        f"of {C.fmt(best_rom)} and above whatever h: their error is the reduction error "
        "(docs/reduction.md), and on a 60-dof bar they save no time (the step cost is "
        "Python overhead). They are worth it on large 3D models.\n"
        f"* **Penalty**: {C.fmt(pen[-1]['cpu'] if pen else None)} s CPU for u L2 "
        f"{C.fmt(pen[-1]['u_L2'] if pen else None)} at the stiffest k_p, where the θ-method "
        f"takes {C.fmt(th[-1]['cpu'] if th else None)} s for "
        f"{C.fmt(th[-1]['u_L2'] if th else None)}: never competitive, and its error is "
        "bounded below by the regularisation (k_p).",
        "### Observed orders\n\nSlope of log error against log h over the four finest "
        "steps above the reference floor. `plateau`: the error does not decrease over these "
        "steps: the reduction error for the reduced models; for Carpenter's T end and "
        "P phase, errors that are not monotone in h (cancellation) and reach the reference "
        "floor at 2e-6 s, so no order is given.\n\n" + C.md_table(wp["orders"], ocols),
        f"The observed orders of the full models in u L2 are {said['order_paper']} on the "
        "paper case, below the trapezoidal rule's 2 as expected for impacts (the velocity "
        "jumps at each contact switch), and "
        f"{said['order_impact']} on the impact case (in h, with Δx ∝ h).",
        "Every run: [performance/work_precision.md](performance/work_precision.md) "
        "(data: `performance/work_precision.json`).",
    ]
    return "\n\n".join(lines)


def _siconos_section(sc) -> str:
    if sc is None:
        return "Not run (`benchmarks/siconos_compare.py`)."
    rcols = [("N", "nodes"), ("variant", "femrub variant"), ("femrub_us", "femrub µs/step")]
    rcols += [("siconos_us", "best Siconos µs/step"), ("ratio", "Siconos / femrub")]
    rcols += [("us_per_knnz", "femrub µs / 1000 nnz(D)")]
    parts = []
    if sc["siconos_missing"]:
        parts.append(f"**Siconos was skipped:** {sc['siconos_missing']}.")
    parts.append(
        "Problem: free bar of N nodes hitting a rigid obstacle, same h and step count in both "
        "codes; Siconos 4.4 `MoreauJeanOSI(θ = 1/2)` + `LCP` (dense and sparse storage, the "
        'faster counts), femrub `ThetaMethod(activation="predicted")` (the same scheme: '
        "final tip displacements agree to 1e-9 relative or better, column *tip vs femrub* "
        "of the full table). Per step = CPU of the stepping loop / steps, best of several "
        "repetitions, setup excluded.\n\n" + C.md_table(sc["ratios"], rcols)
    )
    parts.append("![cost per step](performance/siconos.png)")
    parts.append(
        "Full table: [performance/siconos.md](performance/siconos.md). Variants: *femrub* "
        "(`run(energy=False)`) and *femrub, energy on* (the default `run()`, which also "
        "keeps the energy balance)."
    )
    parts.append(_targets(sc))
    if sc.get("costs"):
        p, w = sc["costs"]["paper_case"], sc["costs"]["femrub_paper"]
        parts.append(
            "### Paper case and `femrub paper`\n\n"
            f"* Paper case, θ-method h = 1e-4 s over 0.4 s ({p['steps']} steps, energy "
            f"balance on), fresh process: **{p['run_wall']:.2f} s** wall for the run "
            f"({p['cpu']:.2f} s CPU), {p['total_wall']:.2f} s including imports and "
            f"assembly; peak resident memory **{p['peak_rss_mib']:.0f} MiB**.\n"
            f"* `femrub paper` (all figures, {w['runs']} rows): **{w['wall']:.1f} s** wall, "
            f"{w['cpu']:.1f} s CPU, peak resident memory **{w['peak_rss_mib']:.0f} MiB**."
        )
    return "\n\n".join(parts)


def _us(sc, N, variant):
    r = _pick(sc["ratios"], N=N, variant=variant)
    return r[0] if r else {}


def _growth(sc, variant, a=1000, b=10000):
    """Exponent p of per-step cost ∝ nnz^p between sizes ``a`` and ``b``."""
    ra = _pick(sc["rows"], N=a, code="femrub", variant=variant)
    rb = _pick(sc["rows"], N=b, code="femrub", variant=variant)
    if not (ra and rb):
        return float("nan")
    return math.log(rb[0]["per_step"] / ra[0]["per_step"]) / math.log(
        rb[0]["nnz_D"] / ra[0]["nnz_D"]
    )


def _targets(sc) -> str:
    s20, e20 = _us(sc, 20, "femrub"), _us(sc, 20, "femrub, energy on")
    s1k, e1k = _us(sc, 1000, "femrub"), _us(sc, 1000, "femrub, energy on")
    s10k = _us(sc, 10000, "femrub")

    def ok(x, target):
        if x is None or not math.isfinite(x):
            return "—"
        return "**met**" if x >= target else "**missed**"

    g = _growth(sc, "femrub")
    f = C.fmt
    return "\n\n".join(
        [
            "### Targets\n\n"
            f"1. *No slower than Siconos at 20 dofs*: {ok(s20.get('ratio'), 1)} "
            f"(Siconos / femrub = {f(s20.get('ratio'))}: {f(s20.get('femrub_us'))} against "
            f"{f(s20.get('siconos_us'))} µs per step; {f(e20.get('ratio'))} with the energy "
            "balance on).\n"
            f"2. *At least 10× faster at 1000 dofs*: {ok(s1k.get('ratio'), 10)} "
            f"({f(s1k.get('ratio'))}×, {f(e1k.get('ratio'))}× with the energy balance; "
            f"10,000 dofs: {f(s10k.get('ratio'))}×).\n"
            f"3. *Per-step cost linear in the nonzeros*: from 1000 to 10,000 nodes the cost "
            f"grows as nnz^{f(g)} ({f(s1k.get('femrub_us'))} → {f(s10k.get('femrub_us'))} "
            f"µs), {ok(1.25 - g, 0)}. Siconos grows as n² (dense or sparse storage: its step "
            "is not sparse-aware in this configuration), hence the widening gap.\n\n"
            f"The energy balance costs {f(e1k.get('femrub_us'))} against "
            f"{f(s1k.get('femrub_us'))} µs per step at 1000 nodes (its quadratic forms on each "
            "chunk of steps).",
        ]
    )


def _hard_section(hc) -> str:
    if hc is None:
        return "Not run (`benchmarks/hard_cases.py`)."
    cols = [("case", "case"), ("scheme", "scheme"), ("h", "h (s)"), ("status", "status")]
    cols += [("key", "key numbers (SI)"), ("cpu", "CPU (s)")]
    coarse = [r for r in hc["rows"] if "ratio_T" in r]
    table = []
    for rule in ("paper", "predicted"):
        for h in (5e-4, 1e-3, 5e-3):
            for g in (0.5, 0.6, 0.75, 1.0):
                c = _pick(coarse, rule=rule, h=h, gamma=g, coupled=True)
                u = _pick(coarse, rule=rule, h=h, gamma=g, coupled=False)
                if c and u:
                    table.append(
                        {
                            "rule": rule,
                            "h": h,
                            "gamma": g,
                            "inv_W": c[0]["inv_W"],
                            "c": c[0]["ratio_T"],
                            "cs": c[0]["status"],
                            "u": u[0]["ratio_T"],
                            "open": u[0].get("open_share"),
                            "act": u[0].get("active"),
                        }
                    )
    tcols = [("rule", "activation"), ("h", "h (s)"), ("gamma", "γ"), ("inv_W", "1/W (kg)")]
    tcols += [("u", "uncoupled T/T_fine"), ("act", "uncoupled active steps")]
    tcols += [("open", "uncoupled impulse at open gap"), ("c", "coupled T/T_fine")]
    tcols += [("cs", "coupled status")]
    return "\n\n".join([C.md_table(hc["rows"], cols), HARD_NOTES, C.md_table(table, tcols)])


def _read(path: Path, script: str) -> str:
    """A study's Markdown section, or a note that it was not run."""
    return path.read_text().strip() if path.exists() else f"Not run (`{script}`)."


#: the pages rendered into the data folder: file name -> title
PAGES = {
    "speed-and-accuracy.md": "Speed against accuracy on the paper's bar",
    "against-siconos.md": "Speed against Siconos",
    "hard-case-stability.md": "Stability on hard cases",
    "cost-against-size.md": "3D: assembly, reduction and per-step cost against size",
    "exponential-stepper.md": 'Exponential Moreau stepper (`scheme.name = "exponential"`)',
}
#: pages of the section written by other benchmarks (listed in the overview, not rendered)
OTHER_PAGES = {
    "blade-scale.md": "Blade scale: sparse solvers, model cache, progress",
    "rotor37-costs.md": "Rotor 37: mesh to reduced model, the frictional step, output",
    "speed-map-costs.md": "A 40-speed interaction map: where a sweep point's time goes",
    "prestress-campbell-costs.md": "Centrifugal prestress and Campbell diagrams",
    "periodic-rotor37.md": "Periodic orbits of reduced Rotor 37: cost and time runs",
    "bladed-disk.md": "The built-in bladed disk: cost and its sweep against the coincidence",
}

#: the full tables the studies write (linked from the overview)
TABLES = {
    "work_precision.md": "Work–precision: every run",
    "siconos.md": "femrub and Siconos: every run",
    "hard_cases.md": "Hard cases: every run",
    "exponential.md": "Exponential stepper: every run",
    "solvers.md": "Sparse solvers on Rotor 37",
    "mutation_smoke.md": "Mutation smoke check",
}


def _stamp(study: str, data) -> str:
    """Where a study's numbers come from: its script, date, commit and machine."""
    if data is None:
        return f"Not run (`benchmarks/{study}.py`)."
    m = data.get("machine") or {}
    when = m.get("date") or "date not recorded"
    commit = f"commit {m['commit']}" if m.get("commit") else "commit not recorded"
    where = (
        f"Python {m.get('python', '?')}, numpy {m.get('numpy', '?')}, {m.get('cores', '?')} "
        f"cores, load average {m.get('load_average', '?')} at its start"
    )
    return f"*Measured by `python benchmarks/{study}.py` ({when}, {commit}; {where}).*"


def _demote(text: str) -> str:
    """Headings one level up, for a section that becomes a page of its own."""
    return re.sub(r"^#(#+) ", r"\1 ", text, flags=re.M)


def _page_texts(out: Path) -> dict[str, str]:
    """Markdown of every page of ``PAGES`` from the JSON files in ``out``."""
    wp, sc, hc = (_load(out, s) for s in STUDIES[:3])
    cost = out / "cost_3d.md"
    cost_text = cost.read_text() if cost.exists() else "Not run (`benchmarks/cost_3d.py`)."
    bodies = {
        "speed-and-accuracy.md": [
            _stamp("work_precision", wp),
            "## Error measures\n\n" + MEASURES,
            "## Work–precision\n\n" + _demote(_wp_section(wp)),
        ],
        "against-siconos.md": [_stamp("siconos_compare", sc), _demote(_siconos_section(sc))],
        "hard-case-stability.md": [_stamp("hard_cases", hc), _demote(_hard_section(hc))],
        "cost-against-size.md": [cost_text.strip(), COST_3D_NOTES],
        "exponential-stepper.md": [
            _demote(_read(out / "exponential_section.md", "benchmarks/exponential.py"))
        ],
    }
    return {
        name: "\n\n".join([f"# {PAGES[name]}", *bodies[name]]).replace("performance/", "") + "\n"
        for name in PAGES
    }


def _overview(out: Path, rel: str) -> str:
    """The section's front page: headline numbers from the JSON files, then the pages."""
    sc = _load(out, "siconos_compare")
    lines = [
        "# Performance",
        "How fast femrub is, against what accuracy, measured on a 2-core machine shared with "
        "other jobs (CPU times carry about ±20 % noise; SI units). Every table and number on "
        "these pages is rendered by `python benchmarks/run_all.py --render-only` from the JSON "
        "files the studies write into `docs/performance/`, each page stamped with where its "
        "numbers come from; `python benchmarks/run_all.py` runs the studies again (`--quick` "
        "for a fast pass into `build/`). Speed targets live in the benchmarks, not in the "
        "test suite.",
    ]
    if sc is not None:
        rows = {(r["N"], r["variant"]): r for r in sc["ratios"]}
        heads = ["## Headline numbers", _stamp("siconos_compare", sc), ""]
        for n in (20, 1000):
            r = rows.get((n, "femrub"))
            if r:
                heads.append(
                    f"* Bar of {n} nodes hitting an obstacle: {C.fmt(r['femrub_us'])} µs per "
                    f"θ-method step, {C.fmt(r['ratio'])}× faster than Siconos' Moreau–Jean "
                    f"({C.fmt(r['siconos_us'])} µs)."
                )
        if sc.get("costs"):
            w = sc["costs"]["femrub_paper"]
            heads.append(
                f"* `femrub paper` (all figures, {w['runs']} runs, a warm compile cache): "
                f"{w['wall']:.1f} s wall, {w['cpu']:.1f} s CPU, peak resident memory "
                f"{w['peak_rss_mib']:.0f} MiB."
            )
        lines.append("\n".join(heads))
    prefix = f"{rel}/" if rel != "." else ""
    pages = {**PAGES, **OTHER_PAGES}
    tables = {name: title for name, title in TABLES.items() if (out / name).exists()}
    for heading, listed in (("Pages", pages), ("Every run, as the studies wrote it", tables)):
        links = (f"* [{title}]({prefix}{name})" for name, title in listed.items())
        lines.append(f"## {heading}\n\n" + "\n".join(links))
    toc = "\n".join(f"{prefix}{name.removesuffix('.md')}" for name in (*pages, *tables))
    lines.append("```{toctree}\n:hidden:\n\n" + toc + "\n```")
    return "\n\n".join(lines) + "\n"


def render(out: Path, doc: Path) -> Path:
    """Write the pages of ``PAGES`` into ``out`` and the overview ``doc`` from its JSON files."""
    for name, text in _page_texts(out).items():
        (out / name).write_text(text)
    rel = Path(*out.relative_to(doc.parent).parts) if out.is_relative_to(doc.parent) else out
    doc.write_text(_overview(out, rel.as_posix()))
    return doc


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fast pass on small settings")
    ap.add_argument("--out", type=Path, help="output folder (default docs/performance)")
    ap.add_argument("--skip", action="append", default=[], choices=STUDIES)
    ap.add_argument("--render-only", action="store_true", help="rebuild the Markdown only")
    args = ap.parse_args(argv)
    out = args.out or (C.ROOT / "build" / "performance-quick" if args.quick else C.OUT)
    out = out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    here = Path(__file__).resolve().parent
    if not args.render_only:
        for study in STUDIES:
            if study in args.skip:
                continue
            cmd = [sys.executable, str(here / f"{study}.py"), "--out", str(out)]
            t0 = time.perf_counter()
            print(f"== {study}{' (quick)' if args.quick else ''}", flush=True)
            subprocess.run(cmd + (["--quick"] if args.quick else []), check=True)
            print(f"== {study}: {time.perf_counter() - t0:.0f} s", flush=True)
    doc = out.parent / "performance.md" if out == C.OUT.resolve() else out / "performance.md"
    print(f"wrote {render(out, doc)}")


if __name__ == "__main__":
    main()
