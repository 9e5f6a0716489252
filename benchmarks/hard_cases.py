"""Hard cases, long versions (the fast ones are in tests/test_hard_cases.py).

Every case runs to its end or to a physical stop criterion (tip temperature rise 1500 K,
``diverged-physically``) and records status, key numbers and CPU time:

* coarse steps: θ-method at h = 5e-4, 1e-3, 5e-3 s on the paper case, both activation
  rules, coupled and uncoupled, against a fine step; numerical damping γ > 1/2 at 5e-3 s;
* restitution e = 0, 0.5, 1 without load (energy constant over many impacts for e = 1);
* thermal runaway α = 7 m/s; grazing contact; chattering under a large preload;
* stiff heat equation (graded mesh, conductivity × 1000); many contacts closing at once;
* Carpenter just below and above its stability limit.

Writes ``docs/performance/hard_cases.{md,json}``. Run ``python benchmarks/hard_cases.py``
(``--quick``: shorter windows, fewer variants).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import femrub as fr
from femrub.model.build import ContactSpec, Load, first_order_model

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

LIMITS = {"tip_temperature": 1500.0}
FULL = {"t": 0.4, "h_fine": 1e-6, "gammas": (0.6, 0.75, 1.0), "n_stiff": (60, 200)}
QUICK = {"t": 0.05, "h_fine": 1e-5, "gammas": (1.0,), "n_stiff": (60,)}


def _summary(res) -> dict:
    """Key numbers of a run (SI units)."""
    e = res.energy
    T = res.signals.get("tip_temperature")
    P = res.impulse.sum(axis=1)
    return {
        "t_stop": float(res.t[-1]),
        "T_end": float(T[-1, 0]) if T is not None else np.nan,
        "F_max": float(res.force.max()) if res.force.size else 0.0,
        "impulse": float(P.sum()),
        "friction_heat": float(e["friction_heat"][-1]) if e else np.nan,
        "penetration": float(max(0.0, -res.gap.min())) if res.gap.size else 0.0,
        "impacts": len(res.contact_phases()),
        "energy_error": res.energy_error(),
    }


def _run(case, stepper, t_end, keys, note="", **kw) -> dict:
    """Run ``stepper`` to ``t_end``; keep ``keys`` of the summary as the row's key numbers."""
    lim = LIMITS if "tip_temperature" in stepper.model.observations else None
    res, cpu, _ = C.timed(stepper.run, t_end, limits=lim, **kw)
    s = _summary(res)
    key = ", ".join(f"{k} {C.fmt(s[k])}" for k in keys)
    row = {"case": case, "scheme": _scheme(stepper), "h": stepper.h, "status": res.status}
    row.update(key=(note + "; " if note else "") + key, cpu=cpu, message=res.message, **s)
    return row | {"_res": res}


def _scheme(st) -> str:
    if isinstance(st, fr.ThetaMethod):
        g = "" if st.gamma == 0.5 else f", γ={st.gamma:g}"
        return f"θ {st.activation}{g}"
    return st.name


def coarse_steps(cfg) -> list[dict]:
    """θ-method at coarse steps against a fine step: paper case, coupled and uncoupled."""
    rows, T = [], cfg["t"]
    keys = ("T_end", "F_max", "impulse", "friction_heat", "penetration")
    for coupled in (True, False):
        model = C.paper_model(coupled=coupled)
        tag = "coarse steps, " + ("coupled" if coupled else "uncoupled")
        ref = _run(tag, fr.ThetaMethod(model, cfg["h_fine"]), T, keys, "fine-step reference")
        rows.append(ref)
        for rule in fr.steppers.ACTIVATION_RULES:
            for h in (5e-4, 1e-3, 5e-3):
                gammas = (0.5, *cfg["gammas"]) if h == 5e-3 else (0.5,)
                for g in gammas:
                    st = fr.ThetaMethod(model, h, activation=rule, gamma=g)
                    W = float(st._Wm[0, 0])  # Delassus operator, kg⁻¹
                    r = _run(tag, st, T, keys, f"1/W {1 / W:.3g} kg")
                    r.update(gamma=g, rule=rule, coupled=coupled, inv_W=1 / W)
                    r["ratio_T"] = r["T_end"] / ref["T_end"]
                    r["ratio_heat"] = r["friction_heat"] / ref["friction_heat"]
                    r["key"] += f"; T/T_fine {r['ratio_T']:.3g}, Q/Q_fine {r['ratio_heat']:.3g}"
                    P, gap = r["_res"].impulse[:, 0], r["_res"].gap[:, 0]
                    r["active"] = int((P > 0).sum())
                    r["open_share"] = float(P[gap > 1e-6].sum() / P.sum()) if P.sum() else 0.0
                    r["key"] += f"; {r['active']} active steps, {r['open_share']:.0%} at open gap"
                    rows.append(r)
    return rows


