"""Work–precision study: error against CPU time and against the step h, for every scheme.

Three cases (definitions of the error measures in ``docs/performance/speed-and-accuracy.md``):

* ``paper``: the paper's coupled bar (α = 3 m/s) over ``t_paper`` (0.1 s: four contact
  phases); reference = θ-method ("paper" rule) at ``h_ref`` = 1e-7 s, checked against
  2 ``h_ref``. Methods: θ-method with each activation rule, Carpenter up to its stability
  limit, reduced models (RM1, RM2, larger Craig–Bampton models) with the θ-method and RM1
  with Carpenter;
* ``paper-short``: the same over the first load period (0.035 s) with the penalty baseline
  (BDF, restarts at contact switches) for several stiffnesses, next to the θ-method and
  Carpenter: the penalty is too slow (5–15 s per 0.035 s) for the long window;
* ``impact``: a free bar hitting a rigid obstacle against the exact d'Alembert solution,
  refined in space and time together (fixed Courant number ν = c h / Δx).

Writes ``docs/performance/work_precision.{md,json}``, ``work_precision.png`` (error vs CPU)
and ``order.png`` (error vs h). Run ``python benchmarks/work_precision.py [--quick]``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import femrub as fr
from femrub.reduction import craig_bampton_thermal

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

FULL = {
    "t_paper": 0.1,
    "h_ref": 1e-7,
    "theta_h": (1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6),
    "carpenter_h": (2.5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6),
    "roms": (("RM1", 3, 12), ("RM2", 2, 5), ("CB(4,12)", 4, 12), ("CB(8,19)", 8, 19)),
    "rom_h": (1e-4, 1e-5, 1e-6),
    "rom_carpenter_h": (8e-5, 4e-5, 1e-5),
    "t_short": 0.035,
    "short_h": (1e-4, 1e-5, 1e-6),
    "penalty_k": (1e6, 1e7, 1e8, 1e9),
    "penalty_h": 1e-5,
    "impact_n": (25, 50, 100, 200, 400, 800),
    "penalty_impact_n": (25, 50, 100),
}
QUICK = {
    "t_paper": 0.02,
    "h_ref": 1e-6,
    "theta_h": (1e-3, 1e-4, 1e-5),
    "carpenter_h": (2e-5, 1e-5),
    "roms": (("RM1", 3, 12),),
    "rom_h": (1e-4, 1e-5),
    "rom_carpenter_h": (4e-5,),
    "t_short": 0.01,
    "short_h": (1e-4,),
    "penalty_k": (1e6,),
    "penalty_h": 1e-4,
    "impact_n": (25, 50),
    "penalty_impact_n": (25,),
}
ERRORS = ("u_L2", "u_max", "T_end", "P_phase", "t1")
COLUMNS = [
    ("case", "case"),
    ("method", "method"),
    ("h", "h (s)"),
    ("k", "k_p (N/m)"),
    ("n_dofs", "dofs"),
    ("steps", "steps"),
    ("cpu", "CPU (s)"),
    ("offline", "offline (s)"),
    ("u_L2", "u L2"),
    ("u_max", "u max"),
    ("T_end", "T end"),
    ("P_phase", "P phase"),
    ("t1", "t1 err (s)"),
    ("status", "status"),
]


def _row(case, method, res, cpu, ref, t_end, period, **extra) -> dict:
    row = {"case": case, "method": method, "h": res.h, "k": None, "n_dofs": None, "offline": None}
    row.update(extra)
    m = C.Measures.of(res, period, t_end)
    row.update(C.compare(m, ref), steps=res.steps, cpu=cpu, status=res.status)
    return row


def _run(make, t_end, energy=True):
    """Build a stepper with ``make()`` and run it; return ``(results, CPU seconds)``."""

    def go():
        stepper = make()
        lim = {"tip_temperature": 1500.0} if "tip_temperature" in stepper.model.observations else {}
        return stepper.run(t_end, energy=energy, limits=lim)

    res, cpu, _ = C.timed(go)
    return res, cpu


def paper_case(cfg, log) -> tuple[list[dict], dict]:
    """Rows of the ``paper`` and ``paper-short`` cases, and the reference self-check."""
    T, Ts, P = cfg["t_paper"], cfg["t_short"], C.PERIOD
    full = C.paper_model()
    ref_res, cpu_ref = _run(lambda: fr.ThetaMethod(full, cfg["h_ref"]), T, energy=False)
    ref, ref_s = C.Measures.of(ref_res, P, T), C.Measures.of(ref_res, P, Ts)
    chk_res, _ = _run(lambda: fr.ThetaMethod(full, 2 * cfg["h_ref"]), T, energy=False)
    check = C.compare(C.Measures.of(chk_res, P, T), ref)
    log(f"  reference h = {cfg['h_ref']:g} s: {cpu_ref:.1f} s CPU; check (2h): {check}")
    rows = []
    for rule in fr.steppers.ACTIVATION_RULES:
        for h in cfg["theta_h"]:
            res, cpu = _run(lambda h=h, r=rule: fr.ThetaMethod(full, h, activation=r), T)
            rows.append(_row("paper", f"θ {rule}", res, cpu, ref, T, P, n_dofs=full.n_dofs))
    for h in cfg["carpenter_h"]:
        res, cpu = _run(lambda h=h: fr.Carpenter(full, h), T)
        rows.append(_row("paper", "Carpenter", res, cpu, ref, T, P, n_dofs=full.n_dofs))
    for name, n_uv, n_t in cfg["roms"]:
        (rom, _), offline, _ = C.timed(craig_bampton_thermal, full, n_uv, n_t)
        extra = {"n_dofs": rom.n_dofs, "offline": offline}
        for h in cfg["rom_h"]:
            res, cpu = _run(lambda h=h, m=rom: fr.ThetaMethod(m, h), T)
            rows.append(_row("paper", f"{name} θ", res, cpu, ref, T, P, **extra))
        if name == "RM1":
            for h in cfg["rom_carpenter_h"]:
                res, cpu = _run(lambda h=h, m=rom: fr.Carpenter(m, h), T)
                rows.append(_row("paper", "RM1 Carpenter", res, cpu, ref, T, P, **extra))
        log(f"  {name}: {rom.n_dofs} dofs")
    log(f"  paper case: {len(rows)} runs")
    short = []
    for h in cfg["short_h"]:
        res, cpu = _run(lambda h=h: fr.ThetaMethod(full, h), Ts)
        short.append(_row("paper-short", "θ paper", res, cpu, ref_s, Ts, P, n_dofs=full.n_dofs))
    for h in [x for x in cfg["carpenter_h"] if x >= 1e-5]:
        res, cpu = _run(lambda h=h: fr.Carpenter(full, h), Ts)
        short.append(_row("paper-short", "Carpenter", res, cpu, ref_s, Ts, P, n_dofs=full.n_dofs))
    for k in cfg["penalty_k"]:
        res, cpu = _run(
            lambda k=k: fr.Penalty(full, cfg["penalty_h"], stiffness=k, method="BDF"), Ts
        )
        short.append(
            _row("paper-short", "penalty BDF", res, cpu, ref_s, Ts, P, k=k, n_dofs=full.n_dofs)
        )
        log(f"  penalty k = {k:g} N/m: {cpu:.1f} s CPU")
    return rows + short, {"h_ref": cfg["h_ref"], "cpu_ref": cpu_ref, **check}


def impact_case(cfg, log) -> list[dict]:
    """Rows of the ``impact`` case (exact reference), refined at fixed Courant number."""
    ref, T, rows = C.exact_impact_measures(), C.IMPACT_T_END, []
    series = [
        ("θ paper ν=0.5", 0.5, lambda m, h: fr.ThetaMethod(m, h)),
        ("θ predicted ν=0.5", 0.5, lambda m, h: fr.ThetaMethod(m, h, activation="predicted")),
        ("θ paper ν=4", 4.0, lambda m, h: fr.ThetaMethod(m, h)),
        ("Carpenter ν=0.5", 0.5, lambda m, h: fr.Carpenter(m, h)),
        ("Carpenter ν=0.9", 0.9, lambda m, h: fr.Carpenter(m, h)),
    ]
    for n in cfg["impact_n"]:
        model, dx = C.impact_model(n), C.LENGTH / n
        for name, nu, make in series:
            h = nu * dx / C.WAVE_SPEED
            res, cpu = _run(lambda m=model, h=h, f=make: f(m, h), T)
            rows.append(_row("impact", name, res, cpu, ref, T, None, n_dofs=model.n_dofs))
        if n in cfg["penalty_impact_n"]:
            k = 100.0 * C.E * C.AREA / dx
            h = 0.5 * dx / C.WAVE_SPEED
            res, cpu = _run(
                lambda m=model, h=h, k=k: fr.Penalty(m, h, stiffness=k, method="BDF"), T
            )
            rows.append(
                _row(
                    "impact",
                    "penalty BDF k=100EA/Δx",
                    res,
                    cpu,
                    ref,
                    T,
                    None,
                    k=k,
                    n_dofs=model.n_dofs,
                )
            )
        log(f"  impact n = {n}: done")
    return rows


#: statuses whose runs are measured (an ``inaccurate`` run's error is measured here directly:
#: the reduced models' energy balance does not close, their error against the reference does)
USABLE = ("ok", "inaccurate")


def orders(rows, check) -> list[dict]:
    """Observed order: slope of log(error) vs log(h) over the four finest steps of a series.

    Points with an error below 3× the reference self-check (paper cases) are left out.
    """
    out = []
    series = dict.fromkeys((r["case"], r["method"]) for r in rows if r["k"] is None)
    for case, method in series:
        pts = [
            r for r in rows if r["case"] == case and r["method"] == method and r["status"] in USABLE
        ]
        pts.sort(key=lambda r: r["h"])
        row = {"case": case, "method": method}
        for key in ("u_L2", "T_end", "P_phase"):
            floor = 3 * check.get(key, 0.0) if case.startswith("paper") else 0.0
            xy = [(r["h"], r[key]) for r in pts if np.isfinite(r[key]) and r[key] > floor][:4]
            if len(xy) < 3:
                row[key] = math.nan
            elif xy[0][1] > 0.5 * max(e for _, e in xy):  # no decrease: reduction error
                row[key] = f"plateau {C.fmt(xy[0][1])}"
            else:
                x, y = np.log(np.array(xy)).T
                row[key] = float(np.polyfit(x, y, 1)[0])
        out.append(row)
    return out


def winners(rows, check, key="u_L2", levels=(1e-1, 1e-2, 1e-3, 1e-4)) -> list[dict]:
    """Cheapest run (CPU) of each case whose error ``key`` is within each accuracy level."""
    out = []
    for case in dict.fromkeys(r["case"] for r in rows):
        floor = 3 * check.get(key, 0.0) if case.startswith("paper") else 0.0
        for tol in levels:
            if tol <= floor:
                continue
            ok = [
                r
                for r in rows
                if r["case"] == case
                and r["status"] in USABLE
                and np.isfinite(r[key])
                and r[key] <= tol
            ]
            if not ok:
                out.append({"case": case, "measure": key, "level": tol, "winner": "none reached"})
                continue
            ok.sort(key=lambda r: r["cpu"])
            best = ok[0]
            other = next((r for r in ok if r["method"] != best["method"]), None)
            out.append(
                {
                    "case": case,
                    "measure": key,
                    "level": tol,
                    "winner": best["method"],
                    "h": best["h"],
                    "k": best["k"],
                    "cpu": best["cpu"],
                    "runner_up": other["method"] if other else "—",
                    "runner_up_cpu": other["cpu"] if other else math.nan,
                }
            )
    return out


def plot(rows, check, out: Path, x: str, fname: str) -> Path:
    """Error vs ``x`` ("cpu" or "h"): one column per case, rows u_L2 and T_end / P_phase."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r["case"] for r in rows))
    fig, axes = plt.subplots(2, len(cases), figsize=(5.2 * len(cases), 8.0), squeeze=False)
    for j, case in enumerate(cases):
        sub = [r for r in rows if r["case"] == case]
        second = "P_phase" if case == "impact" else "T_end"
        for i, key in enumerate(("u_L2", second)):
            ax = axes[i, j]
            for method in dict.fromkeys(r["method"] for r in sub):
                pts = [r for r in sub if r["method"] == method and np.isfinite(r[key])]
                if x == "h" and "penalty" in method:
                    continue
                pts.sort(key=lambda r: (r["k"] or 0.0, -r["h"]))  # along the refinement
                xs = [r[x] for r in pts]
                ys = [max(r[key], 1e-12) for r in pts]
                style = "--" if "RM" in method or "CB" in method else "-"
                ax.loglog(xs, ys, style, marker="o", ms=4, label=method)
            if case != "impact" and check.get(key):
                ax.axhline(3 * check[key], color="k", ls=":", lw=1, label="reference floor")
            ax.set_xlabel("CPU time (s)" if x == "cpu" else "time step h (s)")
            ax.set_ylabel(f"{key} error" + (" (relative)" if key != "t1" else " (s)"))
            ax.set_title(f"{case}: {key}")
            ax.grid(True, which="both", alpha=0.3)
        axes[0, j].legend(fontsize=7)
    fig.tight_layout()
    path = out / fname
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def report(rows, ords, wins, check, cfg) -> str:
    """The Markdown table file ``work_precision.md``."""
    ocols = [("case", "case"), ("method", "method"), ("u_L2", "order u L2")]
    ocols += [("T_end", "order T end"), ("P_phase", "order P phase")]
    wcols = [("case", "case"), ("measure", "error"), ("level", "≤"), ("winner", "cheapest")]
    wcols += [("h", "h (s)"), ("k", "k_p"), ("cpu", "CPU (s)")]
    wcols += [("runner_up", "next method"), ("runner_up_cpu", "its CPU (s)")]
    return "\n\n".join(
        [
            "# Work–precision study: measured table",
            f"Settings: `{ {k: v for k, v in cfg.items() if not isinstance(v, tuple)} }`. "
            f"Reference self-check (θ at 2 h_ref against h_ref = {check['h_ref']:g} s): "
            + ", ".join(f"{k} {C.fmt(check[k])}" for k in ERRORS),
            "## Cheapest method per accuracy level\n\n" + C.md_table(wins, wcols),
            "## Observed orders (slope of log error vs log h, four finest steps)\n\n"
            + C.md_table(ords, ocols),
            "## All runs\n\n" + C.md_table(rows, COLUMNS),
        ]
    )


def run_study(cfg: dict, out: Path, log=print) -> dict:
    """Run every case of ``cfg`` and write the table, JSON and plots into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    rows, check = paper_case(cfg, log)
    rows += impact_case(cfg, log)
    ords = orders(rows, check)
    wins = winners(rows, check, "u_L2") + winners(
        [r for r in rows if r["case"] != "impact"], check, "T_end", (1e-1, 1e-2, 1e-3)
    )
    (out / "work_precision.md").write_text(report(rows, ords, wins, check, cfg) + "\n")
    doc = {"settings": cfg, "machine": C.machine(), "check": check}
    doc.update(rows=rows, orders=ords, winners=wins)
    C.write_json(out / "work_precision.json", doc)
    plot(rows, check, out, "cpu", "work_precision.png")
    plot(rows, check, out, "h", "order.png")
    return doc


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a fast pass on small settings")
    ap.add_argument("--out", type=Path, default=C.OUT, help="output folder")
    args = ap.parse_args(argv)
    doc = run_study(QUICK if args.quick else FULL, args.out)
    print(f"wrote {args.out}/work_precision.md ({len(doc['rows'])} runs)")


if __name__ == "__main__":
    main()
