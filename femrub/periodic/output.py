"""A branch's results folder: ``branch.csv``, ``branch.png``, ``summary.json``, orbits.

* ``branch.csv``: one row per point, the parameter in a column named after its key (SI),
  the summary measures of one period (:func:`~femrub.periodic.continuation.measures`;
  ``max_tip_displacement`` in m), ``stable``, ``max_floquet_modulus``,
  ``unsettled_columns`` (finite-difference monodromy columns that depend on the step: the
  multipliers are uncertain when above 0), ``newton_iterations``, ``residual``,
  ``special`` (fold, period-doubling, neimark-sacker, branch-point, stability-change or
  empty), ``steps_per_period``,
  ``h`` (s), ``period`` (s);
* ``branch.png``: the first measure (the tip displacement) against the parameter, stable
  stretches solid, unstable dashed, special points marked;
* ``summary.json``: ``status`` (``ok`` only if every point converged and the branch reached
  its end; ``inaccurate`` when some points' multipliers are uncertain), ``message``, the
  key and range, counts, the special points, ``wall_seconds``;
* ``orbits/NNN/history.npz``: one period of each selected orbit with the keys of a run's
  history (``t``, ``gap``, ``impulse``, ``normal_force``, ``signal_<name>``).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from ..output.jsonfile import write_json
from ..output.safe_write import atomic_file

__all__ = ["write_branch"]

FIXED = (
    "stable",
    "max_floquet_modulus",
    "unsettled_columns",
    "newton_iterations",
    "residual",
    "special",
)


def _rows(branch) -> tuple[list, list]:
    measures = list(branch.points[0].measures) if branch.points else []
    head = [branch.key, *measures, *FIXED, "steps_per_period", "h", "period"]
    rows = []
    for p in branch.points:
        rows.append(
            [
                p.parameter,
                *(p.measures.get(m, math.nan) for m in measures),
                int(p.stable),
                p.max_floquet_modulus,
                p.unsettled,
                p.iterations,
                p.residual,
                p.special,
                p.steps,
                p.h,
                p.period,
            ]
        )
    return head, rows


def _write_csv(branch, path: Path) -> None:
    head, rows = _rows(branch)
    with atomic_file(path, "w") as fh:
        w = csv.writer(fh)
        w.writerow(head)
        w.writerows(rows)


def _plot(branch, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    if branch.points:
        name = next(iter(branch.points[0].measures))
        p, y = branch.parameter, branch.column(name)
        ok = np.array([q.stable for q in branch.points])
        for i in range(len(p) - 1):  # each segment in the style of its end points
            style = "-" if ok[i] and ok[i + 1] else "--"
            ax.plot(p[i : i + 2], y[i : i + 2], style, color="C0")
        marks = {
            "fold": "o",
            "period-doubling": "s",
            "neimark-sacker": "D",
            "branch-point": "^",
            "stability-change": "v",
        }
        for kind, marker in marks.items():
            idx = [i for i, q in enumerate(branch.points) if q.special == kind]
            if idx:
                ax.plot(p[idx], y[idx], marker, color="C3", label=kind)
        ax.plot([], [], "-", color="C0", label="stable")
        ax.plot([], [], "--", color="C0", label="unstable")
        ax.set_ylabel(f"{name} (SI)")
        ax.legend()
    ax.set_xlabel(f"{branch.key} (SI)")
    ax.set_title(f"periodic orbits: {branch.status}")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    with atomic_file(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=120)
    plt.close(fig)


def _write_orbit(model_of, branch, i: int, orbit, folder: Path) -> None:
    """One period of orbit ``i`` as ``history.npz`` with a run's keys."""
    point = branch.points[i]
    model = model_of(point.parameter)
    data = {"t": orbit.t, "impulse": orbit.P, "normal_force": orbit.P / point.h}
    if model.contact is not None:
        data["gap"] = np.asarray(model.contact.gap(orbit.t, orbit.X))
    for name, O in model.observations.items():
        data[f"signal_{name}"] = np.asarray(O @ orbit.X.T).T.squeeze()
    data["parameter"] = np.array(point.parameter)
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_file(folder / "history.npz", "wb") as fh:
        np.savez_compressed(fh, **data)


def write_branch(branch, out, *, model_of=None, extra: dict | None = None) -> dict:
    """Write ``branch`` into the folder ``out`` (module docstring); ``model_of``: the
    family ``p -> model`` for the orbits' signals (``None``: no orbits written); ``extra``:
    more entries of ``summary.json``. Returns the summary."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _write_csv(branch, out / "branch.csv")
    _plot(branch, out / "branch.png")
    orbits = []
    if model_of is not None:
        for i, orbit in branch.orbits.items():
            name = f"{i:03d}"
            _write_orbit(model_of, branch, i, orbit, out / "orbits" / name)
            orbits.append({"point": i, "folder": f"orbits/{name}"})
    pts = branch.points
    doc = {
        "status": branch.status,
        "message": branch.message,
        "key": branch.key,
        "points": len(pts),
        "converged": sum(p.converged for p in pts),
        "stable": sum(p.stable for p in pts),
        "range": [pts[0].parameter, pts[-1].parameter] if pts else [],
        "special": [
            {"point": i, "kind": p.special, branch.key: p.parameter}
            for i, p in enumerate(pts)
            if p.special
        ],
        "orbits": orbits,
        **(extra or {}),
    }
    write_json(out / "summary.json", doc)
    return doc
