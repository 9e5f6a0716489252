"""Rotor 37 reduced model against 2x and 4x larger reduced models.

``python benchmarks/reduction_convergence_3d.py --rotor37 [--scene NAME] [--set K=V]``
(run it under ``flock /tmp/femrub-heavy.lock``). The full Rotor 37 model (194,276 state
dofs) cannot be stepped on a 2-core / 24 GB machine (factorising its iteration matrix took
more than 13 GB and 13 min, docs/reduction_3d.md), so the scene's reduced model is judged
against reduced models 2x and 4x larger, all sub-bases of one reductor built at the 4x
sizes with the scene's projection and thermal reduction. The full model is built without a
stepper (:func:`femrub.app.simulation.build` with ``stepper=False``), through the model
cache. Every model is stepped over one lobe passage (``t_end = 2π / (2 Ω)``, or the
``scheme.t_end`` given with ``--set``) with the
scene's scheme and step; differences (:func:`femrub.reduction.estimate.compare`, fields
reconstructed on the mesh ``y = R X̄``) of the default and 2x models to the 4x one, and of
the default to the 2x one: convergence shows as ``‖2x − 4x‖ ≪ ‖default − 4x‖``. The
largest model is also stepped with its initial displacement perturbed by
:data:`~femrub.reduction.estimate.PERTURBATION` (``estimate.twin``): the difference of these
twins is the sensitivity of the nonsmooth response, the floor below which no two models can
be told apart; and at half the step (signals of every other step, impulses summed): the
time-discretisation error of the largest model, for scale.
"""

from __future__ import annotations

import math
import os
import resource
import time

import numpy as np

from femrub.analysis import make_stepper
from femrub.analysis.reduction_check import lobe_passage, twin
from femrub.analysis.step_check import coarsen
from femrub.app.cache import ModelCache
from femrub.app.cli import _changes
from femrub.app.scheme import bare_stepper, scheme_options
from femrub.app.simulation import build
from femrub.reduction import ThermoelasticCraigBampton
from femrub.reduction.estimate import PERTURBATION, compare, field_norms
from femrub.scene.scene import load_scene

#: stored states per run (fields are compared at these times)
STORED = 50
#: size factors of the models compared (1 = the scene's sizes; ``--factors``)
FACTORS = (1, 2, 4)


