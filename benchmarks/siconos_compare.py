"""Per-step cost of femrub against Siconos on a bar impacting a rigid obstacle; paper-case cost.

Same mechanical problem in both codes: a free bar of N nodes (N displacement dofs; lumped
mass, linear elements, 0.3 m, 1 mm², E = 110 GPa, ρ = 4500 kg/m³) moving at 0.1 m/s towards
an obstacle 10 µm away, Newton restitution 0, over 1.5 × (contact start + contact duration),
same step h and step count. Siconos 4.4 (Debian ``python3-siconos``, driven through
``/usr/bin/python3`` in a subprocess): ``LagrangianLinearTIDS`` + ``LagrangianLinearTIR`` +
``NewtonImpactNSL``, ``MoreauJeanOSI(θ = 1/2)``, ``LCP``, ``TimeStepping``; mass and
stiffness stored dense or sparse (``SimpleMatrix(..., SPARSE)``), the faster one is the
reference. femrub: ``ThetaMethod(activation="predicted")`` (the Moreau–Jean rule, γ = 1/2:
the same scheme; the final states agree to round-off) on ``bar_model(clamped=False)``.
Per-step cost = CPU time of the stepping loop / steps, best of several repetitions, setup
(assembly, factorisation) excluded and reported apart.

Also measured: the paper's 1D case (θ-method, h = 1e-4 s, 0.4 s) in a fresh process and the
whole ``femrub paper`` command: wall time and peak resident memory.

Writes ``docs/performance/siconos.{md,json}`` and ``siconos.png``. Siconos absent: its
columns are skipped with a message. Run ``python benchmarks/siconos_compare.py [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import femrub as fr

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

SICONOS_PYTHON = os.environ.get("SICONOS_PYTHON", "/usr/bin/python3")
FULL = {"sizes": {20: 20000, 100: 20000, 1000: 2000, 10000: 50}, "reps": 3, "paper": True}
QUICK = {"sizes": {20: 4000, 100: 2000, 1000: 200}, "reps": 2, "paper": False}
DENSE_SICONOS_MAX = 2000  # dense 10k × 10k: 0.8 GB per matrix and a dense LU per run

SICONOS_SCRIPT = r"""
import json, sys, time
import numpy as np
import siconos.kernel as sk
p = json.loads(sys.argv[1])
N, steps, h, sparse = p["N"], p["steps"], p["h"], p["storage"] == "sparse"
dx = p["L"] / (N - 1); m = p["rho"] * p["A"] * dx; k = p["E"] * p["A"] / dx
best, q = float("inf"), None
for rep in range(p["reps"]):
    s0 = time.process_time()
    if sparse:
        M = sk.SimpleMatrix(N, N, sk.SPARSE, N); K = sk.SimpleMatrix(N, N, sk.SPARSE, 3 * N)
        for j in range(N):
            M.setValue(j, j, m / 2 if j in (0, N - 1) else m)
            K.setValue(j, j, k if j in (0, N - 1) else 2 * k)
            if j + 1 < N:
                K.setValue(j, j + 1, -k); K.setValue(j + 1, j, -k)
        ds = sk.LagrangianLinearTIDS(np.zeros(N), np.full(N, p["v0"]), np.eye(N))
        ds.setMassPtr(M); ds.setKPtr(K)
    else:
        M = np.diag(np.where(np.isin(np.arange(N), (0, N - 1)), m / 2, m))
        K = np.diag(np.where(np.isin(np.arange(N), (0, N - 1)), k, 2 * k))
        K -= k * (np.eye(N, k=1) + np.eye(N, k=-1))
        ds = sk.LagrangianLinearTIDS(np.zeros(N), np.full(N, p["v0"]), M)
        ds.setKPtr(K)
    H = np.zeros((1, N)); H[0, -1] = -1.0
    inter = sk.Interaction(sk.NewtonImpactNSL(0.0), sk.LagrangianLinearTIR(H, np.array([p["gap"]])))
    nsds = sk.NonSmoothDynamicalSystem(0.0, 2 * steps * h)
    nsds.insertDynamicalSystem(ds); nsds.link(inter, ds)
    sim = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, h), sk.MoreauJeanOSI(0.5), sk.LCP())
    sim.initialize()
    c0 = time.process_time(); setup = c0 - s0
    for _ in range(steps):
        sim.computeOneStep(); sim.nextStep()
    best = min(best, (time.process_time() - c0) / steps)
    q = ds.q()
