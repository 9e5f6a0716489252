"""3D costs against the number of dofs: assembly, reduction and per-step cost.

Box blades (span 0.1 m, chord 30 mm, thickness 3 mm, hub radius 0.3 m, 8 tip contacts, a
lobed casing, thermal coupling on) meshed with gmsh at decreasing element sizes; for each
size: assembly of the thermoelastic model (vector P2 + P1, ``solid_model``), the
thermoelastic Craig–Bampton reduction (n_uv = n_θ = 20), the θ-method's per-step CPU on the
reduced model, and on the full model where its factorisation stays affordable. Each size
runs in a fresh process (peak memory per size). Writes ``cost_3d.json`` and ``cost_3d.md``.

Run: ``python benchmarks/cost_3d.py [--quick] [--out DIR]``.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

SIZES = {"3e3": 0.02, "8e3": 0.005, "2e4": 0.0032, "4e4": 0.002, "1e5": 0.0015}
QUICK = {"1e3": 0.02, "3e3": 0.01}
FULL_STEPPING_BELOW = 40_000  # FE dofs: the full model's sparse factorisation above is minutes


def one_size(h_mesh: float) -> dict:
    """Build, reduce and step one box blade; return the timings (s) and sizes."""
    import femrub as fr
    from femrub.contact.casing import Lobed
    from femrub.geometry import box_blade
    from femrub.model.rub import solid_model
    from femrub.reduction import craig_bampton_thermal

    t0 = time.perf_counter()
    blade = box_blade(span=0.1, chord=0.03, thickness=0.003, h=h_mesh, hub_radius=0.3, n_contact=8)
    t_mesh = time.perf_counter() - t0
    mat = fr.Material(young=110e9, rho=4500.0, rho_c=4500 * 585.0, conductivity=7.0)
    t0 = time.perf_counter()
    model, _ = solid_model(
        blade, mat, casing=Lobed(2e-6, 3e-6, 2), rotation_speed=1000.0, friction=0.05
    )
    t_asm = time.perf_counter() - t0
    t0 = time.perf_counter()
    rom, _ = craig_bampton_thermal(model, 20, 20)
    t_red = time.perf_counter() - t0
    h, steps = 1e-6, 2000
    st = fr.ThetaMethod(rom, h)
    res = st.run(steps * h)
    row = {
        "h_mesh": h_mesh,
        "tets": blade.n_tets,
        "fe_dofs": model.info["fe_dofs"],
        "state_dofs": model.n_dofs,
        "reduced_dofs": rom.n_dofs,
        "mesh_s": t_mesh,
        "assembly_s": t_asm,
        "reduction_s": t_red,
        "reduced_us_per_step": 1e6 * res.cpu_seconds / max(res.steps, 1),
    }
    if model.info["fe_dofs"] < FULL_STEPPING_BELOW:
        t0 = time.perf_counter()
        full = fr.ThetaMethod(model, h)
        row["full_setup_s"] = time.perf_counter() - t0
        r = full.run(50 * h)
        row["full_us_per_step"] = 1e6 * r.cpu_seconds / max(r.steps, 1)
    row["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return row


COLS = [
    ("fe_dofs", "FE dofs"),
    ("state_dofs", "state dofs"),
    ("tets", "tets"),
    ("mesh_s", "mesh (s)"),
    ("assembly_s", "assembly (s)"),
    ("reduction_s", "reduction (s)"),
    ("reduced_dofs", "reduced dofs"),
    ("reduced_us_per_step", "reduced µs/step"),
    ("full_setup_s", "full: factorise (s)"),
    ("full_us_per_step", "full µs/step"),
    ("peak_rss_mib", "peak RSS (MiB)"),
]


def table(rows) -> str:
    def fmt(v):
        if v is None:
            return "—"
        if isinstance(v, float):
            return f"{v:.3g}"
        return str(v)

    head = "| " + " | ".join(c[1] for c in COLS) + " |\n|" + "---|" * len(COLS) + "\n"
    return head + "\n".join("| " + " | ".join(fmt(r.get(k)) for k, _ in COLS) + " |" for r in rows)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument(
        "--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "performance"
    )
    ap.add_argument("--one", type=float, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one is not None:
        print(json.dumps(one_size(args.one)))
        return
    rows = []
    for label, h in (QUICK if args.quick else SIZES).items():
        out = subprocess.run(
            [sys.executable, __file__, "--one", str(h)], capture_output=True, text=True
        )
        if out.returncode:
            print(f"size {label} failed: {out.stderr.strip()[-300:]}", flush=True)
            continue
        row = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(row)
        print(f"  {label}: {row}", flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "cost_3d.json").write_text(json.dumps({"rows": rows}, indent=2))
    (args.out / "cost_3d.md").write_text(table(rows) + "\n")
    print(f"wrote {args.out / 'cost_3d.md'}")


if __name__ == "__main__":
    main()
