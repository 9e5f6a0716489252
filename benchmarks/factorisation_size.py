"""SuperLU against MKL Pardiso on 3D elasticity stiffness matrices of growing size.

``femrub.fem.linalg.sparse_lu`` factorises a one-off matrix (static shapes, shift-invert
modes, the prestress' Newton tangents) with Pardiso from ``PARDISO_ABOVE`` unknowns. This
study measures where Pardiso starts to pay: the clamped P2 tetrahedral stiffness of a box
``1 × 1 × 4`` at several mesh sizes, each factorised ``--repeat`` times by both solvers
in turn (Cholesky ordering for both, in one process, Pardiso warmed up once before); the
table gives the median wall seconds and their ratio. Writes
``docs/performance/factorisation_size.json`` and the table between the
``factorisation_size`` markers of ``docs/performance/blade-scale.md``.

Run: ``python benchmarks/factorisation_size.py [--repeat 3] [--no-write]``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import skfem as fe
from skfem.models.elasticity import lame_parameters, linear_elasticity

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C

from femrub.fem import linalg

JSON = C.OUT / "factorisation_size.json"
PAGE = C.OUT / "blade-scale.md"
#: cells across the box's section and along its length: from about 500 to 25,000 unknowns
MESHES = ((2, 4), (2, 8), (3, 12), (4, 16), (5, 14), (5, 20), (6, 18), (6, 24))


def stiffness(across: int, along: int):
    """Clamped (``z = 0``) P2 stiffness of the box (steel), on its free dofs."""
    x = np.linspace(0.0, 1.0, across + 1)
    mesh = fe.MeshTet.init_tensor(x, x, np.linspace(0.0, 4.0, along + 1))
    basis = fe.Basis(mesh, fe.ElementVector(fe.ElementTetP2()))
    K = fe.asm(linear_elasticity(*lame_parameters(2.1e11, 0.3)), basis)
    free = basis.complement_dofs(basis.get_dofs(lambda p: p[2] < 1e-9).all())
    return K[free][:, free].tocsc()


def _seconds(K, above: int) -> float:
    linalg.PARDISO_ABOVE = above
    t0 = time.perf_counter()
    linalg.sparse_lu(K, symmetric=True)
    return time.perf_counter() - t0


def measure(repeat: int) -> dict:
    """Median factorisation seconds of both solvers at each size."""
    default = linalg.PARDISO_ABOVE
    rows = []
    try:
        _seconds(stiffness(2, 4), 1)  # MKL's first call loads and spins up its threads
        for across, along in MESHES:
            K = stiffness(across, along)
            superlu, pardiso = [], []
            for _ in range(repeat):
                superlu.append(_seconds(K, K.shape[0] + 1))
                pardiso.append(_seconds(K, 1))
            s, p = statistics.median(superlu), statistics.median(pardiso)
            rows.append(
                {"unknowns": K.shape[0], "nnz": K.nnz, "superlu": s, "pardiso": p, "ratio": s / p}
            )
            print(f"{K.shape[0]} unknowns: SuperLU {s:.2f} s, Pardiso {p:.2f} s", flush=True)
    finally:
        linalg.PARDISO_ABOVE = default
    return {"machine": C.machine(), "repeat": repeat, "threshold": default, "rows": rows}


def table(data: dict) -> str:
    cols = [
        ("unknowns", "unknowns"),
        ("nnz", "nonzeros"),
        ("superlu", "SuperLU (s)"),
        ("pardiso", "Pardiso (s)"),
        ("ratio", "SuperLU / Pardiso"),
    ]
    m = data["machine"]
    head = (
        f"{C.stamp('python benchmarks/factorisation_size.py', m)} Median of "
        f"{data['repeat']} factorisations each; `PARDISO_ABOVE` was {data['threshold']}."
    )
    return head + "\n\n" + C.md_table(data["rows"], cols)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args(argv)
    data = measure(args.repeat)
    text = table(data)
    if args.no_write:
        print(text)
        return
    C.write_json(JSON, data)
    C.write_between(PAGE, "factorisation_size", text, "## Factorisation against size\n\n")
    print(text)


if __name__ == "__main__":
    main()
