"""Small linear-algebra routines: dense for small operators, sparse LU for large ones.

A scipy sparse mat-vec costs several microseconds of Python overhead whatever its size; for
the few-dozen-dof models of the paper (and for reduced models) dense numpy arrays are an
order of magnitude faster per step. Large finite-element operators stay sparse.
"""

from __future__ import annotations

import functools
import glob
import importlib.util
import os
import sys
import threading
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .. import progress
from ..blas import libraries_loaded
from .spmm import block_columns, csr_dense

__all__ = [
    "DENSE_BELOW",
    "MKL_REPRODUCIBLE",
    "PARDISO_ABOVE",
    "compact",
    "Factorised",
    "pardiso_available",
    "project",
    "sparse_lu",
]

DENSE_BELOW = 600
#: Size above which MKL Pardiso replaces SuperLU for one-off factorisations with many
#: right-hand sides (reduction, eigen-solvers, prestress tangents): on 3D P2 elasticity
#: SuperLU is faster below about 2,000 unknowns, Pardiso 2 to 3 times faster from 3,500 and
#: 4 to 6 times from 10,000 (``benchmarks/factorisation_size.py``,
#: docs/performance/blade-scale.md).
PARDISO_ABOVE = 3_000

#: Condition number estimate above which a symmetric matrix is called singular.
SINGULAR_CONDITION = 1e14
#: Pardiso matrix types: real symmetric positive definite, symmetric indefinite, general.
_SPD, _SYM, _GENERAL = 2, -2, 11


@functools.cache
def _has_pypardiso() -> bool:
    return importlib.util.find_spec("pypardiso") is not None and pardiso_available()


#: MKL's conditional numerical reproducibility (``MKL_CBWR``), set before femrub loads MKL
#: unless the environment sets it: MKL then keeps one code path for this processor, so a
#: threaded Pardiso factorisation and its solves give the same bits from run to run on the
#: same number of threads (without it, two runs of a Rotor 37 stiffness on two threads
#: differ at round-off about one time in two). It has no effect when another library of
#: the process loaded MKL first.
MKL_REPRODUCIBLE = "AUTO"


def pardiso_available() -> bool:
    """Whether MKL Pardiso can be loaded (``pypardiso`` and the MKL runtime installed).

    The runtime's path is then kept in ``PYPARDISO_MKL_RT``, the variable pypardiso reads
    first: without it every solver object searches the environment's library folders
    again (about 0.7 s each in a virtual environment). The first search looks where pip's
    ``mkl`` wheel puts the runtime (``sys.prefix/lib``, :func:`_mkl_runtime`) before
    pypardiso's search of every folder below it (1.4 s in a virtual environment, paid by
    each process: each sweep worker, each run). MKL is loaded in :data:`MKL_REPRODUCIBLE`
    mode."""
    os.environ.setdefault("MKL_CBWR", MKL_REPRODUCIBLE)
    guess = None if "PYPARDISO_MKL_RT" in os.environ else _mkl_runtime()
    if guess:  # before pypardiso's import, which makes a solver object
        os.environ["PYPARDISO_MKL_RT"] = guess
    try:
        import pypardiso

        solver = pypardiso.PyPardisoSolver()
    except ImportError:
        return False
    except OSError:
        if not guess:
            return False
        del os.environ["PYPARDISO_MKL_RT"]  # not loadable: pypardiso's own search
        try:
            solver = pypardiso.PyPardisoSolver()
        except (ImportError, OSError):
            return False
    libraries_loaded()  # MKL's threads are limited with the other BLAS libraries
    path = getattr(solver.libmkl, "_name", None)
    if path:
        os.environ.setdefault("PYPARDISO_MKL_RT", path)
    return True


def _mkl_runtime() -> str | None:
    """The MKL runtime in ``sys.prefix/lib`` (pip's ``mkl`` wheel), or ``None``."""
    found = glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*"))
    return min(found, key=len) if found else None