def restitution(cfg) -> list[dict]:
    """Free vibration against the casing, no load, e = 0, 0.5, 1: energy over many impacts."""
    rows = []
    for e in (0.0, 0.5, 1.0):
        model = fr.bar_model(
            force_amplitude=0.0, initial_velocity=0.1, restitution=e, coupling="none", alpha=0.0
        )
        out = _run(f"restitution e = {e:g}, no load", fr.ThetaMethod(model, 1e-5), cfg["t"], ())
        E = out["_res"].energy["kinetic"] + out["_res"].energy["elastic"]
        dE = np.diff(E)
        out["drift"] = float(np.max(np.abs(E - E[0])) / E[0])
        out["key"] = (
            f"impacts {out['impacts']}, E_end/E0 {E[-1] / E[0]:.3g}, max ∣E−E0∣/E0 "
            f"{out['drift']:.2e}, largest step increase of E {dE.max() / E[0]:.1e} E0"
        )
        rows.append(out)
    return rows


def runaway(cfg) -> list[dict]:
    """α = 7 m/s: the contact stays closed and the temperature runs away (paper Fig. 3)."""
    model, rows = C.paper_model(alpha=7.0), []
    keys = ("t_stop", "T_end", "F_max", "energy_error")
    for st in (fr.ThetaMethod(model, 1e-4), fr.ThetaMethod(model, 1e-5), fr.Carpenter(model, 1e-5)):
        r = _run("thermal runaway α = 7 m/s", st, 0.4, keys)
        e = r["_res"].energy
        r["key"] += f", heat residual {abs(e['heat_error'][-1]) / e['friction_heat'][-1]:.1e}"
        rows.append(r)
    return rows


def contact_regimes(cfg) -> list[dict]:
    """Grazing contact (gap = peak static deflection) and chattering under a 50 N load."""
    rows, T = [], cfg["t"]
    gap = 7.0 * 0.3 / (110e9 * 1e-6)
    keys = ("impacts", "F_max", "penetration", "T_end", "energy_error")
    for h in (1e-4, 1e-5):
        model = fr.bar_model(alpha=1.0, gap=gap)
        rows.append(_run("grazing (gap 19.09 µm)", fr.ThetaMethod(model, h), T, keys))
    model = fr.bar_model(alpha=1.0, force_amplitude=50.0)
    for st in (fr.ThetaMethod(model, 1e-4), fr.ThetaMethod(model, 1e-5), fr.Carpenter(model, 1e-5)):
        r = _run("chattering (50 N preload)", st, T, keys)
        res = r["_res"]
        closed = float((res.impulse[:, 0] > 0).mean())
        dW = np.diff(res.energy["contact_work"]).max()
        r["key"] += f", closed {100 * closed:.0f} % of steps, max step contact work {dW:.1e} J"
        rows.append(r)
    return rows


