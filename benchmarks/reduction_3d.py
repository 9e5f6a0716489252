"""Cost of the thermoelastic Craig–Bampton reduction on a 3D cantilever box.

A titanium-like box 100 × 20 × 4 mm (x along the blade), clamped and held at ambient
temperature at x = 0, meshed with scikit-fem ``MeshTet`` (tensor mesh), vector P2
displacements with HRZ-lumped mass, P1 temperatures (row-sum lumped heat capacity), physical
coupling ``K^uθ = −∫ b θ div v``. Contacts: the x-displacement of the tip vertices on the
edge z = H (one contact per vertex, normal +x, gap 0.8 µm), frictional heat α = 3 m/s on
their temperature dofs; an axial tip load ``F0 sin(Ω t)`` shared by the contact vertices.

For each size the reduction (n_uv = 6, n_θ = 12, Petrov–Galerkin) runs in a fresh process:
wall and CPU time of each stage, Python-level peak memory of the reduction (``tracemalloc``)
and peak resident memory of the process (``getrusage``, which also counts SuperLU and
ARPACK). With ``--simulate`` (default for the smallest size) the full and reduced models are
also run with the θ-method (h = 1e-6 s, 2 ms) and compared.

Run ``python benchmarks/reduction_3d.py [--quick]``; keeps the table with where it was
measured in ``docs/performance/reduction_3d.json`` (key ``cost``) and renders it between the
``reduction_3d_cost`` markers of ``docs/reduction_3d.md`` (``--quick``: print only).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import skfem as fem

import femrub as fr

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine, store_section  # noqa: E402

from femrub.model.build import ContactSpec, Load, first_order_model
from femrub.reduction import ThermoelasticCraigBampton

L, W, H = 0.1, 0.02, 0.004  # m
SIZES = {"1e4": (20, 6, 3), "3e4": (28, 9, 4), "1e5": (54, 16, 4)}
QUICK = {"3e3": (10, 4, 2)}
N_UV, N_THETA = 6, 12
ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "reduction_3d.md"
STORE = ROOT / "docs" / "performance" / "reduction_3d.json"
F0, OMEGA, GAP, ALPHA = 100.0, 5000.0, 0.8e-6, 3.0  # N, rad/s, m, m/s


def box_model(nx: int, ny: int, nz: int) -> fr.FirstOrderModel:
    """First-order model of the cantilever box (see module docstring)."""
    mesh = fem.MeshTet.init_tensor(
        np.linspace(0, L, nx + 1), np.linspace(0, W, ny + 1), np.linspace(0, H, nz + 1)
    )
    bu = fem.Basis(mesh, fem.ElementVector(fem.ElementTetP2()))
    bt = bu.with_element(fem.ElementTetP1())
    mat = fr.Material(young=110e9, rho=4500.0, rho_c=4500.0 * 585.0, conductivity=7.0)
    mats = fr.assemble_thermoelastic(
        bu,
        bt,
        mat,
        lumping="hrz",
        heat_lumping="row-sum",
        coupling="physical",
        fixed_u=bu.get_dofs(lambda x: x[0] < 1e-12).all(),
        fixed_t=bt.get_dofs(lambda x: x[0] < 1e-12).all(),
    )
    tipv = np.flatnonzero((np.abs(mesh.p[0] - L) < 1e-12) & (np.abs(mesh.p[2] - H) < 1e-12))
    rows = mats.u_index(bu.nodal_dofs[0, tipv])
    normals = np.zeros((rows.size, mats.n_u))
    normals[np.arange(rows.size), rows] = 1.0
    heat = mats.t_index(bt.nodal_dofs[0, tipv])
    f = np.zeros(mats.n_u)
    f[rows] = F0 / rows.size
    model = first_order_model(
        mats,
        contact=ContactSpec(normals=normals, gap=GAP, heat_dofs=heat, heat_coefficient=ALPHA),
        loads=[Load(f, lambda t: np.sin(OMEGA * t), "u", "tip_force")],
        observe={"tip_displacement": ("u", rows), "tip_temperature": ("theta", heat)},
        info={"n_fe": mats.n_u + mats.n_t, "n_u_fe": mats.n_u, "n_t_fe": mats.n_t},
    )
    return model


def _rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def worker(nx: int, ny: int, nz: int, simulate: bool) -> dict:
    t0, c0 = time.perf_counter(), time.process_time()
    model = box_model(nx, ny, nz)
    out = {
        "mesh": [nx, ny, nz],
        "n_fe": model.info["n_fe"],
        "n_state": model.n_dofs,
        "n_contacts": model.n_contacts,
        "assembly_s": time.perf_counter() - t0,
        "rss_after_assembly_mib": _rss_mib(),
    }
    tracemalloc.start()
    t0, c0 = time.perf_counter(), time.process_time()
    red = ThermoelasticCraigBampton(model, N_UV, N_THETA)
    rom = red.reduce()
    out.update(
        reduction_s=time.perf_counter() - t0,
        reduction_cpu_s=time.process_time() - c0,
        timings=rom.info["timings"],
        tracemalloc_peak_mib=tracemalloc.get_traced_memory()[1] / 2**20,
        rss_peak_mib=_rss_mib(),
        n_reduced=rom.n_dofs,
        omega1=float(np.sqrt(red.omega2[0])),
    )
    tracemalloc.stop()
    if simulate:
        h, t_end = 1e-6, 2e-3
        full_res = fr.ThetaMethod(model, h).run(t_end, energy=False)
        red_res = fr.ThetaMethod(rom, h).run(t_end, energy=False)
        first = lambda res, name: res.signal(name).reshape(len(res.t), -1)[:, 0]  # noqa: E731
        T, Tr = first(full_res, "tip_temperature"), first(red_res, "tip_temperature")
        u, ur = first(full_res, "tip_displacement"), first(red_res, "tip_displacement")
        out["simulation"] = {
            "full_cpu_s": full_res.cpu_seconds,
            "reduced_cpu_s": red_res.cpu_seconds,
            "contact_phases": len(full_res.contact_phases()),
            "T_end_full": float(T[-1]),
            "T_end_error": float(Tr[-1] / T[-1] - 1.0) if T[-1] else float("nan"),
            "F_max_full": float(full_res.force.sum(axis=1).max()),
            "F_max_error": float(red_res.force.sum(axis=1).max() / full_res.force.sum(axis=1).max())
            - 1.0,
            "u_L2_error": float(np.sqrt(np.mean((u - ur) ** 2) / np.mean(u**2))),
        }
    return out


def _table(results: list[dict]) -> str:
    lines = [
        f"Reduction to n_uv = {N_UV}, n_θ = {N_THETA} (Petrov–Galerkin); one fresh process per "
        "size on this machine (2 cores). FE dofs = displacement + temperature dofs; state = "
        "2 n_u + n_θ (first-order).",
        "",
        "| mesh | FE dofs | state dofs | contacts | reduced dofs | assembly (s) | static shapes "
        "(s) | modes (s) | bases + projection (s) | reduction wall / CPU (s) | Python peak "
        "(MiB) | process peak RSS (MiB) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        t = r["timings"]
        lines.append(
            f"| {'×'.join(map(str, r['mesh']))} | {r['n_fe']} | {r['n_state']} "
            f"| {r['n_contacts']} | {r['n_reduced']} | {r['assembly_s']:.1f} "
            f"| {t['static_shapes']:.2f} | {t['modes']:.2f} "
            f"| {t['bases'] + t['projection']:.2f} | {r['reduction_s']:.1f} / "
            f"{r['reduction_cpu_s']:.1f} | {r['tracemalloc_peak_mib']:.0f} "
            f"| {r['rss_peak_mib']:.0f} |"
        )
    sims = [r for r in results if "simulation" in r]
    if sims:
        lines += [
            "",
            "θ-method, h = 1e-6 s over 2 ms, full vs reduced model:",
            "",
            "| FE dofs | contact phases | T tip end (K) | T error | F max error | u time-L2 "
            "| CPU full (s) | CPU reduced (s) |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for r in sims:
            s = r["simulation"]
            lines.append(
                f"| {r['n_fe']} | {s['contact_phases']} | {s['T_end_full']:.3g} "
                f"| {100 * s['T_end_error']:+.1f} % | {100 * s['F_max_error']:+.1f} % "
                f"| {100 * s['u_L2_error']:.1f} % | {s['full_cpu_s']:.1f} | "
                f"{s['reduced_cpu_s']:.2f} |"
            )
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one small box (~3e3 dofs)")
    ap.add_argument("--simulate", choices=("smallest", "all", "none"), default="smallest")
    ap.add_argument("--worker", nargs=3, type=int, help=argparse.SUPPRESS)
    ap.add_argument("--sim", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        print(json.dumps(worker(*args.worker, args.sim)))
        return
    sizes = QUICK if args.quick else SIZES
    where, results = machine(), []
    for k, (label, mesh) in enumerate(sizes.items()):
        sim = args.simulate == "all" or (args.simulate == "smallest" and k == 0)
        cmd = [sys.executable, __file__, "--worker", *map(str, mesh)] + (["--sim"] if sim else [])
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
        results.append(json.loads(proc.stdout.strip().splitlines()[-1]))
        r = results[-1]
        print(
            f"{label}: {r['n_fe']} FE dofs, reduction {r['reduction_s']:.1f} s, "
            f"peak RSS {r['rss_peak_mib']:.0f} MiB (process {time.perf_counter() - t0:.0f} s)"
        )
    print(_table(results))
    if not args.quick:
        command = "python benchmarks/reduction_3d.py" + "".join(f" {a}" for a in (argv or []))
        entry = {"command": command, "machine": where, "text": _table(results), "data": results}
        store_section(STORE, PAGE, "reduction_3d", "cost", entry)
        print(f"wrote {PAGE}")


if __name__ == "__main__":
    main()
