"""Exponential Moreau stepper against the θ-method and Carpenter.

Four studies, one command (``python benchmarks/exponential.py [--quick]``):

* ``accuracy``: paper case (α = 3 m/s, coupled) over 0.4 s: tip temperature at 0.4 s and
  first-contact time of the exponential stepper at h = 5e-4 and 5e-3 s against a converged
  θ-method reference (two fine steps, their difference reported);
* ``work-precision``: paper case over 0.1 s, error against CPU for θ (paper rule), Carpenter
  and the exponential stepper, reference θ at ``h_ref``; errors as in
  docs/performance/speed-and-accuracy.md (``u_L2`` on the reference grid, piecewise-linear
  interpolant of the run) plus ``u_L2 nodes``
  (the run's own output times: the error of the computed states);
* ``events``: the same with event location off (impulses at step ends only);
* ``impact``: free bar hitting a rigid obstacle on a fixed mesh, several Courant numbers,
  error against the exact solution at the run's output times;
* ``blade``: the reduced twisted NACA blade scene (``twisted-naca``), short window, against a
  fine θ-method step; its Coulomb friction replaced by the α law of the same heat at full slip
  (``α = η μ Ω r_tip``) for every method (the comparison made before the exponential stepper
  had friction, kept);
* ``blade_friction``: the same scene with its Coulomb friction and "power" heat law, every
  method (θ on its compiled friction blocks, Carpenter, exponential) against a fine θ step.

Every method runs with one BLAS thread (``threadpoolctl``): on these small dense systems more
threads only add spinning worker threads to the process's CPU time.

* ``floor`` (``exponential_floor.py``): where an exponential run's CPU goes;
* ``bound`` (``exponential_bound.py``): the exponential stepper's least cost at 1 % tip temperature.

Writes docs/performance/exponential.{md,json,png} (tables, notes: ``exponential_report.py``).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

import femrub as fr

try:
    from . import _common as C
    from .exponential_bound import bound
    from .exponential_floor import floor, frictionless
    from .exponential_levels import THETA_BLOCKS, cheapest
    from .exponential_report import markdown, plot, section
except ImportError:  # run as a script
    import _common as C
    from exponential_bound import bound
    from exponential_floor import floor, frictionless
    from exponential_levels import THETA_BLOCKS, cheapest
    from exponential_report import markdown, plot, section

FULL = {
    "t_acc": 0.4,
    "acc_ref_h": (1e-6, 5e-7),
    "acc_h": (5e-3, 5e-4),
    "t_wp": 0.1,
    "h_ref": 2e-7,
    "theta_h": (1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6),
    "carpenter_h": (2.5e-5, 2e-5, 1e-5, 5e-6),
    "exp_h": (5e-3, 2e-3, 1e-3, 5e-4, 4e-4, 2.5e-4, 2e-4, 1e-4),  # steps dividing t_wp
    "impact_n": 100,
    "impact_nu": (0.5, 1.0, 2.0, 4.0, 8.0),
    "blade_t": 0.004,
    "blade_ref_h": 2e-7,
    "blade_theta_h": (1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6, 5e-7),
    "blade_exp_h": (2e-4, 1e-4, 5e-5, 2e-5, 1e-5),
    # θ on its compiled friction blocks (μ = 1e-9: no compiled frictionless multi-contact path)
    "blade_theta_block_h": (1e-4, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6, 5e-7, 2.5e-7),
    "blade_carpenter_f": (0.9, 0.5, 0.2),
    "fric_theta_h": (1e-4, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6, 5e-7, 2.5e-7),
    "fric_exp_h": (2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6),
    "floor_u_h": 2.5e-4,  # the exponential's coarsest step within 1 % u_L2 (paper case)
}
QUICK = {
    "t_acc": 0.1,
    "acc_ref_h": (1e-5, 5e-6),
    "acc_h": (5e-3, 5e-4),
    "t_wp": 0.02,
    "h_ref": 2e-6,
    "theta_h": (1e-4, 1e-5),
    "carpenter_h": (2e-5,),
    "exp_h": (1e-3, 1e-4),
    "impact_n": 40,
    "impact_nu": (0.5, 4.0),
    "blade_t": 0.0,
    "blade_ref_h": 2e-6,
    "blade_theta_h": (),
    "blade_exp_h": (),
    "blade_theta_block_h": (),
    "blade_carpenter_f": (),
    "fric_theta_h": (),
    "fric_exp_h": (),
    "floor_u_h": 1e-4,
}


#: a run cheaper than this (CPU s) is repeated and its best time kept, up to REPEATS runs:
#: single timings of tens of ms move by ±30 % on a shared machine
REPEAT_BELOW, REPEATS = 0.5, 5


def _run(make, t_end, energy=True):
    """``(Results, CPU s)`` of building the stepper and running it (the best of
    :data:`REPEATS` runs when one costs less than :data:`REPEAT_BELOW` s)."""
    best = math.inf
    for _ in range(REPEATS):
        c0 = time.process_time()
        res = make().run(t_end, energy=energy)
        best = min(best, time.process_time() - c0)
        if best >= REPEAT_BELOW:
            break
    return res, best


def _nodal_l2(t, u, t_ref, u_ref) -> float:
    """Relative l2 error of ``u`` at its own times against ``u_ref`` interpolated there."""
    r = np.interp(t, t_ref, u_ref)
    return float(np.sqrt(np.sum((u - r) ** 2) / np.sum(r**2)))


def accuracy(cfg, log) -> dict:
    """Tip temperature at ``t_acc`` and first contact time, paper case (coupled, α = 3)."""
    model, T = C.paper_model(), cfg["t_acc"]
    refs = []
    for h in cfg["acc_ref_h"]:
        res, cpu = _run(lambda h=h: fr.ThetaMethod(model, h), T, energy=False)
        refs.append((h, res.signals["tip_temperature"][-1, 0], res.first_contact_time(), cpu))
        log(f"accuracy ref θ h={h:g}: T={refs[-1][1]:.6g} K t1={refs[-1][2]:.6g} s ({cpu:.1f} s)")
    T_ref, t1_ref = refs[-1][1], refs[-1][2]
    rows = []
    for name, make in (
        ("exponential", lambda h: fr.ExponentialMoreau(model, h)),
        ("θ paper", lambda h: fr.ThetaMethod(model, h)),
    ):
        for h in cfg["acc_h"]:
            res, cpu = _run(lambda h=h, make=make: make(h), T)
            Th = res.signals["tip_temperature"][-1, 0]
            rows.append(
                {
                    "method": name,
                    "h": h,
                    "status": res.status,
                    "T_end": Th,
                    "T_err": (Th - T_ref) / T_ref,
                    "t1": res.first_contact_time(),
                    "t1_err_steps": (res.first_contact_time() - t1_ref) / h,
                    "cpu": cpu,
                }
            )
            log(f"accuracy {name} h={h:g}: T={Th:.6g} ({rows[-1]['T_err']:+.2%}) {cpu:.2f} s")
    return {
        "t_end": T,
        "reference": [{"h": h, "T_end": Tr, "t1": t1, "cpu": c} for h, Tr, t1, c in refs],
        "reference_spread": abs(refs[0][1] - refs[-1][1]) / abs(T_ref),
        "rows": rows,
    }


def work_precision(cfg, log) -> dict:
    """Error against CPU on the paper case over ``t_wp``."""
    model, T = C.paper_model(), cfg["t_wp"]
    ref_res, ref_cpu = _run(lambda: fr.ThetaMethod(model, cfg["h_ref"]), T, energy=False)
    ref = C.Measures.of(ref_res, C.PERIOD, T)
    log(f"work-precision reference θ h={cfg['h_ref']:g} ({ref_cpu:.1f} s)")
    series = [
        ("θ paper", cfg["theta_h"], lambda h: fr.ThetaMethod(model, h)),
        ("Carpenter", cfg["carpenter_h"], lambda h: fr.Carpenter(model, h)),
        ("exponential", cfg["exp_h"], lambda h: fr.ExponentialMoreau(model, h)),
        (
            "exponential, no events",
            cfg["exp_h"],
            lambda h: fr.ExponentialMoreau(model, h, events=False),
        ),
    ]
    rows = []
    # the same exponential runs without the energy balance (its exact work integrals)
    series.append(("exponential, energy off", cfg["exp_h"], series[2][2]))
    for name, hs, make in series:
        for h in hs:
            energy = name != "exponential, energy off"
            res, cpu = _run(lambda h=h, make=make: make(h), T, energy=energy)
            m = C.Measures.of(res, C.PERIOD, T)
            err = C.compare(m, ref)
            err["u_L2_nodes"] = _nodal_l2(m.t, m.u, ref.t, ref.u)
            rows.append({"method": name, "h": h, "cpu": cpu, "status": res.status, **err})
            log(
                f"wp {name} h={h:g}: u_L2 {err['u_L2']:.3g} nodes {err['u_L2_nodes']:.3g} "
                f"T_end {err['T_end']:.3g} cpu {cpu:.3f}"
            )
    return {"t_end": T, "h_ref": cfg["h_ref"], "ref_cpu": ref_cpu, "rows": rows}


def impact(cfg, log) -> list[dict]:
    """Free bar impact, fixed mesh, several Courant numbers, exact reference."""
    n = cfg["impact_n"]
    model, dx, T = C.impact_model(n), C.LENGTH / n, C.IMPACT_T_END
    rows = []
    for name, make in (
        ("exponential", lambda h: fr.ExponentialMoreau(model, h)),
        ("θ paper", lambda h: fr.ThetaMethod(model, h)),
    ):
        for nu in cfg["impact_nu"]:
            h = nu * dx / C.WAVE_SPEED
            res, cpu = _run(lambda h=h, make=make: make(h), T)
            u = res.signal("tip_displacement")
            err = _nodal_l2(res.t, u, res.t, C.impact_exact_displacement(res.t))
            P = res.impulse.sum()
            rows.append(
                {
                    "method": name,
                    "nu": nu,
                    "h": h,
                    "u_L2_nodes": err,
                    "impulse_err": abs(P - C.EXACT.impulse) / C.EXACT.impulse,
                    "cpu": cpu,
                }
            )
            log(f"impact {name} ν={nu}: u_L2 nodes {err:.3g} impulse {rows[-1]['impulse_err']:.3g}")
    return rows


def blade(cfg, log) -> dict:
    """Reduced twisted NACA blade (scene ``twisted-naca``) against a fine θ step."""
    if not cfg["blade_t"]:
        return {}
    from femrub.app.simulation import Simulation
    from femrub.scene import load_scene

    scene = load_scene("twisted-naca", {"outputs.vtk_stride": 0})
    model, T = frictionless(Simulation.from_scene(scene).model, scene), cfg["blade_t"]
    ref_res, ref_cpu = _run(lambda: fr.ThetaMethod(model, cfg["blade_ref_h"]), T, energy=False)
    t_ref, u_ref = ref_res.t, ref_res.signal("tip_displacement")
    T_ref = ref_res.signals["tip_temperature"][-1, 0]
    log(
        f"blade: {model.n_dofs} reduced dofs, reference θ h={cfg['blade_ref_h']:g} "
        f"({ref_cpu:.1f} s)"
    )
    # θ has no compiled path for this frictionless two-contact model (per-step Python); its
    # compiled friction blocks run the same model with μ = 1e-9 (its best implementation)
    c = model.contact
    blocks = model.with_(contact=replace(c, friction=np.full(c.n, 1e-9)))
    fr.ThetaMethod(blocks, cfg["blade_ref_h"]).run(10 * cfg["blade_ref_h"])  # compile/load
    h_lim = fr.Carpenter(model, 1e-9).stability_limit()
    carpenter_h = tuple(f * h_lim for f in cfg["blade_carpenter_f"])
    log(f"blade: Carpenter stability limit {h_lim:.3g} s")
    runs = (
        ("θ paper", cfg["blade_theta_h"], lambda h: fr.ThetaMethod(model, h)),
        (THETA_BLOCKS, cfg["blade_theta_block_h"], lambda h: fr.ThetaMethod(blocks, h)),
        ("Carpenter", carpenter_h, lambda h: fr.Carpenter(model, h)),
        ("exponential", cfg["blade_exp_h"], lambda h: fr.ExponentialMoreau(model, h)),
    )
    return {
        "n_dofs": model.n_dofs,
        "t_end": T,
        "ref_cpu": ref_cpu,
        "carpenter_limit": h_lim,
        "rows": _blade_rows(runs, T, t_ref, u_ref, T_ref, log),
    }


def blade_friction(cfg, log) -> dict:
    """The reduced twisted NACA blade with its Coulomb friction ("power" heat), every method
    on that model, against a fine θ step (its compiled friction blocks)."""
    if not cfg["blade_t"]:
        return {}
    from femrub.app.simulation import Simulation
    from femrub.scene import load_scene

    scene = load_scene("twisted-naca", {"outputs.vtk_stride": 0})
    model, T = Simulation.from_scene(scene).model, cfg["blade_t"]
    c = model.contact
    ref_res, ref_cpu = _run(lambda: fr.ThetaMethod(model, cfg["blade_ref_h"]), T, energy=False)
    t_ref, u_ref = ref_res.t, ref_res.signal("tip_displacement")
    T_ref = ref_res.signals["tip_temperature"][-1, 0]
    log(f"blade friction: μ = {c.friction}, reference θ ({ref_cpu:.1f} s), T {T_ref:.6g} K")
    h_lim = fr.Carpenter(model, 1e-9).stability_limit()
    runs = (
        ("θ paper", cfg["fric_theta_h"], lambda h: fr.ThetaMethod(model, h)),
        (
            "Carpenter",
            tuple(f * h_lim for f in cfg["blade_carpenter_f"]),
            lambda h: fr.Carpenter(model, h),
        ),
        ("exponential", cfg["fric_exp_h"], lambda h: fr.ExponentialMoreau(model, h)),
    )
    return {
        "n_dofs": model.n_dofs,
        "t_end": T,
        "mu": float(np.max(c.friction)),
        "ref_cpu": ref_cpu,
        "T_ref": float(T_ref),
        "carpenter_limit": h_lim,
        "rows": _blade_rows(runs, T, t_ref, u_ref, T_ref, log),
    }


def _blade_rows(runs, T, t_ref, u_ref, T_ref, log) -> list[dict]:
    """Errors and CPU of ``runs`` ((method, steps, make), ...) against the reference."""
    from femrub.contact.friction import coulomb_check

    rows = []
    for name, hs, make in runs:
        for h in hs:
            res, cpu = _run(lambda h=h, make=make: make(h), T)
            u = res.signal("tip_displacement")
            Th = res.signals["tip_temperature"][-1, 0]
            row = {
                "method": name,
                "h": h,
                "cpu": cpu,
                "status": res.status,
                "u_L2": float(
                    np.sqrt(
                        np.trapezoid((np.interp(t_ref, res.t, u) - u_ref) ** 2, t_ref)
                        / np.trapezoid(u_ref**2, t_ref)
                    )
                ),
                "u_L2_nodes": _nodal_l2(res.t, u, t_ref, u_ref),
                "T_end": abs(Th - T_ref) / abs(T_ref),
                "min_gap": float(res.gap.min()),
                "energy_error": float(res.energy_error()),
                "heat_error": float(res.heat_error()),
            }
            if res.friction_limit is not None and np.any(res.friction_limit > 0):
                ch = coulomb_check(
                    res.force,
                    res.friction_force,
                    res.slip_velocity,
                    res.contact_state,
                    res.friction_limit,
                )
                row["coulomb_direction"] = ch["direction"]
                row["coulomb_sliding"] = ch["slip_equality"]
            rows.append(row)
            log(
                f"blade {name} h={h:g}: u_L2 {row['u_L2']:.3g} T_end {row['T_end']:.3g} "
                f"{cpu:.2f} s {res.status}"
            )
    return rows


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--skip", nargs="*", default=[], help="studies to skip")
    ap.add_argument("--out", type=Path, help="output folder (default docs/performance)")
    args = ap.parse_args(argv)
    cfg = QUICK if args.quick else FULL

    def log(msg):
        print(msg, flush=True)

    doc = {
        "machine": C.machine(),
        "config": {k: list(v) if isinstance(v, tuple) else v for k, v in cfg.items()},
    }
    name = "exponential_quick" if args.quick and args.out is None else "exponential"
    out = (args.out or C.OUT) / name
    old = {}
    if args.skip and out.with_suffix(".json").exists():  # keep the studies not rerun
        old = C.read_json(out.with_suffix(".json"))
        doc = {**{k: v for k, v in old.items() if k in args.skip}, **doc}
        # the 1-minute load (start, end) of the run each kept study was measured in
        kept = old.get("study_load", {})
        doc["study_load"] = {k: v for k, v in kept.items() if k in args.skip and k in doc}
    from femrub.steppers.exponential.kernels import warm_up

    warm_up()  # compiled once per machine (numba's cache): never in a timed run
    for name, fn in (
        ("accuracy", accuracy),
        ("work_precision", work_precision),
        ("impact", impact),
        ("blade", blade),
        ("blade_friction", blade_friction),
        ("floor", floor),
        ("bound", lambda cfg, log: bound(cfg, log, doc)),
    ):
        if name not in args.skip:
            load0 = C.machine()["load_average"]
            with threadpool_limits(limits=1, user_api="blas"):
                doc[name] = fn(cfg, log)
            doc.setdefault("study_load", {})[name] = [load0, C.machine()["load_average"]]
    doc["machine"]["load_average_end"] = C.machine()["load_average"]
    if old and set(doc.get("study_load", {})) <= set(args.skip):
        doc["machine"] = old["machine"]  # nothing measured: the tables are re-rendered only
    out.parent.mkdir(parents=True, exist_ok=True)
    C.write_json(out.with_suffix(".json"), doc)
    out.with_suffix(".md").write_text(markdown(doc))
    out.with_name(out.name + "_section.md").write_text(section(doc) + "\n")
    if "work_precision" in doc:
        plot(doc["work_precision"], out.with_suffix(".png"))
        for level in (0.1, 0.01, 0.001):
            for key in ("u_L2", "u_L2_nodes", "T_end"):
                best = cheapest(doc["work_precision"]["rows"], key, level)
                log(
                    f"≤ {level:g} {key}: "
                    + ", ".join(f"{m} {r['cpu']:.3g} s (h={r['h']:g})" for m, r in best.items())
                )
    return doc


if __name__ == "__main__":
    main()
