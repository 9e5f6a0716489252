"""Convergence of the reduced 3D rub models against the full model.

For the built-in ``twisted-naca`` scene the full model is stepped once (states stored at
checkpoints), then one reductor is built at the largest sizes and its sub-basis models of
growing sizes are stepped with the same scheme and step. For each size: relative error of
the contact impulse per lobe passage, of the contact temperature history, of the
displacement and temperature fields (mass / heat-capacity weighted L2 over the blade,
largest over the checkpoints, and at the final time), the energy and heat balance residuals,
the lowest temperature reached, the hierarchical estimate of
:mod:`femrub.reduction.estimate` (against the largest model) and the CPU times.

``python benchmarks/reduction_convergence_3d.py [--quick]`` keeps its table with where it was
measured in ``docs/performance/reduction_3d.json`` and renders it between the
``reduction_3d_<study>`` markers of ``docs/reduction_3d.md`` (one study per scene and kind),
with a plot ``docs/reduction_3d_<scene>.png``; ``--render-only`` renders the page from the
JSON without running anything.

``--default`` instead runs the scene as ``femrub run`` does (default reduction: ``auto``
sizes, its estimate and verdict) and the same scene with ``reduction.method = "none"``,
and writes the acceptance numbers (final temperature and displacement fields,
contact temperature history, balances, lowest temperature) into the subsection
"default reduction vs full" (:mod:`default_vs_full`). ``--scene NAME`` and ``--set
KEY=VALUE`` choose the scene (default ``twisted-naca``; ``rotor37-thermal`` with
``--set scheme.t_end=2.3e-3`` for one lobe passage).

``--rotor37`` (``--scene``, default ``rotor37-thermal``; run it under ``flock
/tmp/femrub-heavy.lock``): the full Rotor 37 model cannot be stepped on a 2-core / 24 GB
machine, so the scene's reduced model is compared over one lobe passage with reduced models
2x and 4x larger, sub-bases of one reductor (:mod:`reduction_rotor37`); subsection
"default reduction vs 2× and 4× reduced models".
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numpy as np
from _common import (
    command_line,
    machine,
    read_json,
    render_sections,
    stamped_sections,
    store_section,
)

from femrub.analysis.reduction_check import lobe_passage
from femrub.app.simulation import build
from femrub.reduction import PROJECTIONS, ThermoelasticCraigBampton
from femrub.reduction.estimate import compare, field_norms
from femrub.scene.scene import load_scene

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGE = DOCS / "reduction_3d.md"
STORE = DOCS / "performance" / "reduction_3d.json"


def study(name, changes, sizes, thermal, every, projection="static-mass"):
    scene = load_scene(name, {"reduction.method": "none", "outputs.vtk_stride": 0, **changes})
    sim = build(scene)
    full, t_end = sim.model, scene["scheme"]["t_end"]
    make = lambda m: sim.stepper.__class__(m, sim.stepper.h, **_opts(sim))  # noqa: E731
    t0 = time.process_time()
    ref = sim.stepper.run(t_end, store_every=every)
    cpu_full = time.process_time() - t0
    window = lobe_passage(scene)
    norms = field_norms(full)
    most = (max(s[0] for s in sizes), max(s[1] for s in sizes))
    t0 = time.process_time()
    red = ThermoelasticCraigBampton(full, *most, thermal=thermal, projection=projection)
    cpu_red = time.process_time() - t0
    rows, big = [], None
    for n_uv, n_t in sizes:
        model = red.reduce(n_uv, n_t)
        t0 = time.process_time()
        res = make(model).run(t_end, store_every=every)
        cpu = time.process_time() - t0
        X = red.reconstruct(res.states, n_uv, n_t)
        if (n_uv, n_t) == most:
            big = (res, X)
        e = compare(res, ref, X, ref.states, norms, window)
        fin = compare(res, ref, X[-1:], ref.states[len(X) - 1 : len(X)], norms, window)
        tmin = float(X[:, full.layout.t].min()) if full.layout.n_t else 0.0
        rows.append(
            dict(
                n_uv=n_uv,
                n_theta=n_t,
                n=model.n_dofs,
                n_bt=model.info["n_boundary_theta"],
                err=e,
                u_end=fin["displacement"],
                t_end=fin.get("temperature", 0.0),
                energy=res.energy_error(),
                heat=res.heat_error(),
                tmin=tmin,
                status=res.status,
                cpu=cpu,
                res=res,
                X=X,
            )
        )
    for r in rows:
        r["est"] = compare(r["res"], big[0], r["X"], big[1], norms, window)
    return dict(
        scene=name,
        full=ref,
        cpu_full=cpu_full,
        cpu_reductor=cpu_red,
        rows=rows,
        window=window,
        n_full=full.n_dofs,
        t_end=t_end,
        thermal=thermal,
        projection=projection,
        full_energy=ref.energy_error(),
        full_heat=ref.heat_error(),
    )


def _heading(st) -> str:
    return (
        f"### {st['scene']} (thermal reduction `{st['thermal']}`, projection "
        f"`{st.get('projection', 'petrov-galerkin')}`)"
    )


def _opts(sim):
    from femrub.app.scheme import scheme_options

    return {k: v for k, v in scheme_options(sim.scene).items() if v is not None}


def table(st) -> str:
    pct = lambda x: f"{100 * x:.2f} %"  # noqa: E731
    lines = [
        _heading(st),
        "",
        f"Full model {st['n_full']} state dofs, t_end = {st['t_end']:g} s, lobe passage "
        f"{st['window']:.3g} s; full run CPU {st['cpu_full']:.1f} s, energy balance "
        f"{st['full_energy']:.1e}, heat balance {st['full_heat']:.1e}; reductor (largest "
        f"sizes) CPU {st['cpu_reductor']:.1f} s.",
        "",
        "| n_uv | n_θ | dofs | θ boundary coords | impulse/passage | T contact | u (max over t) | "
        "θ (max over t) | u end | θ end | energy bal. | heat bal. | T min (K) | "
        "estimate vs largest (force / T / u) | CPU (s) | status |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in st["rows"]:
        e, s = r["err"], r["est"]
        lines.append(
            f"| {r['n_uv']} | {r['n_theta']} | {r['n']} | {r['n_bt']} | {pct(e['contact_force'])} "
            f"| {pct(e['contact_temperature'])} | {pct(e['displacement'])} | "
            f"{pct(e.get('temperature', 0))} | {pct(r['u_end'])} | {pct(r['t_end'])} | "
            f"{pct(r['energy'])} | {pct(r['heat'])} | {r['tmin']:.2f} | "
            f"{pct(s['contact_force'])} / {pct(s['contact_temperature'])} / "
            f"{pct(s['displacement'])} | {r['cpu']:.2f} | {r['status']} |"
        )
    return "\n".join(lines) + "\n"


def plot(st, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    n = [r["n"] for r in st["rows"]]
    for k in ("contact_force", "contact_temperature", "displacement", "temperature"):
        ax[0].semilogy(n, [max(r["err"].get(k, np.nan), 1e-6) for r in st["rows"]], "o-", label=k)
    ax[0].semilogy(n, [max(r["energy"], 1e-9) for r in st["rows"]], "k--", label="energy bal.")
    ax[0].semilogy(n, [max(r["heat"], 1e-9) for r in st["rows"]], "k:", label="heat bal.")
    ax[0].axhline(0.05, color="r", lw=0.8)
    ax[0].set(xlabel="reduced state dofs", ylabel="relative error vs full", title=st["scene"])
    ax[0].legend(fontsize=7)
    f = st["full"]
    key = "contact_temperature" if "contact_temperature" in f.signals else "tip_temperature"
    ax[1].plot(f.t, f.signals[key].max(axis=1), "k", lw=2, label="full")
    for r in st["rows"]:
        ax[1].plot(
            r["res"].t,
            r["res"].signals[key].max(axis=1),
            lw=0.8,
            label=f"({r['n_uv']}, {r['n_theta']})",
        )
    ax[1].set(xlabel="t (s)", ylabel="hottest contact temperature rise (K)")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rotor37", action="store_true")
    ap.add_argument("--factors", default="1,2,4", help="--rotor37: size factors compared")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--thermal", default="inputs", choices=("inputs", "boundary"))
    ap.add_argument("--projection", default="static-mass", choices=PROJECTIONS)
    ap.add_argument("--default", action="store_true", help="default reduction vs full model")
    ap.add_argument("--scene", default="twisted-naca")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--render-only", action="store_true", help="render the page from the JSON")
    a = ap.parse_args(argv)
    if a.render_only:
        render_sections(PAGE, stamped_sections(read_json(STORE), "reduction_3d"))
        return 0
    write_section = section_writer(command_line("reduction_convergence_3d.py", argv))
    if a.default:
        from default_vs_full import run_default

        return run_default(a.scene, a.set, DOCS / "reduction_3d.md", write_section)
    if a.rotor37:  # the full model cannot be stepped: against 2x and 4x reduced models
        from reduction_rotor37 import run_rotor37

        scene = "rotor37-thermal" if a.scene == "twisted-naca" else a.scene
        factors = tuple(int(x) for x in a.factors.split(","))
        return run_rotor37(scene, a.set, DOCS / "reduction_3d.md", write_section, factors)
    name, changes = "twisted-naca", {}
    sizes = [(4, 4), (8, 8), (16, 16), (40, 40), (80, 80), (160, 80)]
    if a.quick:
        changes["scheme.t_end"] = 0.002
        sizes = sizes[1:4]
    every = 500
    st = study(name, changes, sizes, a.thermal, every, a.projection)
    text = table(st)
    print(text)
    if not a.quick:
        png = DOCS / f"reduction_3d_{name}_{a.thermal}_{a.projection}.png"
        plot(st, png)
        write_section(DOCS / "reduction_3d.md", st, text + f"\n![{name}]({png.name})\n")
    return st


def section_writer(command: str):
    """``write_section(path, st, text)`` that keeps ``text`` in :data:`STORE` under the key
    of ``st`` (its ``key``, or the slug of its heading) with ``command`` and the machine as it
    was when the writer was made, and renders the page."""
    where = machine()

    def write_section(path: Path, st, text: str) -> None:
        key = st.get("key") or re.sub(
            r"[^a-z0-9]+", "-", (st.get("heading") or _heading(st)).lower()
        )
        entry = {"command": command, "machine": where, "text": text}
        store_section(STORE, path, "reduction_3d", key.strip("-"), entry)

    return write_section


if __name__ == "__main__":
    sys.exit(main() and 0)
