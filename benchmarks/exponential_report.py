"""Tables, notes and plot of ``benchmarks/exponential.py`` (docs/performance/exponential*)."""

from __future__ import annotations

import math

try:
    from . import _common as C
    from .exponential_bound import BOUND_COLS, BOUND_TEXT
    from .exponential_levels import OTHERS, TARGET, THETA_BLOCKS, cheapest
    from .exponential_notes import NOTES
except ImportError:  # run as a script
    import _common as C
    from exponential_bound import BOUND_COLS, BOUND_TEXT
    from exponential_levels import OTHERS, TARGET, THETA_BLOCKS, cheapest
    from exponential_notes import NOTES


def plot(wp, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for ax, key in zip(axes, ("u_L2", "u_L2_nodes", "T_end")):
        for method in dict.fromkeys(r["method"] for r in wp["rows"]):
            rs = [r for r in wp["rows"] if r["method"] == method and r[key] > 0]
            ax.loglog([r["cpu"] for r in rs], [r[key] for r in rs], "o-", label=method)
        ax.axhline(0.01, color="k", lw=0.6, ls=":")
        ax.set_xlabel("CPU (s)")
        ax.set_ylabel(f"{key} error")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"paper case, {wp['t_end']} s: error against CPU")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(doc) -> str:
    """Every table of the study (docs/performance/exponential.md)."""
    out = [f"# Exponential stepper study\n\nMachine: {doc['machine']}\n"]
    if "accuracy" in doc:
        a = doc["accuracy"]
        out += [
            f"## Paper case, tip temperature at {a['t_end']} s\n",
            C.md_table(
                a["reference"],
                [
                    ("h", "θ reference h (s)"),
                    ("T_end", "T (K)"),
                    ("t1", "first contact (s)"),
                    ("cpu", "CPU (s)"),
                ],
            ),
            f"\nReference spread (two finest θ steps): {a['reference_spread']:.3g}\n",
            C.md_table(
                a["rows"],
                [
                    ("method", "method"),
                    ("h", "h (s)"),
                    ("status", "status"),
                    ("T_end", "T (K)"),
                    ("T_err", "T error"),
                    ("t1", "first contact (s)"),
                    ("t1_err_steps", "t1 error (steps)"),
                    ("cpu", "CPU (s)"),
                ],
            ),
        ]
    if "work_precision" in doc:
        w = doc["work_precision"]
        out += [
            f"\n## Work–precision, paper case over {w['t_end']} s (θ reference h = "
            f"{w['h_ref']:g} s)\n",
            C.md_table(
                w["rows"],
                [
                    ("method", "method"),
                    ("h", "h (s)"),
                    ("u_L2", "u L2"),
                    ("u_L2_nodes", "u L2 nodes"),
                    ("T_end", "T end"),
                    ("P_phase", "P phase"),
                    ("t1", "t1 (s)"),
                    ("cpu", "CPU (s)"),
                ],
            ),
        ]
    if "impact" in doc:
        out += [
            "\n## Free bar impact, fixed mesh, against the exact solution\n",
            C.md_table(
                doc["impact"],
                [
                    ("method", "method"),
                    ("nu", "Courant ν"),
                    ("h", "h (s)"),
                    ("u_L2_nodes", "u L2 nodes"),
                    ("impulse_err", "impulse error"),
                    ("cpu", "CPU (s)"),
                ],
            ),
        ]
    if doc.get("blade"):
        b = doc["blade"]
        out += [
            f"\n## Reduced twisted NACA blade ({b['n_dofs']} coordinates), {b['t_end']} s; "
            f"Carpenter limit {b['carpenter_limit']:.3g} s\n",
            C.md_table(
                b["rows"],
                [
                    ("method", "method"),
                    ("h", "h (s)"),
                    ("u_L2", "u L2"),
                    ("u_L2_nodes", "u L2 nodes"),
                    ("T_end", "T end"),
                    ("min_gap", "min gap (m)"),
                    ("cpu", "CPU (s)"),
                ],
            ),
        ]
    if doc.get("blade_friction"):
        b = doc["blade_friction"]
        out += [
            f"\n## Reduced twisted NACA blade with Coulomb friction (μ = {b['mu']:g}, power "
            f"heat), {b['t_end']} s; reference θ {b['T_ref']:.6g} K\n",
            C.md_table(b["rows"], _FRICTION_COLS),
        ]
    if doc.get("floor"):
        out += [
            "\n## Cost floor of the exponential stepper (CPU s, best of 5)\n",
            C.md_table(_floor_rows(doc), _FLOOR_COLS),
        ]
    if doc.get("bound"):
        out += [
            "\n## Least cost against the 3× target at 1 % tip temperature (CPU s)\n",
            C.md_table(doc["bound"], BOUND_COLS),
        ]
    return "\n".join(out) + "\n"