print(json.dumps({"per_step": best, "setup": setup, "tip": float(q[-1])}))
"""


def siconos_available() -> str | None:
    """``None`` if Siconos runs under SICONOS_PYTHON, else the reason it does not."""
    try:
        out = subprocess.run(
            [SICONOS_PYTHON, "-c", "import siconos.kernel"], capture_output=True, text=True
        )
    except OSError as exc:
        return f"{SICONOS_PYTHON} not runnable ({exc})"
    if out.returncode:
        return f"Siconos not installed for {SICONOS_PYTHON} (`apt-get install -y python3-siconos`)"
    return None


def siconos_run(N, steps, h, storage, reps) -> dict:
    """Run the Siconos driver in a subprocess; return per-step CPU (s), setup, tip (m)."""
    p = dict(N=N, steps=steps, h=h, storage=storage, reps=reps, L=C.LENGTH, rho=C.RHO)
    p.update(A=C.AREA, E=C.E, v0=C.V0, gap=C.GAP)
    out = subprocess.run(
        [SICONOS_PYTHON, "-c", SICONOS_SCRIPT, json.dumps(p)], capture_output=True, text=True
    )
    if out.returncode:
        raise RuntimeError(f"siconos failed: {out.stderr.strip()[-400:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


VARIANTS = ("femrub", "femrub, energy on")


def femrub_run(model, h, steps, variant, reps) -> tuple[float, float]:
    """Best per-step CPU (s) of ``reps`` runs, and the final tip displacement (m)."""
    best, tip = math.inf, math.nan
    for _ in range(reps):
        stepper = fr.ThetaMethod(model, h, activation="predicted")
        res = stepper.run(steps * h, energy=variant.endswith("energy on"))
        if res.status != "ok" or res.steps == 0:
            raise RuntimeError(f"femrub run {variant!r} ended {res.status}: {res.message}")
        best = min(best, res.cpu_seconds / res.steps)
        tip = float(res.signal("tip_displacement")[-1])
    return best, tip


def compare_sizes(cfg, log) -> tuple[list[dict], str | None]:
    """One row per (size, code/variant): per-step CPU, setup, nnz, final tip."""
    missing = siconos_available()
    if missing:
        log(f"  Siconos skipped: {missing}")
    rows = []
    for N, steps in cfg["sizes"].items():
        h = C.IMPACT_T_END / steps
        (model, setup, _) = C.timed(C.impact_model, N - 1)
        stepper, fact, _ = C.timed(fr.ThetaMethod, model, h, activation="predicted")
        D = (model.A - 0.5 * h * model.B).tocsr()
        base = {"N": N, "state": model.n_dofs, "steps": steps, "h": h, "nnz_D": D.nnz}
        variants = list(VARIANTS)
        tips = {}
        for v in variants:
            per, tip = femrub_run(model, h, steps, v, cfg["reps"])
            rows.append({**base, "code": "femrub", "variant": v, "per_step": per, "tip": tip})
            rows[-1]["setup"] = setup + fact
            tips[v] = tip
            log(f"  N = {N}: femrub {v}: {1e6 * per:.1f} µs/step")
        if missing:
            continue
        for storage in ("dense", "sparse"):
            if storage == "dense" and N > DENSE_SICONOS_MAX:
                continue
            reps = cfg["reps"] if N <= 100 else 1
            s = siconos_run(N, steps, h, storage, reps)
            dtip = abs(s["tip"] - tips["femrub"]) / abs(tips["femrub"])
            rows.append({**base, "code": "Siconos", "variant": storage, **s, "tip_diff": dtip})
            log(f"  N = {N}: Siconos {storage}: {1e6 * s['per_step']:.1f} µs/step")
    return rows, missing


def ratios(rows) -> list[dict]:
    """Per size: best Siconos per-step cost over femrub's, for each femrub variant."""
    out = []
    for N in dict.fromkeys(r["N"] for r in rows):
        sic = [r["per_step"] for r in rows if r["N"] == N and r["code"] == "Siconos"]
        for r in rows:
            if r["N"] == N and r["code"] == "femrub":
                row = {"N": N, "variant": r["variant"], "femrub_us": 1e6 * r["per_step"]}
                row["us_per_knnz"] = 1e9 * r["per_step"] / r["nnz_D"]
                if sic:
                    row.update(siconos_us=1e6 * min(sic), ratio=min(sic) / r["per_step"])
                out.append(row)
    return out


