"""Mutation smoke check: do the tests catch a wrong physics term?

Applies, one at a time, a list of representative one-line physics bugs (:data:`MUTATIONS`)
to a scratch copy of the repository (the working tree is never touched), runs the tests
that should catch each one, and reports which bugs survive. None may survive.

Each mutation names the test files selected for it (the fast relevant subset, so the whole
check takes minutes, not hours); ``--full`` runs the whole default suite instead. A
mutation whose line is no longer in the source is reported ``not applicable`` (update the
list when the code moves).

Usage::

    python benchmarks/mutation_smoke.py            # writes docs/performance/mutation_smoke.md
    python benchmarks/mutation_smoke.py --full     # every mutation against the default suite
    python benchmarks/mutation_smoke.py -k heat    # only mutations whose name contains 'heat'

Exit status 1 when a mutation survives or does not apply.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "performance" / "mutation_smoke.md"
IGNORE = shutil.ignore_patterns(
    ".git",
    "__pycache__",
    "*.egg-info",
    ".hypothesis",
    ".pytest_cache",
    ".ruff_cache",
    "out",
    "results",
    "*.vtu",
    "*.pvd",
)


@dataclass(frozen=True)
class Mutation:
    """A one-line bug: replace ``old`` by ``new`` in ``path`` (exactly one occurrence)."""

    name: str
    path: str
    old: str
    new: str
    tests: tuple[str, ...]


T = "tests/"
MUTATIONS = [
    # -- the thermal side --------------------------------------------------------------------
    Mutation(
        "conductivity x10 in the weak form",
        "femrub/fem/forms.py",
        "return w.k * w.area * dot(grad(theta), grad(eta))",
        "return 10.0 * w.k * w.area * dot(grad(theta), grad(eta))",
        (T + "test_thermal_analytic.py",),
    ),
    Mutation(
        "strain heating C^θu sign flipped (physical coupling)",
        "femrub/fem/forms.py",
        "return w.area * w.T0 * w.b * trace(sym_grad(u)) * eta",
        "return -w.area * w.T0 * w.b * trace(sym_grad(u)) * eta",
        (T + "test_thermal_analytic.py",),
    ),
    Mutation(
        "strain heating C^θu sign flipped (paper coupling)",
        "femrub/fem/assembly.py",
        "Ctu = -material.reference_temperature * Kut.T",
        "Ctu = material.reference_temperature * Kut.T",
        (T + "test_thermal_analytic.py",),
    ),
    Mutation(
        "heat capacity x1.25",
        "femrub/fem/forms.py",
        "return w.rho_c * w.area * theta * eta",
        "return 1.25 * w.rho_c * w.area * theta * eta",
        (T + "test_thermal_analytic.py", T + "test_rub_3d_reference.py"),
    ),
    Mutation(
        "Rayleigh stiffness term dropped (physics.rayleigh)",
        "femrub/fem/assembly.py",
        "C = a_r * M + b_r * K",
        "C = a_r * M",
        (T + "test_damping_decay.py",),
    ),
    Mutation(
        "Rayleigh stiffness term dropped (physics.damping_ratio)",
        "femrub/fem/discretisation.py",
        "C=(rayleigh[0] * mats.M + rayleigh[1] * mats.K).tocsr()",
        "C=(rayleigh[0] * mats.M).tocsr()",
        (T + "test_damping_decay.py",),
    ),
    Mutation(
        "thermal stress K^uθ sign flipped (physical coupling)",
        "femrub/fem/forms.py",
        "return -w.area * w.b * theta * trace(sym_grad(v))",
        "return w.area * w.b * theta * trace(sym_grad(v))",
        (T + "test_thermal_analytic.py",),
    ),
    Mutation(
        "thermal stress modulus (λ + 2μ) α instead of (d λ + 2μ) α",
        "femrub/fem/assembly.py",
        "b = (dim * lam + 2.0 * mu) * material.expansion",
        "b = (lam + 2.0 * mu) * material.expansion",
        (T + "test_solid.py",),
    ),
    Mutation(
        "frictional heat input halved (heat rows of the model)",
        "femrub/model/build.py",
        "Ht[L.t] = hd.T",
        "Ht[L.t] = 0.5 * hd.T",
        (T + "test_rub_3d_reference.py", T + "test_energy.py"),
    ),
    Mutation(
        "frictional heat law α = η μ Ω r halved",
        "femrub/contact/heat.py",
        "return eta * mu * abs(omega) * radii",
        "return 0.5 * eta * mu * abs(omega) * radii",
        (T + "test_rub_3d_reference.py",),
    ),
    # -- coupling, scheme, contact, reduction, lumping --------------------------------------
    Mutation(
        "paper coupling sign (K^uθ = −β K^uu)",
        "femrub/fem/assembly.py",
        "Kut = beta * K",
        "Kut = -beta * K",
        (T + "test_assembly.py",),
    ),
    Mutation(
        "θ-method γ = 0.55 by default",
        "femrub/steppers/theta.py",
        "gamma: float = 0.5,",
        "gamma: float = 0.55,",
        (T + "test_energy.py", T + "test_convergence_orders.py"),
    ),
    Mutation(
        "impact law: restitution sign (one contact, default rule)",
        "femrub/contact/theta_block.py",
        "p_cap = (min(g_k, 0.0) + e * max(g_k, 0.0) - g_p) / gz",
        "p_cap = (min(g_k, 0.0) - e * max(g_k, 0.0) - g_p) / gz",
        (T + "test_energy.py", T + "test_impact_exact.py", T + "test_activation.py"),
    ),
    Mutation(
        "impact law: restitution sign (several contacts, default rule)",
        "femrub/contact/activation.py",
        "q = (2.0 / h) * (g_p - _target(g_k, e))",
        "q = (2.0 / h) * (g_p - _target(g_k, -e))",
        (T + "test_multicontact.py", T + "test_activation.py", T + "test_energy.py"),
    ),
    Mutation(
        "tip mass doubled (row-sum lumping)",
        "femrub/fem/assembly.py",
        "return sp.diags(rows).tocsr()",
        "return sp.diags(rows * np.r_[np.ones(rows.size - 1), 2.0]).tocsr()",
        (T + "test_assembly.py",),
    ),
    Mutation(
        "tip heat capacity doubled (row-sum lumping)",
        "femrub/fem/lumping.py",
        "return sp.diags(np.asarray(matrix.sum(axis=1)).ravel()).tocsr()",
        "return sp.diags(np.asarray(matrix.sum(axis=1)).ravel()"
        " * np.r_[np.ones(matrix.shape[0] - 1), 2.0]).tocsr()",
        (T + "test_assembly.py",),
    ),
    Mutation(
        "static shapes sign (Craig-Bampton Eq. 11)",
        "femrub/reduction/craig_bampton.py",
        "psi = solver.solve(-sp.csc_matrix(B)[:, self._bnd][self._int])",
        "psi = solver.solve(sp.csc_matrix(B)[:, self._bnd][self._int])",
        (T + "test_reduction.py",),
    ),
    Mutation(
        "Carpenter's position correction dropped",
        "femrub/steppers/carpenter.py",
        "out[L.u] += h * self._solve(self._B @ dv)[L.u]",
        "out[L.u] += 0.0 * h * self._solve(self._B @ dv)[L.u]",
        (T + "test_paper_case.py", T + "test_multicontact.py"),
    ),
    Mutation(
        "HRZ lumping without its mass scaling",
        "femrub/fem/lumping.py",
        "out[c::n_components] = diag[c::n_components] * totals[c] / diag[c::n_components].sum()",
        "out[c::n_components] = diag[c::n_components]",
        (T + "test_assembly.py", T + "test_solid.py"),
    ),
]


def _run_one(scratch: Path, mut: Mutation, tests, timeout: float) -> tuple[str, str, float]:
    """Apply ``mut`` in ``scratch``, run ``tests``, restore; return (status, detail, seconds)."""
    target = scratch / mut.path
    original = target.read_text()
    count = original.count(mut.old)
    if count != 1:
        return "not applicable", f"line found {count} times in {mut.path}", 0.0
    target.write_text(original.replace(mut.old, mut.new))
    env = {**os.environ, "PYTHONPATH": str(scratch), "MPLBACKEND": "Agg"}
    cmd = [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", *tests]
    t0 = time.perf_counter()
    try:
        out = subprocess.run(
            cmd, cwd=scratch, env=env, capture_output=True, text=True, timeout=timeout
        )
        rc, text = out.returncode, out.stdout + out.stderr
    except subprocess.TimeoutExpired:
        rc, text = 124, "timeout"
    finally:
        target.write_text(original)
    seconds = time.perf_counter() - t0
    if rc == 0:
        return "SURVIVED", "all selected tests pass", seconds
    failed = [ln.split(" ", 1)[1] for ln in text.splitlines() if ln.startswith(("FAILED", "ERROR"))]
    detail = failed[0].split(" - ")[0] if failed else f"pytest exit {rc}"
    return "killed", detail, seconds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--full", action="store_true", help="run the whole default suite each time")
    ap.add_argument("-k", default="", help="only mutations whose name contains this text")
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per mutation")
    ap.add_argument("--no-write", action="store_true", help="do not write the Markdown table")
    args = ap.parse_args(argv)
    chosen = [m for m in MUTATIONS if args.k.lower() in m.name.lower()]
    rows = []
    with tempfile.TemporaryDirectory(prefix="femrub-mutants-") as tmp:
        scratch = Path(tmp) / "repo"
        shutil.copytree(ROOT, scratch, ignore=IGNORE)
        for mut in chosen:
            tests = ("tests",) if args.full else mut.tests
            status, detail, sec = _run_one(scratch, mut, tests, args.timeout)
            rows.append((mut, status, detail, sec, tests))
            print(f"{status:>14}  {sec:6.1f} s  {mut.name}  [{detail}]", flush=True)
    lines = [
        "# Mutation smoke check (benchmarks/mutation_smoke.py)",
        "",
        f"Selection: {'the whole default suite' if args.full else 'per-mutation subset'}; "
        f"load average at the end: {os.getloadavg()[0]:.1f}.",
        "",
        "| mutation | file | tests run | result | first failing test | s |",
        "|---|---|---|---|---|---|",
    ]
    for mut, status, detail, sec, tests in rows:
        names = ", ".join(Path(t).name for t in tests)
        lines.append(f"| {mut.name} | `{mut.path}` | {names} | {status} | `{detail}` | {sec:.0f} |")
    text = "\n".join(lines) + "\n"
    if not args.no_write and not args.k:
        OUT.write_text(text)
        print(f"wrote {OUT.relative_to(ROOT)}")
    bad = [r for r in rows if r[1] != "killed"]
    print(f"{len(rows) - len(bad)}/{len(rows)} mutations killed")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