def _peak_gib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def measure(name: str, sets: list[str], factors=FACTORS, log=print) -> dict:
    """Step the scene's reduced model and its enlargements by ``factors``; the differences of
    every pair (``runs[i]["vs"][j]``: model ``i`` against the larger model ``j``)."""
    changes = {"outputs.vtk_stride": 0, **_changes(type("A", (), {"set": sets}))}
    scene = load_scene(name, changes)
    if scene["reduction"]["method"] != "craig-bampton":
        raise SystemExit(f"{name}: reduction.method must be 'craig-bampton' (fixed sizes)")
    h = scene["scheme"]["h"]
    window = max(1, round(lobe_passage(scene) / h)) * h  # a whole number of steps
    if "scheme.t_end" not in changes:
        scene = load_scene(name, {**changes, "scheme.t_end": window})
    t_end, opts = scene["scheme"]["t_end"], scene["reduction"]
    base = (opts["n_uv"], opts["n_theta"])
    sizes = [(f * base[0], f * base[1]) for f in factors]
    load0 = os.getloadavg()
    t0 = time.perf_counter()
    bare = {k: v for k, v in changes.items() if not k.startswith("reduction.")}
    fsim = build(
        load_scene(  # the full model only assembled: no time-step check, no stepper
            name,
            {**bare, "scheme.t_end": t_end, "reduction.method": "none", "scheme.step_check": False},
        ),
        cache=ModelCache(),
        stepper=False,
        log=log,
    )
    full = fsim.model
    t_full = time.perf_counter() - t0
    log(f"full model {full.n_dofs} state dofs built in {t_full:.0f} s; reductor at {sizes[-1]}")
    t0, c0 = time.perf_counter(), time.process_time()
    red = ThermoelasticCraigBampton(
        full, *sizes[-1], projection=opts["projection"], thermal=opts["thermal"]
    )
    red.solver.free()
    t_red, c_red = time.perf_counter() - t0, time.process_time() - c0
    log(f"reductor built in {t_red:.0f} s (CPU {c_red:.0f} s), peak {_peak_gib():.1f} GiB")
    norms = field_norms(full)
    runs = []
    for s in sizes:
        model = red.reduce(*s)
        st = bare_stepper(scene, model)
        c0 = time.process_time()
        res = st.run(t_end, store_every=max(1, st.steps_to(t_end) // STORED))
        cpu = time.process_time() - c0
        X = red.reconstruct(res.states, *s)
        tmin = float(X[:, full.layout.t].min()) if full.layout.n_t else 0.0
        impulse = float(np.abs(res.impulse).sum())
        runs.append(
            dict(
                sizes=s,
                n=model.n_dofs,
                n_bt=model.info["n_boundary_theta"],
                res=res,
                X=X,
                cpu=cpu,
                tmin=tmin,
                energy=res.energy_error(),
                heat=res.heat_error(),
                status=res.status,
                impulse=impulse,
            )
        )
        log(f"{s}: {model.n_dofs} dofs stepped in {cpu:.1f} s CPU, status {res.status}")
    diff = lambda a, b: compare(a["res"], b["res"], a["X"], b["X"], norms, window)  # noqa: E731
    for i, r in enumerate(runs):
        r["factor"] = factors[i]
        r["vs"] = {j: diff(r, runs[j]) for j in range(i + 1, len(runs))}
    # the noise floor: the largest model against itself with u0 perturbed by 1e-15 m
    tw = twin(red, sizes[-1], lambda m: bare_stepper(scene, m), t_end, checkpoints=STORED)
    twin_diff = compare(tw[0], runs[-1]["res"], tw[1], runs[-1]["X"], norms, window)
    log(f"twin of {sizes[-1]} stepped")
    # the time-step floor: the largest model at h / 2 against itself at h
    s = scene["scheme"]
    st = make_stepper(s["name"], red.reduce(*sizes[-1]), s["h"] / 2, **scheme_options(scene))
    half = st.run(t_end, store_every=2 * max(1, st.steps_to(t_end) // (2 * STORED)))
    Xh = red.reconstruct(half.states, *sizes[-1])
    half_diff = compare(runs[-1]["res"], coarsen(half, 2), runs[-1]["X"], Xh, norms, window)
    log(f"{sizes[-1]} at h/2 stepped")
    for r in runs:
        r.pop("X")
    return dict(
        scene=name,
        sets=sets,
        t_end=t_end,
        revolutions=t_end * scene["loads"]["rotation_speed"] / (2 * math.pi),
        h=scene["scheme"]["h"],
        window=window,
        n_full=full.n_dofs,
        n_contacts=full.n_contacts,
        runs=runs,
        twin=twin_diff,
        half=half_diff,
        projection=opts["projection"],
        thermal=opts["thermal"],
        conduction=getattr(full.blocks, "info", {}).get("conduction", "?"),
        times=dict(full=t_full, reductor=t_red, reductor_cpu=c_red),
        peak=_peak_gib(),
        load=(load0, os.getloadavg()),
    )


ROWS = (
    ("contact force impulse per lobe passage", "contact_force"),
    ("contact temperature history", "contact_temperature"),
    ("displacement field, max over t (L2_M)", "displacement"),
    ("displacement field at t_end (L2_M)", "displacement_end"),
    ("temperature field, max over t (L2_C)", "temperature"),
    ("temperature field at t_end (L2_C)", "temperature_end"),
)


def _name(run) -> str:
    return "default" if run["factor"] == 1 else f"{run['factor']}×"


def table(r: dict) -> str:
    pct = lambda x: "–" if x is None else f"{100 * x:.2f} %"  # noqa: E731
    runs = r["runs"]
    f = lambda s: f"({s[0]}, {s[1]})"  # noqa: E731
    pairs = sorted(
        ((i, j) for i in range(len(runs)) for j in runs[i]["vs"]), key=lambda p: (-p[1], p[0])
    )
    t, ld = r["times"], r["load"]
    big = runs[-1]
    others = ", ".join(f"{f(x['sizes'])} ({_name(x)})" for x in runs[1:])
    lines = [
        f"### {r['scene']}: default reduction vs "
        + " and ".join(", ".join(_name(x) for x in runs[1:]).rsplit(", ", 1))
        + " reduced models",
        "",
        "`flock /tmp/femrub-heavy.lock python benchmarks/reduction_convergence_3d.py --rotor37"
        + "".join(f" --set {s}" for s in r["sets"])
        + (
            ""
            if tuple(x["factor"] for x in runs) == FACTORS
            else " --factors " + ",".join(str(x["factor"]) for x in runs)
        )
        + f"`: built-in `{r['scene']}` (projection `{r['projection']}`, thermal "
        f"`{r['thermal']}`, conduction `{r['conduction']}`), t_end = {r['t_end']:.4g} s "
        f"({r['revolutions']:.3g} revolutions), h = {r['h']:g} s. The full model "
        f"({r['n_full']} state dofs, "
        f"{r['n_contacts']} contacts) cannot be stepped on this machine, so the default sizes "
        f"{f(runs[0]['sizes'])} are compared with {others}, sub-bases of one reductor built at "
        f"the {_name(big)} sizes ({t['reductor']:.0f} s wall, {t['reductor_cpu']:.0f} s CPU; "
        f"full model assembly {t['full']:.0f} s; process peak {r['peak']:.1f} GiB); load "
        f"average {ld[0][0]:.1f} → {ld[1][0]:.1f} (2 cores).",
        "",
        "| quantity | "
        + " | ".join(f"{_name(runs[i])} vs {_name(runs[j])}" for i, j in pairs)
        + f" | {_name(big)} vs its twin (u0 + {PERTURBATION:g} m) | {_name(big)} at h vs h/2 |",
        "|---|" + "---|" * (len(pairs) + 2),
    ]
    for label, k in ROWS:
        cells = " | ".join(pct(runs[i]["vs"][j].get(k)) for i, j in pairs)
        lines.append(f"| {label} | {cells} | {pct(r['twin'].get(k))} | {pct(r['half'].get(k))} |")
    lines += [
        "",
        "| model | (n_uv, n_θ) | reduced dofs | θ boundary coords | total contact impulse (N s) "
        "| energy bal. | heat bal. | T min (K) | CPU (s) | status |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for x in runs:
        lines.append(
            f"| {_name(x)} | {f(x['sizes'])} | {x['n']} | {x['n_bt']} | {x['impulse']:.4g} | "
            f"{x['energy']:.1e} | {x['heat']:.1e} | {x['tmin']:.3f} | {x['cpu']:.1f} | "
            f"{x['status']} |"
        )
    return "\n".join(lines) + "\n"


def run_rotor37(name, sets, doc, write_section, factors=FACTORS):
    """Measure, print and write the subsection into ``doc`` (``write_section``)."""
    r = measure(name, sets, factors)
    text = table(r)
    print(text)
    write_section(doc, {"heading": f"### {name}: default reduction vs 2×"}, text)
    return r