class _Pardiso:
    """MKL Pardiso factorisation with the ``splu``-like ``solve(rhs, trans)`` interface.

    Symmetric matrices are factorised as positive definite (Cholesky, ``L Lᵀ``, on the upper
    triangle) and, when a pivot is not positive, as symmetric indefinite (``L D Lᵀ`` with
    Bunch-Kaufman pivoting); other matrices by LU with pivot perturbation and iterative
    refinement. Solves call Pardiso's solve phase directly: the ``pypardiso.solve`` entry
    point hashes the whole matrix on every call to check it is the factorised one. Threads
    may share a factorisation: its solves take turns (Pardiso's solve phase writes in the
    factorisation's memory).
    """

    def __init__(self, M, symmetric: bool, definite: bool = True):
        import pypardiso

        self.symmetric = symmetric
        self._AT = None
        self._solving = threading.Lock()
        A = sp.csr_matrix(M, dtype=float)
        if not symmetric:
            self._factor(pypardiso, A, _GENERAL)
            return
        full, A = A, sp.triu(A, format="csr")
        if definite:
            try:
                self._factor(pypardiso, A, _SPD)
            except pypardiso.pardiso_wrapper.PyPardisoError:  # not positive definite
                definite = False
        if not definite:
            self._factor(pypardiso, A, _SYM)
        # a singular matrix may factorise with a round-off pivot: estimate the condition
        # number from one solve, ‖x‖ ‖A‖ / ‖b‖ with b = 1, as SuperLU's exact zero pivot
        x = self.solve(np.ones(A.shape[0]))
        est = np.abs(x).max() * abs(full).sum(axis=1).max()
        if not np.isfinite(est) or est > SINGULAR_CONDITION:
            raise RuntimeError(f"condition number estimate {est:.1e}: numerically singular")

    @property
    def method(self) -> str:
        return {_SPD: "Cholesky", _SYM: "LDLt", _GENERAL: "LU"}[self.mtype] + " (MKL Pardiso)"

    def free(self) -> None:
        """Release MKL's memory of the factorisation (pypardiso never does: a factor of the
        Rotor 37 stiffness is about 0.5 GB); called when the object is collected."""
        s, self._s = getattr(self, "_s", None), None
        if s is not None:
            try:
                s.free_memory(everything=True)
            except Exception:  # pragma: no cover - interpreter shutdown, other pypardiso
                pass
        at, self._AT = getattr(self, "_AT", None), None
        if at is not None:
            at.free()

    def __del__(self):
        self.free()

    def _factor(self, pypardiso, A, mtype: int) -> None:
        A.sort_indices()
        s = pypardiso.PyPardisoSolver(mtype=mtype)
        if mtype == _GENERAL:
            s.set_iparm(8, 20)  # iterative refinement steps: residuals near round-off
        else:  # explicit settings: the defaults add refinement solves that cost 5x here
            for i, v in ((1, 1), (2, 2), (8, 0), (10, 8), (11, 0), (13, 0), (21, 1), (35, 0)):
                s.set_iparm(i, v)
        try:
            s.factorize(A)
        except pypardiso.pardiso_wrapper.PyPardisoError:
            s.free_memory(everything=True)
            raise
        self.A, self.mtype, self._s = A, mtype, s

    def solve(self, rhs, trans: str = "N"):
        if np.size(rhs) == 0:  # Pardiso rejects an empty right-hand side (error -1)
            return np.zeros(np.shape(rhs))
        if trans != "N" and not self.symmetric:
            if self._AT is None:
                self._AT = _Pardiso(self.A.T, False)
            return self._AT.solve(rhs)
        b = np.asfortranarray(rhs, dtype=float)
        s = self._s
        many = b.ndim == 2 and b.shape[1] > 1
        t0 = time.perf_counter() if many else 0.0
        with self._solving:  # one solve at a time in a factorisation's memory
            if hasattr(s, "_call_pardiso"):  # solve phase only (pypardiso 0.4)
                s.set_phase(33)
                out = s._call_pardiso(self.A, b)
            else:  # pragma: no cover - other pypardiso versions
                out = s.solve(self.A, b)
        if many:
            progress.note(
                f"solved {b.shape[1]} right-hand sides of {b.shape[0]} unknowns in "
                f"{time.perf_counter() - t0:.2f} s"
            )
        return out.reshape(np.shape(rhs))


def sparse_lu(
    M,
    *,
    symmetric: bool = False,
    what: str = "matrix",
    pardiso: bool = True,
    definite: bool = True,
):
    """Sparse factorisation of ``M`` with ``solve(rhs, trans="N")``.

    MKL Pardiso when ``M`` is large (``n >= PARDISO_ABOVE``) and ``pypardiso`` is installed
    (a default dependency on x86-64): Cholesky for a symmetric positive definite ``M``
    (``symmetric=True``), else symmetric indefinite or general LU. Otherwise SuperLU
    (minimum-degree ordering on ``A + Aᵀ`` for symmetric patterns). ``definite=False``: a
    symmetric ``M`` likely to be indefinite is factorised as LDLᵀ without trying Cholesky
    first (a failed Cholesky of a Rotor 37 tangent costs about as much as the LDLᵀ).

    Pardiso pays off for one-off factorisations with many right-hand sides (reduction,
    eigen-solvers); a per-step solve is faster with SuperLU (per-call overhead), so
    steppers pass ``pardiso=False``.
    """
    n = M.shape[0]
    name = what.split(" (")[0]  # without the hint of the error message
    try:
        if pardiso and n >= PARDISO_ABOVE and _has_pypardiso():
            try:
                with progress.phase(f"factorising the {name} ({n} unknowns)") as p:
                    lu = _Pardiso(M, symmetric, definite)
                    p["detail"] = lu.method
            except Exception as exc:  # a Pardiso error: singular, or out of memory
                if type(exc).__name__ != "PyPardisoError":
                    raise
                raise RuntimeError(str(exc)) from None
            return lu
        spec = "MMD_AT_PLUS_A" if symmetric else "COLAMD"
        if n < PARDISO_ABOVE:
            return spla.splu(sp.csc_matrix(M), permc_spec=spec)
        with progress.phase(f"factorising the {name} ({n} unknowns, SuperLU)"):
            return spla.splu(sp.csc_matrix(M), permc_spec=spec)
    except RuntimeError as exc:
        raise ValueError(f"the {what} is singular ({exc})") from None


