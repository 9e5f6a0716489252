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

Per-step arrays of any trailing shape (``extra``, e.g. per-contact vectors) are flattened
into CSV columns by :func:`flatten_columns`; every CSV header carries its unit
(``t [s]``, :data:`UNITS`) and ``history.npz["meta"]`` holds the same units.
"""

from __future__ import annotations

import csv
import functools
import json
import os
import zipfile
import zlib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .balance import ENERGY_TERMS, HEAT_TERMS, balance_maxima, energy_error_of, heat_error_of
from .csv_rows import decimate_columns, write_csv_rows
from .jsonfile import jsonable

__all__ = [
    "ENERGY_KEYS",
    "PROBE_PREFIX",
    "UNITS",
    "Results",
    "csv_header",
    "flatten_columns",
    "npz_key",
    "signal_units",
    "unit_of",
]

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

#: units of the per-step arrays (SI); energy terms are in J
UNITS = {
    "t": "s",
    "tip_displacement": "m",
    "contact_displacement": "m",
    "tip_velocity": "m/s",
    "tip_temperature": "K",
    "contact_temperature": "K",
    "gap": "m",
    "gap_velocity": "m/s",
    "impulse": "N s",
    "contact_impulse": "N s",
    "normal_force": "N",
    "contact_force": "N",
    "friction_force": "N",
    "slip_velocity": "m/s",
    "contact_state": "-",
    "states": "SI (m, m/s, K by dof)",
    "state_times": "s",
    **{k: "J" for k in ENERGY_KEYS},
}


#: the per-contact friction arrays of ``history.npz`` (friction_limit: μ per contact)
_FRICTION_ARRAYS = ("friction_force", "slip_velocity", "contact_state", "friction_limit")


#: signals saved under their own name in ``history.npz`` (a probe ``probe_<name>``)
PROBE_PREFIX = "probe_"


def npz_key(signal: str) -> str:
    """The ``history.npz`` key of a signal: ``signal_<name>``, a probe under its own name."""
    return signal if signal.startswith(PROBE_PREFIX) else f"signal_{signal}"


def signal_units(model) -> dict[str, str]:
    """Units of ``model``'s signals that :data:`UNITS` does not know (probes, by signal
    name): ``model.info["signal_units"]``, or its full model's for a reduced model."""
    info = getattr(model, "info", None) or {}
    return dict(info.get("signal_units") or info.get("full_info", {}).get("signal_units") or {})


def unit_of(name: str) -> str:
    """SI unit of a per-step array (``"-"`` when unknown or dimensionless)."""
    for prefix in ("signal_", "energy_"):
        if name.startswith(prefix) and name[len(prefix) :] in UNITS:
            return UNITS[name[len(prefix) :]]
    return UNITS.get(name, "-")


