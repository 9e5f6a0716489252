"""A scene reduced with its default settings against the same scene unreduced.

``python benchmarks/reduction_convergence_3d.py --default [--scene NAME] [--set K=V]``
builds the scene exactly as ``femrub run`` does (its reduction, with ``auto`` sizes, the
error estimate and its verdict), steps it, then builds and steps the same scene with
``reduction.method = "none"`` (same mesh, same step). Relative errors of the reduced model
reconstructed on the mesh, ``y = R X̄``:

* final fields: ``‖Δu(t_end)‖_M / ‖u_full(t_end)‖_M`` and ``‖Δθ(t_end)‖_C / ‖θ_full(t_end)‖_C``
  (mass / heat-capacity weighted L2 over the blade), and the largest over the stored times
  relative to the largest norm;
* contact temperature history ``max_t ‖ΔT_c‖_∞ / max_t ‖T_c,full‖_∞`` and contact impulse
  per lobe passage (:func:`femrub.reduction.estimate.compare`);
* energy and heat balance residuals of both runs, the lowest temperature of both.
"""

from __future__ import annotations

import os
import time

from femrub.analysis.reduction_check import lobe_passage, reduce_checked
from femrub.app.cli import _changes
from femrub.app.scheme import bare_stepper
from femrub.app.simulation import build
from femrub.reduction.estimate import QUANTITIES, compare, field_norms
from femrub.scene.scene import load_scene

#: stored states per run (fields and lowest temperature are judged at these times)
STORED = 100