def project(left: np.ndarray, Q, right: np.ndarray, chunk: int = 8192, parts=None) -> np.ndarray:
    """``leftᵀ Q right`` (dense) for a sparse ``Q`` and dense bases ``left``, ``right``.

    Row blocks of ``chunk`` rows are projected one at a time on the columns of the bases
    that are not zero there: the operators of a first-order model are block-sparse
    (``A = diag(I, M, C^θθ)``; ``B`` couples ``u``, ``v``, ``θ`` by blocks; energy forms
    act on one block) and a reduction basis is block-structured (a ``v`` row only has ``v``
    shapes), so this skips most of the dense work of ``leftᵀ (Q right)``. ``parts``: row
    bounds of the blocks of ``right`` (e.g. ``[0, n_u, 2 n_u, n]``, the full state's ``u``,
    ``v``, ``θ``): the columns of ``Q`` in a block multiply only the columns of ``right``
    not zero in it. The sparse × dense products run on every core
    (:func:`~femrub.fem.spmm.csr_dense`).
    """
    if not sp.issparse(Q):
        return left.T @ (np.asarray(Q) @ right)
    if Q.shape[0] < DENSE_BELOW:  # small: the plain products (no gain from the blocks)
        return left.T @ np.asarray(Q @ right)
    Q = sp.csr_matrix(Q)
    out = np.zeros((left.shape[1], right.shape[1]))
    nonzero = right != 0.0  # one boolean pattern
    bounds = np.asarray([0, right.shape[0]] if parts is None else parts, dtype=np.int64)
    columns = block_columns(nonzero, bounds) if parts is not None else None
    none = np.zeros(0, dtype=np.int64)
    for s in range(0, Q.shape[0], chunk):
        Qs = Q[s : s + chunk]
        if Qs.nnz == 0:
            continue
        Ls = left[s : s + chunk]
        lc = np.flatnonzero(np.any(Ls != 0.0, axis=0))
        if columns is None:  # one block: the columns not zero on the rows this chunk reads
            touched = [np.flatnonzero(np.any(nonzero[np.unique(Qs.indices)], axis=0))]
        else:  # the blocks of right this chunk reads
            lo, hi = Qs.indices.min(), Qs.indices.max()
            touched = [
                c if bounds[b] <= hi and lo < bounds[b + 1] else none for b, c in enumerate(columns)
            ]
        rc = np.unique(np.concatenate(touched))
        if lc.size and rc.size:
            QR = csr_dense(Qs, right, touched, bounds, rc)
            out[np.ix_(lc, rc)] += Ls[:, lc].T @ QR
    return out


def compact(M, dense_below: int = DENSE_BELOW):
    """``M`` as a dense array when it is small, as CSR otherwise."""
    if sp.issparse(M):
        return M.toarray() if max(M.shape) < dense_below else M.tocsr()
    return np.asarray(M)


class Factorised:
    """LU factorisation of a constant square matrix: dense (LAPACK) when small, else SuperLU."""

    def __init__(self, M, dense_below: int = DENSE_BELOW, what: str = "matrix"):
        n = M.shape[0]
        self.dense = n < dense_below
        try:
            if self.dense:
                A = M.toarray() if sp.issparse(M) else np.asarray(M)
                self._lu = sla.lu_factor(A, check_finite=True)
                if np.any(np.diag(self._lu[0]) == 0.0):
                    raise np.linalg.LinAlgError("zero pivot")
            else:
                self._lu = sparse_lu(M, what=what, pardiso=False)
        except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
            raise ValueError(f"the {what} is singular or not finite ({exc})") from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``M⁻¹ rhs`` for a vector or a 2D array of columns."""
        if self.dense:
            return sla.lu_solve(self._lu, rhs, check_finite=False)
        return self._lu.solve(np.ascontiguousarray(rhs))