_FLOOR_COLS = [
    ("case", "case"),
    ("key", "at 1 %"),
    ("h", "h (s)"),
    ("steps", "steps"),
    ("events", "events"),
    ("held_sets", "held sets"),
    ("run", "run"),
    ("run_no_energy", "run, energy off"),
    ("constructor", "constructor"),
    ("flows", "sub-step flows"),
    ("probe_rows", "probe rows"),
    ("work_integrals", "work integrals"),
    ("fixed", "fixed"),
    ("quiet_step", "step without event"),
    ("quiet", "steps without event"),
    ("recording", "recorder"),
    ("events_rest", "event steps"),
    ("bound", "run − steps without event"),
    ("best", "best other at 1 %"),
    ("target", "3× target"),
]

_FRICTION_COLS = [
    ("method", "method"),
    ("h", "h (s)"),
    ("u_L2", "u L2"),
    ("u_L2_nodes", "u L2 nodes"),
    ("T_end", "T end"),
    ("status", "status"),
    ("energy_error", "energy error"),
    ("heat_error", "heat error"),
    ("coulomb_direction", "Coulomb direction"),
    ("coulomb_sliding", "Coulomb sliding"),
    ("cpu", "CPU (s)"),
]


def _floor_rows(doc) -> list[dict]:
    """The floor rows with the cheapest θ or Carpenter run within 1 % of the row's error."""
    runs = {"paper": doc.get("work_precision", {}), "blade": doc.get("blade", {})}
    out = []
    for r in doc["floor"]:
        key = r.get("key", "T_end")
        best = cheapest(runs[r["case"]].get("rows", []), key, 0.01)
        cpu = [best[m]["cpu"] for m in OTHERS if m in best]
        other = min(cpu) if cpu else math.nan
        bound = r["run"] - r.get("quiet", 0.0)
        out.append({"key": key, **r, "bound": bound, "best": other, "target": other / TARGET})
    return out


def _level_rows(rows, keys, levels, others=("θ paper", "Carpenter")):
    """Cheapest run per method at each (key, level) and the exponential's CPU ratio."""
    out = []
    for key in keys:
        for level in levels:
            best = cheapest(rows, key, level)
            e = best.get("exponential")
            row = {"key": key, "level": level}
            for m in (*others, "exponential"):
                r = best.get(m)
                row[m] = "not reached" if r is None else f"{r['cpu']:.3g} s (h {r['h']:.2g})"
            ratio = [best[m]["cpu"] / e["cpu"] for m in others if e and m in best]
            row["ratio"] = min(ratio) if ratio else math.nan
            if e is None:
                row["verdict"] = "not reached"
            elif not ratio:
                row["verdict"] = "others not reached at the steps tried"
            else:
                row["verdict"] = "met" if row["ratio"] >= TARGET else "not met"
                if len(ratio) < len(others):  # against the methods that reached the level
                    row["verdict"] += ", others not reached at the steps tried"
            out.append(row)
    return out