def _run(st, t_end):
    every = max(1, st.steps_to(t_end) // STORED)
    t0, c0 = time.perf_counter(), time.process_time()
    res = st.run(t_end, store_every=every)
    return res, time.perf_counter() - t0, time.process_time() - c0


def measure(name: str, sets: list[str]) -> dict:
    """Run ``name`` with its defaults and unreduced; return the numbers (module docstring).

    The full model is assembled once (``reduction.method = "none"``) and reduced as
    ``femrub run`` reduces it (:func:`~femrub.analysis.reduction_check.reduce_checked` with
    the scene's stepper for the estimate).
    """
    changes = {"outputs.vtk_stride": 0, **_changes(type("A", (), {"set": sets}))}
    scene = load_scene(name, changes)
    t_end = scene["scheme"]["t_end"]
    load0 = os.getloadavg()
    t0 = time.perf_counter()
    fsim = build(load_scene(name, {**changes, "reduction.method": "none"}))
    t_build_full = time.perf_counter() - t0
    t0 = time.perf_counter()
    make = lambda m: bare_stepper(scene, m)  # noqa: E731
    model, red, rep = reduce_checked(fsim.model, scene, make_stepper=make)
    t_build_red = time.perf_counter() - t0
    res_r, wall_r, cpu_r = _run(make(model), t_end)
    info = model.info
    Xr = red.reconstruct(res_r.states, info["n_uv"], info["n_theta"])
    sizes = (info["n_uv"], info["n_theta"])
    del model, red
    res_f, wall_f, cpu_f = _run(fsim.stepper, t_end)
    full = fsim.full
    norms = field_norms(full)
    m = min(len(Xr), len(res_f.states))
    Xf = res_f.states[:m]
    errs = compare(res_r, res_f, Xr[:m], Xf, norms, lobe_passage(scene))
    L = full.layout
    tmin = lambda X: float(X[:, L.t].min()) if L.n_t else 0.0  # noqa: E731
    est = rep.get("error", {})
    return dict(
        scene=name,
        sets=sets,
        t_end=t_end,
        h=scene["scheme"]["h"],
        n_full=full.n_dofs,
        sizes=sizes,
        n_reduced=res_r.states.shape[1],
        n_boundary_theta=rep.get("n_boundary_theta"),
        n_contacts=full.n_contacts,
        thermal=rep.get("thermal"),
        errors=errs,
        energy=(res_r.energy_error(), res_f.energy_error()),
        heat=(res_r.heat_error(), res_f.heat_error()),
        tmin=(tmin(Xr), tmin(Xf)),
        status=(res_r.status, res_f.status),
        estimate=est.get("estimate"),
        estimate_detail={k: est.get(k) for k in QUANTITIES},
        verdict="inaccurate"
        if (est.get("estimate") or 0) > scene["reduction"]["tolerance"]
        else res_r.status,
        times=dict(
            build_reduced=t_build_red,
            run_reduced=wall_r,
            cpu_reduced=cpu_r,
            build_full=t_build_full,
            run_full=wall_f,
            cpu_full=cpu_f,
        ),
        load=(load0, os.getloadavg()),
        stored=m,
    )


def table(r: dict) -> str:
    pct = lambda x: "–" if x is None else f"{100 * x:.2f} %"  # noqa: E731
    e = r["errors"]
    ok = lambda x, lim=0.05: "✔" if x is not None and x <= lim else "✘"  # noqa: E731
    setx = (" with " + ", ".join(f"`{s}`" for s in r["sets"])) if r["sets"] else ""
    t, ld = r["times"], r["load"]
    rows = [
        ("final temperature field (L2_C)", e.get("temperature_end"), 0.05),
        ("final displacement field (L2_M)", e.get("displacement_end"), 0.05),
        ("contact temperature history", e.get("contact_temperature"), 0.05),
        ("temperature field, max over t", e.get("temperature"), None),
        ("displacement field, max over t", e.get("displacement"), None),
        ("contact impulse per lobe passage", e.get("contact_force"), None),
        ("energy balance (reduced / full)", r["energy"][0], 0.01),
        ("heat balance (reduced / full)", r["heat"][0], 0.01),
    ]
    lines = [
        f"### {r['scene']}: default reduction vs full",
        "",
        f"`python benchmarks/reduction_convergence_3d.py --default --scene {r['scene']}"
        + "".join(f" --set {s}" for s in r["sets"])
        + f"`: built-in `{r['scene']}`{setx}, h = {r['h']:g} s, t_end = {r['t_end']:g} s; "
        f"full model {r['n_full']} state dofs; default reduction: sizes (n_uv, n_θ) = "
        f"{tuple(r['sizes'])}, {r['n_reduced']} dofs, {r['n_boundary_theta']} thermal "
        f"boundary coordinates for {r['n_contacts']} contacts (thermal `{r['thermal']}`); "
        f"estimate {pct(r['estimate'])} → status `{r['verdict']}`. Fields compared at "
        f"{r['stored']} stored times. Wall time: full build {t['build_full']:.0f} s, "
        f"reduction (incl. estimate) {t['build_reduced']:.0f} s, reduced run "
        f"{t['run_reduced']:.1f} s, full run {t['run_full']:.0f} s (CPU {t['cpu_full']:.0f} s); "
        f"load average {ld[0][0]:.1f} → {ld[1][0]:.1f} (2 cores).",
        "",
        "| quantity | reduced vs full | bar | |",
        "|---|---|---|---|",
    ]
    for label, x, lim in rows:
        extra = ""
        if "balance" in label:
            i = 0 if "energy" in label else 1
            full = r["energy"][1] if i == 0 else r["heat"][1]
            lines.append(f"| {label} | {x:.1e} / {full:.1e} | ≤ 1 % | {ok(x, lim)} |")
            continue
        lines.append(
            f"| {label} | {pct(x)}{extra} | {'≤ 5 %' if lim else ''} | "
            f"{ok(x, lim) if lim else ''} |"
        )
    tr, tf = r["tmin"]
    lines.append(
        f"| lowest temperature (reduced / full) | {tr:.2f} K / {tf:.2f} K | ≥ −0.5 K | "
        f"{ok(-tr, 0.5)} |"
    )
    d = r["estimate_detail"]
    lines += [
        "",
        "Estimate of the run (against the reductor's larger model; force / contact T / u / θ "
        "/ u end / θ end): " + " / ".join(pct(d[k]) for k in QUANTITIES),
    ]
    return "\n".join(lines) + "\n"


def run_default(name, sets, doc, write_section):
    """Measure, print and write the subsection into ``doc`` (``write_section``)."""
    r = measure(name, sets)
    text = table(r)
    print(text)
    key = {"heading": f"### {name}: default reduction vs full"}
    write_section(doc, key, text)
    return r
