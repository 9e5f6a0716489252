"""Sparse solvers and eigen-solvers on the Rotor 37 matrices, and the blade-scale targets.

    python benchmarks/solvers.py            # every candidate, then the end-to-end runs
    python benchmarks/solvers.py --no-e2e   # candidates only

Skips with a message when the Rotor 37 reference data (``../shared/data``) are absent.

1. The matrices of the reduction of the ``rotor37`` scene (interior stiffness ``K_ii``,
   mass ``M_ii``) are assembled once and saved to a temporary folder.
2. Each candidate runs in a fresh process (its peak memory is its own): factorise
   ``K_ii``, solve 230 right-hand sides at once (the static shapes of Eq. 11: 48 + 48
   mechanical and 134 thermal boundary dofs) and one alone (an ARPACK iteration); or
   compute the 12 lowest clamped modes. Missing or broken packages are listed with the
   reason (no wheel for this Python, fails to import, ...).
3. End to end, each in a fresh process: ``rotor37`` from the mesh file to the reduced
   model without cache, then twice with a fresh cache (store, then hit: the time to the
   first step).

CPU = ``time.process_time()`` of the process (all its threads), wall = ``perf_counter``,
peak = ``ru_maxrss``; the machine load (``os.getloadavg``) is recorded with each row, as
the 2-core machine is shared. Writes ``docs/performance/solvers.{json,md}`` and the
section between the ``solvers`` markers of ``docs/performance/blade-scale.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "performance"
N_RHS = 230
N_MODES = 12

FACTOR = {
    "superlu": "SuperLU (scipy), minimum degree on AᵀA + A",
    "pardiso": "MKL Pardiso Cholesky (pypardiso), femrub's default",
    "cholmod-kvxopt": "CHOLMOD (kvxopt wheel)",
    "cholespy": "CHOLMOD (cholespy wheel)",
    "mumps": "MUMPS (python-mumps wheel)",
    "scikit-sparse": "CHOLMOD (scikit-sparse)",
}
EIGEN = {
    "arpack-pardiso": "ARPACK shift-invert, Pardiso Cholesky (default)",
    "arpack-superlu": "ARPACK shift-invert, SuperLU",
    "lobpcg-amg": "LOBPCG + smoothed-aggregation AMG (pyamg)",
    "primme": "PRIMME",
}


def _rss_mb() -> float:
    """Peak resident memory of this process (MB): ``VmHWM``, which an ``exec`` resets (the
    ``ru_maxrss`` of a child keeps its parent's peak on Linux)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _load() -> float:
    return round(os.getloadavg()[0], 2)


# -- data -----------------------------------------------------------------------------------
def prepare(folder: Path) -> dict:
    """Assemble the rotor37 scene's interior K, M (the reduction's) into ``folder``."""
    from femrub.app import translate as tr
    from femrub.app.blade import load_blade
    from femrub.contact.points import locate_contacts
    from femrub.fem.discretisation import assemble, discretise
    from femrub.scene import load_scene

    scene = load_scene("rotor37")
    p = scene["physics"]
    blade = load_blade(scene)
    disc = discretise(blade, p["order"], clamped=scene["boundary"]["clamped"])
    mats = assemble(
        disc, tr.material_of(scene), lumping=p["lumping"], coupling=tr.coupling_of(scene)
    )
    mb = np.unique(locate_contacts(disc).normal_rows(mats).indices)
    mi = np.setdiff1d(np.arange(mats.n_u), mb)
    K, M = mats.K.tocsr(), mats.M.tocsr()
    sp.save_npz(folder / "K.npz", K[mi][:, mi].tocsr())
    sp.save_npz(folder / "M.npz", M[mi][:, mi].tocsr())
    return {"n_interior": int(mi.size), "n_u": int(mats.n_u), "nnz_K": int(K.nnz)}


# -- one candidate (child process) -----------------------------------------------------------
def _factor(name: str, K):
    """``(solve, note)`` of a factorisation of the SPD ``K``."""
    if name == "superlu":
        import scipy.sparse.linalg as spla

        lu = spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A")
        return lu.solve, ""
    if name == "pardiso":
        from femrub.fem.linalg import sparse_lu

        lu = sparse_lu(K, symmetric=True)
        return lu.solve, type(lu).__name__
    if name == "cholmod-kvxopt":
        from kvxopt import cholmod, matrix, spmatrix

        C = K.tocoo()
        A = spmatrix(C.data, C.row.tolist(), C.col.tolist())
        F = cholmod.symbolic(A)
        cholmod.numeric(A, F)

        def solve(r):
            X = matrix(np.asfortranarray(r.reshape(r.shape[0], -1)))
            cholmod.solve(F, X)
            return np.array(X).reshape(r.shape)

        return solve, ""
    if name == "cholespy":
        from cholespy import CholeskySolverD, MatrixType

        C = K.tocsc()
        ch = CholeskySolverD(
            C.shape[0],
            C.indptr.astype(np.int32),
            C.indices.astype(np.int32),
            C.data,
            MatrixType.CSC,
        )

        def solve(r):
            x = np.zeros_like(r)
            ch.solve(np.ascontiguousarray(r), x)
            return x

        return solve, ""
    if name == "mumps":
        import mumps

        ctx = mumps.Context()
        ctx.set_matrix(K.tocsc(), symmetric=True)
        ctx.analyze()
        ctx.factor()
        return ctx.solve, ""
    if name == "scikit-sparse":
        from sksparse.cholmod import cholesky

        return cholesky(K.tocsc()), ""
    raise KeyError(name)


def run_factor(name: str, folder: Path) -> dict:
    K = sp.load_npz(folder / "K.npz").tocsr()
    base, load0 = _rss_mb(), _load()
    R = np.random.default_rng(0).standard_normal((K.shape[0], N_RHS))
    c0, t0 = time.process_time(), time.perf_counter()
    solve, note = _factor(name, K)
    fc, fw = time.process_time() - c0, time.perf_counter() - t0
    after = _rss_mb()
    c0, t0 = time.process_time(), time.perf_counter()
    X = solve(R)
    sc, sw = time.process_time() - c0, time.perf_counter() - t0
    c0, t0 = time.process_time(), time.perf_counter()
    x = solve(R[:, 0].copy())
    oc, ow = time.process_time() - c0, time.perf_counter() - t0
    res = float(np.linalg.norm(K @ X - R) / np.linalg.norm(R))
    res1 = float(np.linalg.norm(K @ x - R[:, 0]) / np.linalg.norm(R[:, 0]))
    return dict(
        factor_cpu=fc,
        factor_wall=fw,
        solves_cpu=sc,
        solves_wall=sw,
        one_cpu=oc,
        one_wall=ow,
        residual=max(res, res1),
        base_mb=base,
        factor_mb=after - base,
        peak_mb=_rss_mb(),
        load=[load0, _load()],
        note=note,
    )


def run_eigen(name: str, folder: Path) -> dict:
    import scipy.sparse.linalg as spla

    K = sp.load_npz(folder / "K.npz").tocsc()
    M = sp.load_npz(folder / "M.npz").tocsc()
    base, load0 = _rss_mb(), _load()
    c0, t0 = time.process_time(), time.perf_counter()
    if name == "arpack-pardiso":
        from femrub.fem.eigen import lowest_modes

        lam, V = lowest_modes(K, M, N_MODES)
    elif name == "arpack-superlu":
        lu = spla.splu(K, permc_spec="MMD_AT_PLUS_A")
        op = spla.LinearOperator(K.shape, matvec=lu.solve, dtype=float)
        lam, V = spla.eigsh(K, k=N_MODES, M=M, sigma=0.0, OPinv=op, which="LM", tol=1e-12)
    elif name == "lobpcg-amg":
        import pyamg

        ml = pyamg.smoothed_aggregation_solver(K.tocsr(), symmetry="symmetric")
        P = ml.aspreconditioner()
        X0 = np.random.default_rng(0).standard_normal((K.shape[0], N_MODES + 4))
        lam, V = spla.lobpcg(K, X0, B=M, M=P, largest=False, tol=1e-8, maxiter=400)
        lam, V = lam[:N_MODES], V[:, :N_MODES]
    elif name == "primme":
        import primme

        lam, V = primme.eigsh(K, N_MODES, M=M, which="SA", tol=1e-10)
    else:
        raise KeyError(name)
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    order = np.argsort(lam)
    lam, V = np.asarray(lam)[order], V[:, order]
    r = np.linalg.norm(K @ V - (M @ V) * lam, axis=0) / np.linalg.norm(K @ V, axis=0)
    return dict(
        cpu=cpu,
        wall=wall,
        f1_hz=float(np.sqrt(lam[0]) / (2 * np.pi)),
        f12_hz=float(np.sqrt(lam[-1]) / (2 * np.pi)),
        residual=float(r.max()),
        base_mb=base,
        peak_mb=_rss_mb(),
        load=[load0, _load()],
    )


def run_e2e(kind: str, cache_dir: str) -> dict:
    """``rotor37`` mesh -> reduced model; ``kind``: ``nocache``, ``store`` or ``hit``."""
    from femrub.app.cache import ModelCache
    from femrub.app.simulation import build
    from femrub.scene import load_scene

    cache = None if kind == "nocache" else ModelCache(cache_dir)
    scene = load_scene("rotor37")
    lines: list[str] = []
    load0 = _load()
    c0, t0 = time.process_time(), time.perf_counter()
    sim = build(scene, log=lines.append, cache=cache)
    next(iter(sim.stepper.iterate(scene["scheme"]["t_end"])))  # the first step
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    return dict(
        cpu=cpu,
        wall=wall,
        peak_mb=_rss_mb(),
        timings=sim.timings,
        n_dofs=sim.model.n_dofs,
        reduction_phases=sim.model.info.get("timings", {}),
        load=[load0, _load()],
        log=lines,
    )


# -- driver ----------------------------------------------------------------------------------
def _child(args: list[str], timeout: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    try:
        cmd = [sys.executable, __file__, "--child", *args]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {"error": f"over {timeout:.0f} s"}
    for line in reversed(p.stdout.splitlines()):
        if line.startswith("{"):
            return json.loads(line)
    tail = (p.stderr.strip().splitlines() or ["no output"])[-1]
    return {"error": tail[:160]}


def _fmt(x, d=1) -> str:
    return "—" if x is None else f"{x:.{d}f}"


INSTALL = {
    "superlu": "in scipy",
    "pardiso": "pypardiso (10 kB) + mkl wheel (221 MB), x86-64 only",
    "cholmod-kvxopt": "kvxopt wheel (21 MB)",
    "cholespy": "cholespy wheel (5.6 MB)",
    "mumps": "python-mumps: newest wheel for cp311 is 0.0.2",
    "scikit-sparse": "no wheel for cp311 x86-64 (builds against SuiteSparse)",
    "arpack-pardiso": "scipy + pypardiso",
    "arpack-superlu": "in scipy",
    "lobpcg-amg": "pyamg wheel (2.4 MB)",
    "primme": "no wheel for cp311 x86-64",
}


def _tables(doc: dict) -> str:
    lines = [
        f"Rotor 37 interior stiffness `K_ii`: {doc['data']['n_interior']} unknowns "
        f"(P2, {doc['data']['nnz_K']} nonzeros in `K`); {N_RHS} right-hand sides (the static "
        "shapes), one alone (an ARPACK iteration). Python "
        f"{doc['python']}, 2 cores shared with other jobs: load = 1-minute load average at "
        "the start and end of each row. MB: peak resident memory of the process above the "
        "matrices it loaded.",
        "",
        "| factorisation | factor CPU (s) | factor wall (s) | 230 solves CPU (s) | "
        "1 solve (s) | residual | factor MB | peak MB | load | install |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in doc["factor"].items():
        if "error" in r:
            lines.append(
                f"| {FACTOR[name]} | not run: {r['error']} | | | | | | | | {INSTALL[name]} |"
            )
            continue
        lines.append(
            f"| {FACTOR[name]} | {_fmt(r['factor_cpu'])} | {_fmt(r['factor_wall'])} | "
            f"{_fmt(r['solves_cpu'])} | {_fmt(r['one_wall'], 2)} | {r['residual']:.1e} | "
            f"{r['factor_mb']:.0f} | {r['peak_mb'] - r['base_mb']:.0f} | "
            f"{r['load'][0]}–{r['load'][1]} | {INSTALL[name]} |"
        )
    lines += [
        "",
        f"| eigen-solver ({N_MODES} lowest clamped modes) | CPU (s) | wall (s) | f1 (Hz) | "
        f"f{N_MODES} (Hz) | residual | peak MB | load | install |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in doc["eigen"].items():
        if "error" in r:
            lines.append(f"| {EIGEN[name]} | not run: {r['error']} | | | | | | | {INSTALL[name]} |")
            continue
        lines.append(
            f"| {EIGEN[name]} | {_fmt(r['cpu'])} | {_fmt(r['wall'])} | {r['f1_hz']:.2f} | "
            f"{r['f12_hz']:.2f} | {r['residual']:.1e} | {r['peak_mb'] - r['base_mb']:.0f} | "
            f"{r['load'][0]}–{r['load'][1]} | {INSTALL[name]} |"
        )
    if doc.get("e2e"):
        lines += [
            "",
            "| `rotor37`, mesh file to first step | CPU (s) | wall (s) | peak MB | "
            "assembly (s) | reduction (s) | reduction phases (s) | load |",
            "|---|---|---|---|---|---|---|---|",
        ]
        what = {"nocache": "no cache", "store": "cache miss (stores)", "hit": "cache hit"}
        for kind, r in doc["e2e"].items():
            if "error" in r:
                lines.append(f"| {what[kind]} | not run: {r['error']} | | | | | | |")
                continue
            ph = ", ".join(
                f"{k.replace('_', ' ')} {v:.1f}" for k, v in r["reduction_phases"].items()
            )
            if kind == "hit":
                ph = "loaded from the cache"
            lines.append(
                f"| {what[kind]} | {_fmt(r['cpu'])} | {_fmt(r['wall'])} | "
                f"{r['peak_mb']:.0f} | {_fmt(r['timings'].get('assembly'))} | "
                f"{_fmt(r['timings'].get('reduction'))} | {ph or '—'} | "
                f"{r['load'][0]}–{r['load'][1]} |"
            )
    return "\n".join(lines) + "\n"


def _write(doc: dict) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "solvers.json").write_text(json.dumps(doc, indent=1, default=str))
    text = _tables(doc)
    (OUT / "solvers.md").write_text("# Sparse solvers on Rotor 37\n\n" + text)
    perf = OUT / "blade-scale.md"
    begin, end = "<!-- solvers:begin -->", "<!-- solvers:end -->"
    doc_text = perf.read_text()
    if begin in doc_text and end in doc_text:
        head, rest = doc_text.split(begin, 1)
        perf.write_text(head + begin + "\n" + text + end + rest.split(end, 1)[1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-e2e", action="store_true", help="skip the end-to-end rotor37 runs")
    ap.add_argument("--only", help="comma-separated candidates to run")
    ap.add_argument("--e2e-only", action="store_true", help="only the end-to-end runs")
    ap.add_argument("--timeout", type=float, default=900.0, help="per candidate (s)")
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        kind, name, folder = args.child
        fn = {"factor": run_factor, "eigen": run_eigen, "e2e": run_e2e}[kind]
        print(json.dumps(fn(name, Path(folder)) if kind != "e2e" else fn(name, folder)))
        return 0
    from femrub.geometry.rotor37 import shared_data_dir

    mesh = shared_data_dir() / "rotor37-fe-mesh"
    if not mesh.is_dir():
        print(f"skipped: the Rotor 37 reference data are not available ({mesh} not found)")
        return 0
    only = set(args.only.split(",")) if args.only else None
    doc = {"python": sys.version.split()[0], "factor": {}, "eigen": {}, "e2e": {}}
    with tempfile.TemporaryDirectory(prefix="femrub-solvers-") as tmp:
        folder = Path(tmp)
        if not args.e2e_only:
            print("assembling the Rotor 37 matrices ...", flush=True)
            doc["data"] = prepare(folder)
        for kind, names in (("factor", FACTOR), ("eigen", EIGEN)) if not args.e2e_only else ():
            for name in names:
                if only and name not in only:
                    continue
                print(f"{kind}: {name} ...", flush=True)
                doc[kind][name] = r = _child([kind, name, str(folder)], args.timeout)
                print(f"  {r}", flush=True)
        if not args.no_e2e:
            cache_dir = folder / "cache"
            for kind in ("nocache", "store", "hit"):
                print(f"rotor37 end to end: {kind} ...", flush=True)
                doc["e2e"][kind] = r = _child(["e2e", kind, str(cache_dir)], args.timeout)
                print(f"  { {k: v for k, v in r.items() if k != 'log'} }", flush=True)
    if (OUT / "solvers.json").exists() and (only or args.no_e2e or args.e2e_only):
        old = json.loads((OUT / "solvers.json").read_text())  # keep the rows not rerun
        for k in ("factor", "eigen", "e2e"):
            old.setdefault(k, {}).update(doc[k])
        old["data"] = doc.get("data") or old.get("data")
        doc = dict(old, python=doc["python"])
    _write(doc)
    print(_tables(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