def stiff_heat(cfg) -> list[dict]:
    """Graded mesh (ratio 3), conductivity × 1000: a stiff heat equation.

    Physical coupling (``E α_th ∫ θ div v``): the paper's nodal ``β K^uu`` is refused on a
    graded mesh (a hot micrometre-long element would expand the tip by ``−β θ``). The
    trapezoidal heat rows (γ_θ = 1/2) are compared with backward Euler (γ_θ = 1) at two
    steps; Carpenter's explicit heat equation needs a nanosecond step.
    """
    rows = []
    for n in cfg["n_stiff"]:
        model = fr.bar_model(
            alpha=3.0, conductivity=3.35e3, grading=3.0, n_elements=n, coupling="physical"
        )
        tag = f"stiff heat, {n} elements ({model.n_dofs} dofs)"
        carp = fr.Carpenter(model, 1e-5)
        lim = carp.stability_limit()
        for gt in (0.5, 1.0):
            for h in (1e-4, 2.5e-5):
                st = fr.ThetaMethod(model, h, gamma_thermal=gt)
                r = _run(f"{tag}, γ_θ={gt}", st, cfg["t"], ("t_stop", "T_end"))
                e, T = r["_res"].energy, r["_res"].signal("tip_temperature")
                heat = abs(e["heat_error"][-1]) / e["friction_heat"][-1]
                r["key"] += (
                    f", T min {C.fmt(T.min())}, F_max {C.fmt(r['F_max'])}, heat res. {heat:.1e}"
                )
                rows.append(r)
        rows.append(_run(tag, carp, 0.01, ("t_stop",), f"stability limit {lim:.2e} s"))
    return rows


def many_contacts(cfg) -> list[dict]:
    """A contact at every node of the paper bar, gaps at 80 % of the static deflection."""
    mats, tip = fr.bar_matrices(fr.PAPER)
    n = mats.n_u
    f = np.zeros(n)
    f[tip] = 7.0
    static = np.linalg.solve(mats.K.toarray(), f)
    spec = ContactSpec(
        normals=np.eye(n), gap=0.8 * static, heat_dofs=np.arange(n), heat_coefficient=1.0
    )
    om = fr.PAPER.force_frequency
    model = first_order_model(
        mats, contact=spec, loads=[Load(f, lambda t: np.sin(om * t))], observe={}
    )
    rows = []
    for h in (1e-4, 1e-5):
        r = _run(f"{n} contacts closing at once", fr.ThetaMethod(model, h), cfg["t"], ())
        res = r["_res"]
        act = (res.impulse > 0).sum(axis=1)
        r["key"] = (
            f"max active contacts in one step {act.max()}, steps with ≥ {n // 2} active "
            f"{int((act >= n // 2).sum())}, penetration {C.fmt(r['penetration'])} m, "
            f"energy error {C.fmt(r['energy_error'])}, {1e6 * r['cpu'] / res.steps:.0f} µs/step"
        )
        rows.append(r)
    return rows


def carpenter_limit(cfg) -> list[dict]:
    """Carpenter at 0.98, 1.02, 1.1 and 2 times its stability limit on the paper case."""
    model = C.paper_model()
    lim = fr.Carpenter(model, 1e-5).stability_limit()
    rows = []
    for f in (0.98, 1.02, 1.1, 2.0):
        st = fr.Carpenter(model, f * lim)
        r = _run("Carpenter near its limit", st, cfg["t"], ("t_stop", "T_end"))
        r["key"] = f"h = {f:g} × {lim:.3e} s; " + r["key"] + f"; steps {r['_res'].steps}"
        rows.append(r)
    return rows


CASES = (coarse_steps, restitution, runaway, contact_regimes, stiff_heat, many_contacts)
CASES += (carpenter_limit,)


def report(rows) -> str:
    cols = [("case", "case"), ("scheme", "scheme"), ("h", "h (s)"), ("status", "status")]
    cols += [("key", "key numbers (SI)"), ("cpu", "CPU (s)")]
    return "# Hard cases: measured table\n\n" + C.md_table(rows, cols)


def run_study(cfg, out: Path, log=print) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for case in CASES:
        new, cpu, _ = C.timed(case, cfg)
        for r in new:
            r.pop("_res", None)
        rows += new
        log(f"  {case.__name__}: {len(new)} runs, {cpu:.1f} s CPU")
    (out / "hard_cases.md").write_text(report(rows) + "\n")
    doc = {"settings": cfg, "machine": C.machine(), "rows": rows}
    C.write_json(out / "hard_cases.json", doc)
    return doc


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shorter windows, fewer variants")
    ap.add_argument("--out", type=Path, default=C.OUT, help="output folder")
    args = ap.parse_args(argv)
    run_study(QUICK if args.quick else FULL, args.out)
    print(f"wrote {args.out}/hard_cases.md")


if __name__ == "__main__":
    main()
