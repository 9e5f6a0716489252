"""Time histories of a run: signals, contact, energy balance; saved to CSV and ``.npz``.

Arrays have one row per stored time. Contact quantities at time ``t_k`` refer to the step
``(t_{k-1}, t_k]``: ``impulse`` (N s) and ``force = impulse / h`` (N), the paper's λ_k.

Energy columns (J), cumulative from ``t = 0``:
``kinetic``, ``elastic`` (mechanical energy ``E = kinetic + elastic``), ``external_work``,
``thermal_work`` (work of the thermal stresses on the structure), ``damping_work`` (<= 0),
``contact_work`` (<= 0 when no energy is created at contacts; ``impact_dissipation`` is its
opposite), ``heat_content`` (J above ambient), ``friction_heat`` (Σ α × impulse),
``heat_load``, ``heat_outflow`` (through the boundaries), with Coulomb friction
``friction_work`` (friction dissipation, >= 0), ``casing_work`` (work of the moving casing
through friction; ``contact_work`` = normal work + ``casing_work`` − ``friction_work``) and
``heat_to_casing`` (the friction power not put into the blade), and the balance residuals
``energy_error = E − E0 − (external + thermal + damping + contact work)`` and
``heat_error = Q − Q0 − (friction_heat + heat_load − heat_outflow)``.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Results", "ENERGY_KEYS"]

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
    "friction_work",
    "casing_work",
    "heat_to_casing",
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
    friction_force: np.ndarray | None = None
    slip_velocity: np.ndarray | None = None
    contact_state: np.ndarray | None = None
    friction_limit: np.ndarray | None = None
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

    def save_csv(self, path) -> Path:
        path = Path(path)
        cols = self.columns()
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(list(cols))
            w.writerows(np.column_stack(list(cols.values())).tolist())
        return path

    def save_npz(self, path) -> Path:
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
        for k in ("friction_force", "slip_velocity", "contact_state", "friction_limit"):
            if getattr(self, k) is not None:
                arrays[k] = getattr(self, k)
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
            extra = {
                k: d[k]
                for k in ("friction_force", "slip_velocity", "contact_state", "friction_limit")
                if k in d.files
            }
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
                **extra,
            )
