"""Time histories of a run: signals, contact, energy balance; saved to CSV and ``.npz``.

Arrays have one row per stored time. Contact quantities at time ``t_k`` refer to the step
``(t_{k-1}, t_k]``: ``impulse`` (N s) and ``force = impulse / h`` (N), the paper's λ_k.

Energy columns (J), cumulative from ``t = 0``:
``kinetic``, ``elastic`` (mechanical energy ``E = kinetic + elastic``), ``external_work``,
``thermal_work`` (work of the thermal stresses on the structure), ``damping_work`` (<= 0),
``contact_work`` (<= 0 when no energy is created at contacts; ``impact_dissipation`` is its
opposite), ``heat_content`` (J above ambient), ``friction_heat`` (Σ α × impulse),
``heat_load``, ``heat_outflow`` (through the boundaries), and the balance residuals
``energy_error = E − E0 − (external + thermal + damping + contact work)`` and
``heat_error = Q − Q0 − (friction_heat + heat_load − heat_outflow)``.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Results", "ENERGY_KEYS", "decimate_columns"]

ENERGY_KEYS = (
    "kinetic",
    "elastic",
    "external_work",
    "thermal_work",
    "damping_work",
    "contact_work",
    "impact_dissipation",
    "heat_content",
    "friction_heat",
    "heat_load",
    "heat_outflow",
    "energy_error",
    "heat_error",
)


@dataclass
class Results:
    """What a stepper's ``run()`` returns.

    ``status`` is ``"ok"``, ``"unstable"`` (numerical blow-up or a step above the scheme's
    stability limit), ``"diverged-physically"`` (a physical stop criterion was reached),
    ``"interrupted"`` or ``"failed"``; the arrays hold everything computed up to then.
    """

    scheme: str
    h: float
    t: np.ndarray
    signals: dict[str, np.ndarray]
    gap: np.ndarray
    impulse: np.ndarray
    energy: dict[str, np.ndarray] = field(default_factory=dict)
    status: str = "ok"
    message: str = ""
    steps: int = 0
    cpu_seconds: float = 0.0
    states: np.ndarray | None = None
    state_times: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    @property
    def force(self) -> np.ndarray:
        """Mean contact force over each step, ``impulse / h`` (N)."""
        return self.impulse / self.h

    def signal(self, name: str, component: int = 0) -> np.ndarray:
        """One component of an observed signal, e.g. ``signal("tip_displacement")``."""
        if name not in self.signals:
            raise KeyError(f"no signal {name!r}; available: {', '.join(self.signals)}")
        return self.signals[name][:, component]

    def contact_phases(self, threshold: float = 0.0) -> list[tuple[float, float]]:
        """Intervals ``(start, end)`` during which any contact carries an impulse."""
        on = np.any(self.impulse > threshold, axis=1)
        if not on.any():
            return []
        edges = np.diff(np.concatenate([[0], on.astype(int), [0]]))
        starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
        return [(float(self.t[s]), float(self.t[e])) for s, e in zip(starts, ends)]

    def first_contact_time(self) -> float | None:
        phases = self.contact_phases()
        return phases[0][0] if phases else None

    def energy_error(self) -> float:
        """Largest mechanical balance residual relative to the energy scale of the run."""
        if "energy_error" not in self.energy or self.t.size < 2:
            return float("nan")
        e = self.energy
        scale = max(
            np.max(np.abs(e["kinetic"] + e["elastic"])),
            np.max(np.abs(e["external_work"])),
            np.max(np.abs(e["thermal_work"])),
            1e-300,
        )
        return float(np.max(np.abs(e["energy_error"])) / scale)

    def heat_error(self) -> float:
        """Largest heat-balance residual relative to the heat scale of the run (0 when no
        heat enters or leaves; NaN without a heat balance)."""
        e = self.energy
        if "heat_error" not in e or self.t.size < 2:
            return float("nan")
        scale = max(
            np.max(np.abs(e[k]))
            for k in ("heat_content", "friction_heat", "heat_load", "heat_outflow")
        )
        return float(np.max(np.abs(e["heat_error"])) / scale) if scale > 0 else 0.0

    def columns(self) -> dict[str, np.ndarray]:
        """Flat table: time, every signal component, gap, force, impulse, energy."""
        cols = {"t": self.t}
        for name, arr in self.signals.items():
            if arr.shape[1] == 1:
                cols[name] = arr[:, 0]
            else:
                for j in range(arr.shape[1]):
                    cols[f"{name}_{j}"] = arr[:, j]
        nc = self.impulse.shape[1]
        for j in range(nc):
            sfx = "" if nc == 1 else f"_{j}"
            cols[f"gap{sfx}"] = self.gap[:, j]
            cols[f"contact_force{sfx}"] = self.force[:, j]
            cols[f"contact_impulse{sfx}"] = self.impulse[:, j]
        cols.update(self.energy)
        return cols

    def save_csv(self, path, every: int = 1, digits: int | None = None) -> Path:
        """Write :meth:`columns` as CSV, every step or one row in ``every``; ``digits``:
        significant digits of the numbers (``None``: every digit, ``repr``).

        With ``every > 1`` the rows are the first step and every ``every``-th one (and the
        last); ``contact_impulse*`` is summed over the steps since the previous row and
        ``contact_force*`` is that impulse over the time since the previous row (the mean
        force), so the CSV keeps the total impulse; other columns are the values at the
        row's time. :meth:`save_npz` keeps every step.
        """
        path = Path(path)
        cols = self.columns()
        if every > 1:
            cols = decimate_columns(cols, int(every))
        table = np.column_stack(list(cols.values()))
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(list(cols))
            if digits is None:
                w.writerows(table.tolist())
            else:
                fmt = ",".join([f"%.{int(digits)}g"] * table.shape[1])
                np.savetxt(fh, table, fmt=fmt, delimiter=",")
        return path

    def save_npz(self, path) -> Path:
        """Every step, compressed (``numpy.savez_compressed``); :meth:`load_npz` reads it."""
        path = Path(path)
        meta = {
            "scheme": self.scheme,
            "h": self.h,
            "status": self.status,
            "message": self.message,
            "steps": self.steps,
            "cpu_seconds": self.cpu_seconds,
            "info": self.info,
        }
        arrays = {f"signal_{k}": v for k, v in self.signals.items()}
        arrays.update({f"energy_{k}": v for k, v in self.energy.items()})
        if self.states is not None:
            arrays["states"], arrays["state_times"] = self.states, self.state_times
        np.savez_compressed(
            path,
            t=self.t,
            gap=self.gap,
            impulse=self.impulse,
            normal_force=self.force,
            meta=json.dumps(meta, default=str),
            **arrays,
        )
        return path

    @classmethod
    def load_npz(cls, path) -> Results:
        with np.load(path) as d:
            meta = json.loads(str(d["meta"]))
            signals = {k[7:]: d[k] for k in d.files if k.startswith("signal_")}
            energy = {k[7:]: d[k] for k in d.files if k.startswith("energy_")}
            states = d["states"] if "states" in d.files else None
            stimes = d["state_times"] if "state_times" in d.files else None
            return cls(
                scheme=meta["scheme"],
                h=meta["h"],
                t=d["t"],
                signals=signals,
                gap=d["gap"],
                impulse=d["impulse"],
                energy=energy,
                status=meta["status"],
                message=meta["message"],
                steps=meta["steps"],
                cpu_seconds=meta["cpu_seconds"],
                states=states,
                state_times=stimes,
                info=meta.get("info", {}),
            )


def decimate_columns(cols: dict, every: int) -> dict:
    """Rows ``0, every, 2 every, …, last`` of ``cols`` (see :meth:`Results.save_csv`)."""
    t = cols["t"]
    idx = np.unique(np.r_[np.arange(0, t.size, every), t.size - 1]) if t.size else t.astype(int)
    out = {k: np.asarray(v)[idx].copy() for k, v in cols.items()}
    if idx.size < 2:
        return out
    dt = np.diff(t[idx])
    for k in cols:
        if k.startswith("contact_impulse"):
            total = np.add.reduceat(np.asarray(cols[k]), idx[:-1] + 1)  # (idx[j-1], idx[j]]
            out[k][1:] = total
            force = "contact_force" + k[len("contact_impulse") :]
            if force in out:
                out[force][1:] = total / np.where(dt > 0, dt, np.inf)
    return out
