"""CalculiX (``ccx``) as a reference code: its input, its run and the files it writes.

* :func:`frequency_input`: the model data of a deck (everything before its first
  ``*STEP``, ``*INCLUDE`` paths made absolute) followed by a frequency step and a
  matrix-storage step, so one run gives the natural frequencies and the assembled
  stiffness and mass;
* :func:`run_ccx`: ``ccx`` on such an input in a folder of its own (never the deck's);
* :func:`read_frequencies`: the eigenvalue table of a ``.dat`` file;
* :func:`read_matrices`: the ``.sti`` / ``.mas`` / ``.dof`` files of the matrix-storage
  step (the free dofs only: CalculiX removes the ``*BOUNDARY`` dofs).

Units are the deck's (N-mm-t-s for Rotor 37: stiffness in N/mm, mass in t).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

__all__ = [
    "CcxMatrices",
    "ccx_executable",
    "ccx_version",
    "frequency_input",
    "read_frequencies",
    "read_matrices",
    "run_ccx",
]

_INCLUDE = re.compile(r"(\binput\s*=\s*)([^,\s]+)", re.IGNORECASE)
_FLOAT = r"[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?"
_EIGEN_ROW = re.compile(rf"^\s*(\d+)\s+({_FLOAT})\s+({_FLOAT})\s+({_FLOAT})\s+({_FLOAT})\s*$")


def ccx_executable() -> str | None:
    """Path of ``ccx`` on ``PATH`` (``$FEMRUB_CCX`` first), or ``None``."""
    return shutil.which(os.environ.get("FEMRUB_CCX", "ccx"))


def ccx_version(exe: str) -> str:
    """The version line ``ccx -v`` prints (``"unknown"`` when it prints none)."""
    done = subprocess.run([exe, "-v"], capture_output=True, text=True, timeout=60)
    found = re.search(r"Version\s+(\S+)", done.stdout + done.stderr)
    return found.group(1) if found else "unknown"


def _absolute(deck: Path, name: str) -> str:
    """An ``*INCLUDE`` file name of ``deck`` as an absolute path."""
    return str((deck.parent / name).resolve())


def _model_data(deck: Path) -> list[str]:
    """The lines of ``deck`` before its first ``*STEP``, ``*INCLUDE`` paths absolute."""
    out = []
    for line in deck.read_text().splitlines():
        if line.lstrip().upper().startswith("*STEP"):
            break
        if line.lstrip().upper().startswith("*INCLUDE"):
            line = _INCLUDE.sub(lambda m: m.group(1) + _absolute(deck, m.group(2)), line)
        out.append(line)
    return out


def frequency_input(deck: Path, modes: int) -> str:
    """A CalculiX input: the model data of ``deck``, its ``modes`` lowest natural
    frequencies (``*FREQUENCY``, the default Lanczos solver, mass-normalised shapes) and
    the assembled stiffness and mass (``*FREQUENCY, SOLVER=MATRIXSTORAGE``)."""
    steps = [
        "*STEP, PERTURBATION",
        "*FREQUENCY",
        str(int(modes)),
        "*END STEP",
        "*STEP, PERTURBATION",
        "*FREQUENCY, SOLVER=MATRIXSTORAGE",
        "1",
        "*END STEP",
    ]
    return "\n".join([*_model_data(Path(deck)), *steps]) + "\n"


def run_ccx(text: str, folder: Path, job: str = "job", *, timeout: float = 3600.0) -> Path:
    """Write ``text`` as ``folder/job.inp``, run ``ccx`` there on one thread; the job's path
    without suffix. Raises ``RuntimeError`` with the end of its log when it fails."""
    exe = ccx_executable()
    if exe is None:
        raise RuntimeError(
            "ccx not found on PATH (apt-get install calculix-ccx, or set FEMRUB_CCX)"
        )
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{job}.inp").write_text(text)
    env = {**os.environ, "OMP_NUM_THREADS": "1", "CCX_NPROC_STIFFNESS": "1"}
    done = subprocess.run(
        [exe, job], cwd=folder, env=env, capture_output=True, text=True, timeout=timeout
    )
    if done.returncode != 0 or "Job finished" not in done.stdout:
        tail = "\n".join((done.stdout + done.stderr).splitlines()[-15:])
        raise RuntimeError(f"ccx failed on {folder / job}.inp (exit {done.returncode}):\n{tail}")
    return folder / job


def read_frequencies(dat: Path) -> dict[str, np.ndarray]:
    """The first eigenvalue table of a CalculiX ``.dat`` file.

    Returns
    -------
    dict
        ``mode`` (1-based), ``eigenvalue`` ω² (rad²/s² in the deck's time unit),
        ``omega`` (rad/s) and ``frequency_hz`` (Hz), one entry per mode.

    Raises
    ------
    ValueError
        The file holds no eigenvalue table.
    """
    lines = Path(dat).read_text().splitlines()
    start = next((i for i, s in enumerate(lines) if "E I G E N V A L U E   O U T P U T" in s), None)
    if start is None:
        raise ValueError(f"{dat}: no eigenvalue table (E I G E N V A L U E   O U T P U T)")
    rows, seen = [], False
    for line in lines[start + 1 :]:
        found = _EIGEN_ROW.match(line)
        if found:
            rows.append([float(x) for x in found.groups()])
            seen = True
        elif seen and line.strip():
            break
    if not rows:
        raise ValueError(f"{dat}: the eigenvalue table has no rows")
    table = np.array(rows)
    return {
        "mode": table[:, 0].astype(int),
        "eigenvalue": table[:, 1],
        "omega": table[:, 2],
        "frequency_hz": table[:, 3],
    }


@dataclass(frozen=True)
class CcxMatrices:
    """Stiffness and mass of the free dofs as CalculiX assembled them (deck's units).

    ``node`` and ``direction`` (1, 2, 3 for x, y, z) name each row.
    """

    K: sp.csr_matrix
    M: sp.csr_matrix
    node: np.ndarray
    direction: np.ndarray

    def rows(self, nodes, directions=(1, 2, 3)) -> np.ndarray:
        """Row of each (node, direction), nodes outer; ``KeyError`` for a constrained dof."""
        where = {(int(n), int(d)): i for i, (n, d) in enumerate(zip(self.node, self.direction))}
        try:
            return np.array([where[int(n), int(d)] for n in nodes for d in directions])
        except KeyError as exc:
            raise KeyError(
                f"dof (node, direction) {exc.args[0]} is not free in the model"
            ) from None


def _symmetric(path: Path, n: int) -> sp.csr_matrix:
    """A matrix stored as its upper triangle, ``row col value`` 1-based per line."""
    data = np.loadtxt(path, ndmin=2)
    i, j, v = data[:, 0].astype(int) - 1, data[:, 1].astype(int) - 1, data[:, 2]
    upper = sp.coo_matrix((v, (i, j)), shape=(n, n)).tocsr()
    return (upper + sp.triu(upper, 1).T).tocsr()


def read_matrices(job: Path) -> CcxMatrices:
    """``job.sti``, ``job.mas`` and ``job.dof`` of a matrix-storage step."""
    job = Path(job)
    dof = np.loadtxt(job.with_suffix(".dof"), dtype=str, ndmin=1)
    node_dir = np.array([s.split(".") for s in dof], dtype=int).reshape(-1, 2)
    n = node_dir.shape[0]
    K = _symmetric(job.with_suffix(".sti"), n)
    M = _symmetric(job.with_suffix(".mas"), n)
    return CcxMatrices(K=K, M=M, node=node_dir[:, 0], direction=node_dir[:, 1])