def paper_costs(log) -> dict:
    """Wall time and peak RSS: paper case (θ, 1e-4 s, 0.4 s) and ``femrub paper``."""
    code = (
        "import json, resource, time; t0 = time.perf_counter(); import femrub as fr\n"
        "m = fr.bar_model(alpha=3.0); t1 = time.perf_counter()\n"
        "r = fr.ThetaMethod(m, 1e-4).run(0.4, limits={'tip_temperature': 1500.0})\n"
        "t2 = time.perf_counter()\n"
        "print(json.dumps({'run_wall': t2 - t1, 'total_wall': t2 - t0, 'cpu': r.cpu_seconds,\n"
        "  'steps': r.steps, 'status': r.status,\n"
        "  'peak_rss_mib': resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))"
    )
    out = json.loads(subprocess.run([sys.executable, "-c", code], capture_output=True).stdout)
    log(f"  paper case h = 1e-4 s: {out}")
    exe = Path(sys.executable).with_name("femrub")
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        proc = subprocess.Popen([str(exe), "paper", "--out", tmp, "-q"])
        _, status, ru = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        runs = json.loads((Path(tmp) / "summary.json").read_text())["runs"]
    whole = {"wall": wall, "cpu": ru.ru_utime + ru.ru_stime, "peak_rss_mib": ru.ru_maxrss / 1024}
    whole.update(exit_status=status, runs=len(runs))
    log(f"  femrub paper: {whole}")
    return {"paper_case": out, "femrub_paper": whole}


def plot(rows, path: Path) -> None:
    """Per-step CPU against nnz of the iteration matrix, femrub and Siconos."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for code, variant in dict.fromkeys((r["code"], r["variant"]) for r in rows):
        pts = sorted(
            (r["nnz_D"], r["per_step"])
            for r in rows
            if (r["code"], r["variant"]) == (code, variant)
        )
        x, y = np.array(pts).T
        ax.loglog(x, 1e6 * y, "o-" if code == "femrub" else "s--", label=f"{code}: {variant}")
    x = np.array(sorted({r["nnz_D"] for r in rows}), dtype=float)
    ax.loglog(x, 1e6 * 5e-9 * x, "k:", lw=1, label="slope 1 (5 ns per nonzero)")
    ax.set_xlabel("nonzeros of the iteration matrix D = A − hγB (femrub)")
    ax.set_ylabel("CPU per step (µs)")
    ax.set_title("Bar impacting a rigid obstacle: cost per step")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def report(rows, rats, missing, costs) -> str:
    cols = [("N", "N (nodes)"), ("state", "femrub state"), ("nnz_D", "nnz D"), ("steps", "steps")]
    cols += [("code", "code"), ("variant", "variant"), ("per_step_us", "CPU/step (µs)")]
    cols += [("setup", "setup (s)"), ("tip_diff", "tip vs femrub")]
    for r in rows:
        r["per_step_us"] = 1e6 * r["per_step"]
    rcols = [("N", "N"), ("variant", "femrub variant"), ("femrub_us", "femrub µs/step")]
    rcols += [("siconos_us", "best Siconos µs/step"), ("ratio", "Siconos / femrub")]
    rcols += [("us_per_knnz", "femrub µs per 1000 nnz")]
    parts = ["# femrub vs Siconos: measured per-step cost"]
    if missing:
        parts.append(f"**Siconos skipped:** {missing}.")
    parts += ["## Ratios\n\n" + C.md_table(rats, rcols), "## All runs\n\n" + C.md_table(rows, cols)]
    if costs:
        p, w = costs["paper_case"], costs["femrub_paper"]
        parts.append(
            "## Paper case and `femrub paper`\n\n"
            f"Paper case (θ-method, h = 1e-4 s, 0.4 s, {p['steps']} steps, energy balance on), "
            f"fresh process: run {p['run_wall']:.2f} s wall ({p['cpu']:.2f} s CPU), "
            f"{p['total_wall']:.2f} s with imports and assembly, peak RSS "
            f"{p['peak_rss_mib']:.0f} MiB.\n\n"
            f"`femrub paper` ({w['runs']} figure rows): {w['wall']:.1f} s wall, "
            f"{w['cpu']:.1f} s CPU, peak RSS {w['peak_rss_mib']:.0f} MiB."
        )
    return "\n\n".join(parts)


def run_study(cfg, out: Path, log=print) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    rows, missing = compare_sizes(cfg, log)
    rats = ratios(rows)
    costs = paper_costs(log) if cfg["paper"] else {}
    (out / "siconos.md").write_text(report(rows, rats, missing, costs) + "\n")
    doc = {"settings": {"sizes": list(cfg["sizes"].items()), "reps": cfg["reps"]}}
    doc.update(machine=C.machine(), siconos_missing=missing, rows=rows, ratios=rats, costs=costs)
    C.write_json(out / "siconos.json", doc)
    plot(rows, out / "siconos.png")
    return doc


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, no paper-case timing")
    ap.add_argument("--out", type=Path, default=C.OUT, help="output folder")
    args = ap.parse_args(argv)
    run_study(QUICK if args.quick else FULL, args.out)
    print(f"wrote {args.out}/siconos.md")


if __name__ == "__main__":
    main()