def section(doc) -> str:
    """docs/performance/exponential-stepper.md (rendered by run_all.py from this section)."""
    lines = [
        "Measured by `python benchmarks/exponential.py` (one BLAS thread for every method; "
        "a run under 0.5 s CPU: the best of 5; "
        f"load average {doc['machine']['load_average']} at the start, "
        f"{doc['machine'].get('load_average_end', '?')} at the end; every run: "
        "[performance/exponential.md](performance/exponential.md), data "
        "`performance/exponential.json`)."
        + "".join(
            f" {k}: load {v[0]} at its start, {v[1]} at its end;"
            for k, v in doc.get("study_load", {}).items()
        ),
        "![exponential: error vs CPU](performance/exponential.png)",
    ]
    if "accuracy" in doc:
        a = doc["accuracy"]
        rows = [{**r, "target": {5e-4: 0.02, 5e-3: 0.2}.get(r["h"], math.nan)} for r in a["rows"]]
        for r in rows:
            ok = abs(r["T_err"]) <= r["target"]
            r["met"] = ("met" if ok else "not met") if r["method"] == "exponential" else "—"
            if r["status"] != "ok":
                r["met"] += f" (run {r['status']})"
        ref = a["reference"]
        lines += [
            f"**Paper case (α = 3 m/s, coupled), tip temperature at {a['t_end']} s** against the "
            f"θ-method at h = {ref[-1]['h']:g} s ({ref[-1]['T_end']:.5g} K; at "
            f"{ref[0]['h']:g} s: {ref[0]['T_end']:.5g} K, spread {a['reference_spread']:.2%}). "
            "First contact: end of the step holding it, in steps from the reference time.",
            C.md_table(
                rows,
                [
                    ("method", "method"),
                    ("h", "h (s)"),
                    ("T_end", "T (K)"),
                    ("T_err", "error"),
                    ("target", "target"),
                    ("met", "verdict"),
                    ("t1_err_steps", "t1 error (steps)"),
                    ("cpu", "CPU (s)"),
                ],
            ),
        ]
    cols = [
        ("key", "error"),
        ("level", "≤"),
        ("θ paper", "θ paper"),
        ("Carpenter", "Carpenter"),
        ("exponential", "exponential"),
        ("ratio", "best other / exponential"),
        ("verdict", f"{TARGET:g}× target"),
    ]
    if "work_precision" in doc:
        w = doc["work_precision"]
        lines += [
            f"**Work–precision, paper case over {w['t_end']} s** (θ reference h = "
            f"{w['h_ref']:g} s; `u_L2` as in §1, `u_L2_nodes` at the run's own output times): "
            "cheapest run reaching each level.",
            C.md_table(
                _level_rows(w["rows"], ("u_L2", "u_L2_nodes", "T_end"), (0.01, 0.001)), cols
            ),
        ]
    if doc.get("blade"):
        b = doc["blade"]
        lines += [
            f"**Reduced twisted NACA blade** (`twisted-naca`, {b['n_dofs']} coordinates, lobed "
            f"casing, {b['t_end']} s; its Coulomb friction replaced by the α law of the same "
            "heat at full slip, α = η μ Ω r_tip, for every method (the frictionless comparison; "
            "the frictional one, every method with Coulomb friction, follows); θ reference "
            f"h = {doc['config']['blade_ref_h']:g} s; "
            f"Carpenter's limit {b['carpenter_limit']:.3g} s).",
            "θ runs per step in Python on this model (no compiled path for two frictionless "
            "contacts on a moving casing); `θ compiled (μ = 1e-9)` is the same model with "
            "μ = 1e-9 on θ's compiled friction blocks, its best implementation, and the "
            "verdict is against it too.",
            C.md_table(
                _level_rows(b["rows"], ("u_L2", "u_L2_nodes", "T_end"), (0.01,), OTHERS),
                [*cols[:3], (THETA_BLOCKS, THETA_BLOCKS), *cols[3:]],
            ),
        ]
    if doc.get("blade_friction"):
        b = doc["blade_friction"]
        exp = [r for r in b["rows"] if r["method"] == "exponential"]
        lines += [
            f"**Reduced twisted NACA blade with its Coulomb friction** (μ = {b['mu']:g}, "
            f'"power" heat law, {b["n_dofs"]} coordinates, {b["t_end"]} s; every method on '
            f"this model, θ on its compiled friction blocks; θ reference h = "
            f"{doc['config']['blade_ref_h']:g} s, tip temperature {b['T_ref']:.6g} K; "
            f"Carpenter's limit {b['carpenter_limit']:.3g} s).",
            C.md_table(_level_rows(b["rows"], ("u_L2", "u_L2_nodes", "T_end"), (0.01,)), cols),
            "Exponential runs (status, balances, Coulomb's law on the recorded steps: `1 + cos` "
            "of friction impulse and end slip, sliding equality; the verdict's bound is 1e-8):",
            C.md_table(exp, _FRICTION_COLS),
        ]
    if doc.get("floor"):
        lines += [
            "**Cost floor of the exponential stepper** (CPU s, best of 5) at its coarsest step "
            "(within 1 % of the tip temperature) and at its coarsest step within 1 % `u_L2`: "
            "fixed = constructor + per held set met: sub-step flows, probe rows, work "
            "integrals; steps without event = their median × their number; recorder = the run "
            "less its steps (energy meter, rows); event steps = the rest. Against the "
            "cheapest θ (either implementation on the blade) or Carpenter run within 1 % of "
            "the same error (the 3× target is a third of it):",
            C.md_table(_floor_rows(doc), _FLOOR_COLS),
        ]
    if doc.get("bound"):
        lines += [
            BOUND_TEXT,
            C.md_table(doc["bound"], BOUND_COLS),
        ]
    if "impact" in doc:
        lines += [
            "**Free bar impact** (fixed mesh, exact solution; error at the output times):",
            C.md_table(
                doc["impact"],
                [
                    ("method", "method"),
                    ("nu", "Courant ν"),
                    ("u_L2_nodes", "u error"),
                    ("impulse_err", "impulse error"),
                    ("cpu", "CPU (s)"),
                ],
            ),
        ]
    return "\n\n".join([*lines, NOTES])