def flatten_columns(arrays: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """One 1D column per component: ``(rows,)`` and ``(rows, 1)`` keep their name,
    ``(rows, k)`` gives ``name_j`` and ``(rows, k, m, ...)`` gives ``name_j_i...``."""
    cols = {}
    for name, arr in arrays.items():
        a = np.asarray(arr)
        if a.ndim == 1:
            cols[name] = a
            continue
        flat = a.reshape(a.shape[0], -1)
        if flat.shape[1] == 1 and a.ndim == 2:
            cols[name] = flat[:, 0]
            continue
        for idx in np.ndindex(*a.shape[1:]):
            cols[name + "".join(f"_{i}" for i in idx)] = a[(slice(None), *idx)]
    return cols


def csv_header(columns, units: dict[str, str]) -> list[str]:
    """Header cells ``"name [unit]"`` of flattened ``columns`` (``units`` by array name)."""
    out = []
    for col in columns:
        base = col
        while base not in units and "_" in base and base.rsplit("_", 1)[1].isdigit():
            base = base.rsplit("_", 1)[0]
        out.append(f"{col} [{units.get(base, unit_of(base))}]")
    return out


#: zlib level of ``history.npz`` (1: float histories barely compress more at 6, 1.5× slower)
NPZ_LEVEL = 1
#: zlib strategies of ``history.npz``, the first that deflates an array's samples enough
#: (:data:`NPZ_DEFLATE_BELOW`): run-length matches only, then the default. A run's impulses
#: and friction forces are mostly zero: run lengths deflate them to the same size as the
#: default (Rotor 37, 50,000 steps: 0.287 against 0.292 of their bytes) in a third to a half
#: of the time; arrays with other repeats (a bar's states) need the default. The file is
#: ordinary deflate, read by ``numpy.load`` and any unzip
NPZ_STRATEGIES = (zlib.Z_RLE, zlib.Z_DEFAULT_STRATEGY)
#: an array of ``history.npz`` is written deflated only when samples of its bytes deflate
#: below this share of their size: the gaps, displacements and slip velocities of a long
#: run deflate to 90-95 % and are stored as they are (Rotor 37, 50,000 steps: the file 5 %
#: larger, written in a third of the time); impulses and friction forces, mostly zero,
#: deflate to 30 %
NPZ_DEFLATE_BELOW = 0.8
#: the samples: this many slices of :data:`NPZ_SAMPLE_BYTES`, spread over an array's bytes
#: (64 KiB an array: a quarter of the time 256 KiB took, a Rotor 37 point's arrays alike)
NPZ_SAMPLES, NPZ_SAMPLE_BYTES = 16, 1 << 12
#: rows of a per-step array reduced at a time (bounds the temporaries of a long run's measures)
ROW_BLOCK = 65536


def _deflater(strategy: int):
    """A raw deflate stream (as a ZIP member holds it) at :data:`NPZ_LEVEL` and ``strategy``."""
    return zlib.compressobj(NPZ_LEVEL, zlib.DEFLATED, -15, 9, strategy)


def _strategy(a: np.ndarray) -> int | None:
    """The first of :data:`NPZ_STRATEGIES` that deflates samples of ``a`` below
    :data:`NPZ_DEFLATE_BELOW` of their size, or ``None``: ``a`` is stored as it is (small
    arrays are deflated by the default strategy)."""
    if a.dtype.hasobject or a.nbytes <= NPZ_SAMPLES * NPZ_SAMPLE_BYTES:
        return zlib.Z_DEFAULT_STRATEGY
    raw = np.ascontiguousarray(a).reshape(-1).view(np.uint8)
    starts = np.linspace(0, raw.size - NPZ_SAMPLE_BYTES, NPZ_SAMPLES).astype(int)
    sample = b"".join(raw[i : i + NPZ_SAMPLE_BYTES].tobytes() for i in starts)
    for strategy in NPZ_STRATEGIES:
        z = _deflater(strategy)
        if len(z.compress(sample) + z.flush()) < NPZ_DEFLATE_BELOW * len(sample):
            return strategy
    return None


def _savez(path: Path, arrays: dict) -> None:
    """``numpy.savez_compressed``'s format at zlib level :data:`NPZ_LEVEL` (read by
    ``numpy.load``), each array deflated by its strategy (:func:`_strategy`) or stored as
    it is."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=NPZ_LEVEL) as zf:
        for key, value in arrays.items():
            a = np.asanyarray(value)
            strategy = _strategy(a)
            zf.compression = zipfile.ZIP_STORED if strategy is None else zipfile.ZIP_DEFLATED
            with zf.open(key + ".npy", "w", force_zip64=True) as f:
                _use_strategy(f, strategy)
                np.lib.format.write_array(f, a, allow_pickle=False)


def _use_strategy(member, strategy: int | None) -> None:
    """Deflate the ZIP member being written with ``strategy`` (``zipfile`` offers the
    level, not the strategy: its writer's compressor, made by ``ZipFile.open`` and fed by
    its ``write``, is replaced before any byte; left as it is for the default strategy, a
    stored member or a ``zipfile`` without that attribute)."""
    if strategy not in (None, zlib.Z_DEFAULT_STRATEGY):
        if getattr(member, "_compressor", None) is not None:
            member._compressor = _deflater(strategy)


class Snapshot(NamedTuple):
    """A run's whole state after its step ``step``: the time ``t`` (s), the state ``X`` and
    the state of the history its contact carries outside ``X`` (:meth:`Contact.history_snapshot
    <femrub.contact.gap.Contact.history_snapshot>`, ``()`` without). A stepper restarted
    from it (:meth:`Stepper.restart(X, t, history) <femrub.steppers.base.Stepper.restart>`)
    continues the run."""

    step: int
    t: float
    X: np.ndarray
    history: tuple


@dataclass
class Results:
    """What a stepper's ``run()`` returns.

    ``status`` is ``"ok"``, ``"inaccurate"`` (a reduced run whose estimated error exceeds
    ``reduction.tolerance``, set by the run folder), ``"unstable"`` (numerical blow-up or a
    step above the scheme's stability limit), ``"diverged-physically"`` (a physical stop
    criterion was reached), ``"interrupted"`` or ``"failed"``; the arrays hold everything
    computed up to then. ``checks``: what the verdict reads of the rows a lean record did not
    keep (:mod:`femrub.output.kept_rows`: ``energy_error``, ``heat_error``, ``coulomb``).
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
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    checks: dict = field(default_factory=dict)
    #: the run's contact with the history it carried outside ``X`` at the run's end (an
    #: abradable coating's wear map, the casing's heat: ``Contact.carried_state``), or ``None``
    contact_history: object = None
    #: the run's :class:`Snapshot` at the steps ``RunOptions.snapshots`` asked for
    snapshots: list = field(default_factory=list)

    @property
    def force(self) -> np.ndarray:
        """Mean contact force over each step, ``impulse / h`` (N)."""
        return self.impulse / self.h

    @functools.cached_property
    def coulomb(self) -> dict | None:
        """:func:`~femrub.contact.friction.coulomb_check` of every recorded step (``None``
        without friction rows), measured once for the verdict and the summary; a lean
        record's is the one measured as its rows passed (``checks["coulomb"]``)."""
        ff = self.friction_force
        if ff is None:
            return self.checks.get("coulomb")
        if not ff.size or self.friction_limit is None:
            return None
        from ..contact.friction import coulomb_check

        return coulomb_check(
            self.force, ff, self.slip_velocity, self.contact_state, self.friction_limit
        )

    def friction_magnitude(self) -> np.ndarray:
        """``|λ_t| / h`` per row and contact (N), ``(rows, n_c)``: the norms of
        ``friction_force`` taken :data:`ROW_BLOCK` rows at a time (no ``(rows, n_c, 3)``
        temporaries on a long run); ``(rows, 0)`` without friction rows."""
        ff = self.friction_force
        if ff is None:
            return np.zeros((len(self.t), 0))
        out = np.empty(ff.shape[:-1])
        for k in range(0, len(ff), ROW_BLOCK):
            out[k : k + ROW_BLOCK] = np.linalg.norm(ff[k : k + ROW_BLOCK], axis=-1)
        return out

    def signal(self, name: str, component: int | None = None) -> np.ndarray:
        """An observed signal, e.g. ``signal("tip_displacement")``: ``(rows,)`` for a signal
        of one component, ``(rows, k)`` for one of ``k`` (``contact_displacement``: one
        column per contact), or its column ``component``."""
        if name not in self.signals:
            raise KeyError(f"no signal {name!r}; available: {', '.join(self.signals)}")
        values = self.signals[name]
        k = values.shape[1]
        if component is None:
            return values[:, 0] if k == 1 else values
        if not -k <= component < k:
            raise IndexError(f"signal {name!r} has {k} components; component {component} asked")
        return values[:, component]

    def probe(self, name: str) -> np.ndarray:
        """The history ``(rows,)`` of the probe ``name`` (``outputs.probes``; SI units:
        ``info["signal_units"]``)."""
        key = PROBE_PREFIX + name
        if key not in self.signals:
            names = [k[len(PROBE_PREFIX) :] for k in self.signals if k.startswith(PROBE_PREFIX)]
            raise KeyError(f"no probe {name!r}; probes of this run: {', '.join(names) or 'none'}")
        return self.signals[key][:, 0]

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
        if "energy_error" not in self.energy or self.t.size < 2:  # lean: measured, or NaN
            return float(np.nan if (v := self.checks.get("energy_error")) is None else v)
        return energy_error_of(balance_maxima(self.energy, terms=ENERGY_TERMS))

    def heat_error(self) -> float:
        """Largest heat-balance residual relative to the heat scale of the run (0 when no
        heat enters or leaves; NaN without a heat balance)."""
        e = self.energy
        if "heat_error" not in e or self.t.size < 2:
            return float(np.nan if (v := self.checks.get("heat_error")) is None else v)
        return heat_error_of(balance_maxima(e, terms=HEAT_TERMS))

    def per_step(self) -> dict[str, np.ndarray]:
        """Every per-step array by name (rows = times), before flattening."""
        arrays = {"t": self.t, **self.signals}
        if self.impulse.shape[1]:
            arrays.update(gap=self.gap, contact_force=self.force, contact_impulse=self.impulse)
        arrays.update(self.extra)
        arrays.update(self.energy)
        return arrays

    def columns(self) -> dict[str, np.ndarray]:
        """Flat table: time, every signal component, gap, force, impulse, extra, energy."""
        return flatten_columns(self.per_step())

    def units(self) -> dict[str, str]:
        """SI unit of every ``history.npz`` array, by key."""
        names = ["t", "gap", "impulse", "normal_force", *map(npz_key, self.signals)]
        names += list(self.extra)
        names += [k for k in _FRICTION_ARRAYS if getattr(self, k) is not None]
        names += [f"energy_{k}" for k in self.energy]
        own = self.info.get("signal_units", {})
        return {k: own.get(k, unit_of(k)) for k in names}

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
        tmp = path.with_name(path.name + ".tmp")
        with tmp.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(csv_header(cols, {**UNITS, **self.info.get("signal_units", {})}))
            if digits is None:
                write_csv_rows(fh, table)
            else:
                fmt = ",".join([f"%.{int(digits)}g"] * table.shape[1])
                np.savetxt(fh, table, fmt=fmt, delimiter=",")
        os.replace(tmp, path)
        return path

    def decimated(self, every: int) -> Results:
        """The history at one row in ``every`` steps (rows ``0, every, 2 every, …`` and the
        last), for storage.

        ``impulse`` and the friction impulse are summed over the steps since the previous
        row, ``(t_{j-1}, t_j]``, and ``h`` becomes the row spacing ``every · h``, so
        ``force = impulse / h`` is the mean force over a row and the total impulse is kept;
        every other array is its value at the row's time. ``info`` records the integration
        step (``step``) and ``every``; ``steps`` and ``cpu_seconds`` are the run's.
        """
        every = int(every)
        n = self.t.size
        if every <= 1 or n < 2:
            return self
        idx = np.unique(np.r_[np.arange(0, n, every), n - 1])

        def summed(a):
            out = a[idx].copy()
            out[1:] = np.add.reduceat(a, idx[:-1] + 1, axis=0)
            return out

        def at(a):
            return None if a is None else np.asarray(a)[idx].copy()

        h_row = self.h * every
        ff = self.friction_force
        return replace(
            self,
            h=h_row,
            t=self.t[idx].copy(),
            signals={k: at(v) for k, v in self.signals.items()},
            gap=at(self.gap),
            impulse=summed(self.impulse),
            energy={k: at(v) for k, v in self.energy.items()},
            friction_force=None if ff is None else summed(ff * self.h) / h_row,
            slip_velocity=at(self.slip_velocity),
            contact_state=at(self.contact_state),
            info={**self.info, "step": self.h, "every": every},
            extra={k: at(v) for k, v in self.extra.items()},
            warnings=list(self.warnings),
        )

    def lean(self) -> Results:
        """The results with only what a comparison of runs reads (times, impulses, signals,
        checkpoint states, status): gaps, friction rows, energy balance and extra rows
        dropped, so that runs held together for an error estimate stay small."""
        return replace(
            self,
            gap=self.gap[:, :0],
            energy={},
            friction_force=None,
            slip_velocity=None,
            contact_state=None,
            extra={},
        )

    def save_npz(self, path) -> Path:
        """Every step, compressed where it pays (``numpy.savez_compressed``'s format, zlib
        level :data:`NPZ_LEVEL`, :func:`_savez`); :meth:`load_npz` reads it."""
        path = Path(path)
        meta = {
            "scheme": self.scheme,
            "h": self.h,
            "status": self.status,
            "message": self.message,
            "steps": self.steps,
            "cpu_seconds": self.cpu_seconds,
            "info": self.info,
            "warnings": self.warnings,
            "checks": self.checks,
            "units": self.units(),
        }
        arrays = {npz_key(k): v for k, v in self.signals.items()}
        arrays.update(self.extra)
        arrays.update({f"energy_{k}": v for k, v in self.energy.items()})
        if self.states is not None:
            arrays["states"], arrays["state_times"] = self.states, self.state_times
        for k in _FRICTION_ARRAYS:
            if getattr(self, k) is not None:
                arrays[k] = getattr(self, k)
        tmp = path.with_name(path.name + ".tmp.npz")
        _savez(
            tmp,
            dict(
                t=self.t,
                gap=self.gap,
                impulse=self.impulse,
                normal_force=self.force,
                meta=json.dumps(jsonable(meta), allow_nan=False),
                **arrays,
            ),
        )
        os.replace(tmp, path)
        return path

    @classmethod
    def load_npz(cls, path) -> Results:
        with np.load(path) as d:
            meta = json.loads(str(d["meta"]))
            signals = {k[7:]: d[k] for k in d.files if k.startswith("signal_")}
            signals.update({k: d[k] for k in d.files if k.startswith(PROBE_PREFIX)})
            energy = {k[7:]: d[k] for k in d.files if k.startswith("energy_")}
            states = d["states"] if "states" in d.files else None
            stimes = d["state_times"] if "state_times" in d.files else None
            known = {"t", "gap", "impulse", "normal_force", "meta", "states", "state_times"}
            friction = {k: d[k] for k in _FRICTION_ARRAYS if k in d.files}
            extra = {
                k: d[k]
                for k in d.files
                if k not in known
                and k not in _FRICTION_ARRAYS
                and not k.startswith(("signal_", "energy_", PROBE_PREFIX))
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
                extra=extra,
                warnings=meta.get("warnings", []),
                checks=meta.get("checks", {}),
                **friction,
            )
