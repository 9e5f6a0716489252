"""Accuracy and cost of the thermoelastic Craig–Bampton reduction on the paper case.

Paper case (model notes): 20-node bar, coupled (β = −4.5e-7 m/K), α = 3 m/s, θ-method with
h = 1e-4 s and γ = 1/2 over 0.4 s. For every (n_uv, n_θ) of a grid and every left projection
the reduced model is run and compared with the full model:

* ``T_end``: relative error of the tip temperature at 0.4 s;
* ``F_max``: relative error of the largest contact force;
* ``u_L2``: time-L2 relative error of the tip displacement;
* ``field``: relative L2 error of the temperature along the bar at 0.4 s (reconstructed);
* CPU time of the run (``time.process_time``).

One reductor per projection, built at the largest sizes, gives every reduced model of the
grid (``reduce(n_uv, n_θ)``).

Writes a Markdown report and a PNG (default ``docs/reduction_study.md`` and
``docs/reduction_study.png``). Run ``python benchmarks/reduction_study.py [--quick]``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import femrub as fr
from femrub.cases.paper_models import PAPER_SIZES
from femrub.reduction import PROJECTIONS, ThermoelasticCraigBampton

ALPHA, H, T_END = 3.0, 1e-4, 0.4
GRID_UV = (0, 2, 3, 4, 6, 8, 12, 20, 38)
GRID_T = (1, 2, 3, 5, 8, 12, 16, 19)
QUICK_UV, QUICK_T = (2, 3, 6, 38), (2, 5, 12, 19)


def _run(model, h=H, scheme="theta"):
    n = int(round(T_END / h))
    stepper = fr.ThetaMethod(model, h) if scheme == "theta" else fr.Carpenter(model, h)
    return stepper.run(T_END, energy=False, store_every=n)


def _errors(res, ref, theta, theta_ref):
    tip = "tip_temperature"
    u_ref = ref.signal("tip_displacement")
    u = np.interp(ref.t, res.t, res.signal("tip_displacement"))
    return {
        "T_end": res.signal(tip)[-1] / ref.signal(tip)[-1] - 1.0,
        "F_max": res.force.max() / ref.force.max() - 1.0,
        "u_L2": np.sqrt(np.mean((u - u_ref) ** 2) / np.mean(u_ref**2)),
        "field": np.linalg.norm(theta - theta_ref) / np.linalg.norm(theta_ref),
        "cpu": res.cpu_seconds,
    }


def study(grid_uv, grid_t, projections):
    full = fr.bar_model(alpha=ALPHA)
    ref = _run(full)
    th_ref = ref.states[-1][full.layout.t]
    rows = []
    for projection in projections:  # one reductor per projection, every size from its bases
        red = ThermoelasticCraigBampton(full, max(grid_uv), max(grid_t), projection=projection)
        for n_uv in grid_uv:
            for n_t in grid_t:
                rom = red.reduce(n_uv, n_t)
                res = _run(rom)
                th = red.reconstruct(res.states[-1], n_uv, n_t)[full.layout.t]
                err = _errors(res, ref, th, th_ref)
                err.update(projection=projection, n_uv=n_uv, n_t=n_t, n=rom.n_dofs)
                rows.append(err)
    return full, ref, rows


def paper_models(full, ref, projections):
    """RM1, RM2 and the full basis with both schemes.

    Carpenter runs at h = 1e-5 s (the full model's limit is 2.6e-5 s) and at h = 4e-5 s,
    which the reduced models' larger stability limit allows; both against the full model
    with Carpenter at h = 1e-5 s.
    """
    out = []
    refs = {"theta": ref, "carpenter": _run(full, 1e-5, "carpenter")}
    th_ref = {k: r.states[-1][full.layout.t] for k, r in refs.items()}
    out.append({"model": "full", "projection": "-", "n": full.n_dofs, "scheme": "theta"})
    out[-1].update(_errors(ref, ref, th_ref["theta"], th_ref["theta"]))
    out.append({"model": "full", "projection": "-", "n": full.n_dofs, "scheme": "carpenter"})
    out[-1].update(_errors(refs["carpenter"], refs["carpenter"], *[th_ref["carpenter"]] * 2))
    out[-1]["limit"] = fr.Carpenter(full, 1e-5).stability_limit()
    for projection in projections:
        red = ThermoelasticCraigBampton(full, projection=projection)  # every shape
        for name, (n_uv, n_t) in PAPER_SIZES.items():
            rom = red.reduce(n_uv, n_t)
            runs = [("theta", H), ("carpenter", 1e-5)]
            if name != "full-basis":  # 4e-5 s is above the full model's limit (2.6e-5 s)
                runs.append(("carpenter", 4e-5))
            for scheme, h in runs:
                res = _run(rom, h, scheme)
                th = red.reconstruct(res.states[-1], n_uv, n_t)[full.layout.t]
                label = scheme if h != 4e-5 else "carpenter h = 4e-5"
                row = {"model": name, "projection": projection, "n": rom.n_dofs, "scheme": label}
                row.update(_errors(res, refs[scheme], th, th_ref[scheme]))
                if scheme == "carpenter":
                    row["limit"] = fr.Carpenter(rom, h).stability_limit()
                    row["status"] = res.status
                out.append(row)
    return out


def _pct(x):
    return f"{100 * x:+.1f} %"


def smallest_accurate(rows, projection, tol_t=0.05, tol_f=0.10):
    """Smallest reduced size whose T_end, F_max errors stay within the tolerances."""
    ok = [
        r
        for r in rows
        if r["projection"] == projection and abs(r["T_end"]) < tol_t and abs(r["F_max"]) < tol_f
    ]
    return min(ok, key=lambda r: (r["n"], r["n_t"])) if ok else None


def report(path: Path, rows, models, grid_uv, grid_t, projections, ref) -> None:
    lines = [
        "# Reduction study: paper case (α = 3 m/s, θ-method h = 1e-4 s, 0.4 s)",
        "",
        "Generated by `python benchmarks/reduction_study.py`. Errors are relative to the full "
        f"model (60 dofs): tip temperature at 0.4 s {ref.signal('tip_temperature')[-1]:.2f} K, "
        f"largest contact force {ref.force.max():.2f} N. CPU: `time.process_time` of `run()`.",
        "",
        "## Paper models (RM1: n^uv = 3, n^θ = 12; RM2: 2, 5)",
        "",
        "| model | projection | scheme | dofs | T(0.4 s) | F max | u time-L2 | θ field "
        "| CPU (s) | Carpenter limit (s) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in models:
        lim = f"{r['limit']:.2e}" if "limit" in r else ""
        if r.get("status", "ok") != "ok":
            lim += f" ({r['status']})"
        lines.append(
            f"| {r['model']} | {r['projection']} | {r['scheme']} | {r['n']} | {_pct(r['T_end'])} "
            f"| {_pct(r['F_max'])} | {100 * r['u_L2']:.1f} % | {100 * r['field']:.1f} % "
            f"| {r['cpu']:.2f} | {lim} |"
        )
    for projection in projections:
        sub = {(r["n_uv"], r["n_t"]): r for r in rows if r["projection"] == projection}
        for key, title in (("T_end", "tip temperature at 0.4 s"), ("F_max", "max force")):
            lines += ["", f"## {projection}: error of the {title} (rows n_uv, columns n_θ)", ""]
            lines.append("| n_uv \\ n_θ | " + " | ".join(str(t) for t in grid_t) + " |")
            lines.append("|---" * (len(grid_t) + 1) + "|")
            for n_uv in grid_uv:
                cells = " | ".join(_pct(sub[n_uv, t][key]) for t in grid_t)
                lines.append(f"| {n_uv} | {cells} |")
        lines += ["", f"## {projection}: tip displacement time-L2 / θ field error", ""]
        lines.append("| n_uv \\ n_θ | " + " | ".join(str(t) for t in grid_t) + " |")
        lines.append("|---" * (len(grid_t) + 1) + "|")
        for n_uv in grid_uv:
            cells = " | ".join(
                f"{100 * sub[n_uv, t]['u_L2']:.1f} / {100 * sub[n_uv, t]['field']:.0f} %"
                for t in grid_t
            )
            lines.append(f"| {n_uv} | {cells} |")
        best = smallest_accurate(rows, projection)
        lines += ["", f"Smallest model with |T error| < 5 % and |F error| < 10 % ({projection}): "]
        lines[-1] += (
            "none in the grid."
            if best is None
            else f"n_uv = {best['n_uv']}, n_θ = {best['n_t']} ({best['n']} dofs)."
        )
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def plot(path: Path, rows, grid_uv, grid_t, projections, ref) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(projections) + 1, figsize=(4.2 * (len(projections) + 1), 3.8))
    for ax, projection in zip(axes, projections):
        sub = {(r["n_uv"], r["n_t"]): r for r in rows if r["projection"] == projection}
        E = np.array([[abs(sub[u, t]["T_end"]) for t in grid_t] for u in grid_uv])
        im = ax.imshow(100 * E, origin="lower", cmap="viridis", vmin=0, vmax=100, aspect="auto")
        ax.set_xticks(range(len(grid_t)), [str(t) for t in grid_t])
        ax.set_yticks(range(len(grid_uv)), [str(u) for u in grid_uv])
        ax.set_xlabel("n_θ")
        ax.set_ylabel("n_uv")
        ax.set_title(f"|tip T error| at 0.4 s (%)\n{projection}", fontsize=9)
        for i in range(len(grid_uv)):
            for j in range(len(grid_t)):
                color = "w" if E[i, j] < 0.5 else "k"
                ax.text(j, i, f"{100 * E[i, j]:.0f}", ha="center", va="center", fontsize=6, c=color)
    fig.colorbar(im, ax=axes[len(projections) - 1], shrink=0.8)
    ax = axes[-1]
    for projection in projections:
        sub = [r for r in rows if r["projection"] == projection]
        ax.plot([r["n"] for r in sub], [r["cpu"] for r in sub], "o", ms=3, label=projection)
    ax.axhline(ref.cpu_seconds, color="k", ls="--", label="full model (60 dofs)")
    ax.set_xlabel("reduced size (dofs)")
    ax.set_ylabel("CPU time of the run (s)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7)
    ax.set_title("θ-method, h = 1e-4 s, 0.4 s", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small grid (a few seconds)")
    ap.add_argument("--out", type=Path, default=Path("docs"), help="output folder")
    ap.add_argument("--name", default="reduction_study", help="file stem of the outputs")
    args = ap.parse_args(argv)
    grid_uv, grid_t = (QUICK_UV, QUICK_T) if args.quick else (GRID_UV, GRID_T)
    t0 = time.perf_counter()
    full, ref, rows = study(grid_uv, grid_t, PROJECTIONS)
    models = paper_models(full, ref, PROJECTIONS)
    args.out.mkdir(parents=True, exist_ok=True)
    md, png = args.out / f"{args.name}.md", args.out / f"{args.name}.png"
    report(md, rows, models, grid_uv, grid_t, PROJECTIONS, ref)
    plot(png, rows, grid_uv, grid_t, PROJECTIONS, ref)
    for p in PROJECTIONS:
        best = smallest_accurate(rows, p)
        print(
            f"{p}: smallest accurate model", None if best is None else (best["n_uv"], best["n_t"])
        )
    print(f"wrote {md} and {png} in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
