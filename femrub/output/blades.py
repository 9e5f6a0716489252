"""Blade by blade: what each blade of a bladed disk went through in a run.

A bladed disk's contacts are ``blade{s}_contact{p}``, blade by blade (``N`` blades of
``n_c`` contacts, :mod:`femrub.model.wheel`); its signals hold each blade's mean normal tip
displacement (``blade_tip_displacement``) and, with the blades' temperature, each blade's
mean tip temperature (``blade_tip_temperature``). :func:`blade_table` reduces a run's
histories to one row per blade, :func:`write_blades` writes it as ``blades.csv`` (SI units)
and adds the blades whose extremes are the wheel's to ``summary.json``.

A tuned wheel's blades share their rows up to the travelling phase (the same forces and
displacements, later or earlier), so unequal rows show mistuning or a response that is not
a travelling wave (localisation, a transient).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .jsonfile import read_json, write_json

__all__ = ["BLADE_COLUMNS", "blade_table", "write_blades"]

#: the columns of ``blades.csv`` and their units
BLADE_COLUMNS = {
    "blade": "-",
    "max_normal_force_n": "N",
    "max_friction_force_n": "N",
    "contact_time_fraction": "-",
    "normal_impulse_ns": "N s",
    "rms_tip_displacement_m": "m",
    "max_abs_tip_displacement_m": "m",
    "max_tip_temperature_k": "K",
    "max_incursion_m": "m",
}


def blade_table(res, n_blades: int, incursion=None) -> dict[str, np.ndarray]:
    """``{column: (N,) values}`` of :data:`BLADE_COLUMNS` from the run ``res``
    (:class:`~femrub.output.results.Results`) of a wheel of ``n_blades`` blades.

    Per blade ``s``, over its contacts and the recorded steps: the largest normal force
    ``P / h`` (N) and friction force ``|P_t| / h`` (N); the share of the steps in which any
    of its contacts carried an impulse; the total normal impulse (N s); the RMS and largest
    ``|.|`` of its mean normal tip displacement (m); its largest mean tip temperature rise
    (K; ``nan`` without temperature dofs); with an abradable coating, ``incursion`` ``(N n_c,)``
    (:attr:`~femrub.contact.abradable.Abradable.incursion`), the deepest its contacts went
    below the unworn coating (m; ``nan`` without a coating).
    """
    N = int(n_blades)
    impulse = np.asarray(res.impulse, dtype=float).reshape(res.impulse.shape[0], N, -1)
    force = impulse / res.h
    table = {
        "blade": np.arange(N),
        "max_normal_force_n": force.max(axis=(0, 2)) if force.size else np.zeros(N),
        "max_friction_force_n": np.zeros(N),
        "contact_time_fraction": (impulse > 0.0).any(axis=2).mean(axis=0),
        "normal_impulse_ns": impulse.sum(axis=(0, 2)),
    }
    if res.friction_force is not None and np.size(res.friction_force):
        ff = np.linalg.norm(np.asarray(res.friction_force, dtype=float), axis=-1)
        table["max_friction_force_n"] = ff.reshape(ff.shape[0], N, -1).max(axis=(0, 2))
    tip = np.asarray(res.signal("blade_tip_displacement"), dtype=float).reshape(-1, N)
    table["rms_tip_displacement_m"] = np.sqrt(np.mean(tip**2, axis=0))
    table["max_abs_tip_displacement_m"] = np.abs(tip).max(axis=0)
    hot = res.signals.get("blade_tip_temperature")
    table["max_tip_temperature_k"] = (
        np.full(N, np.nan) if hot is None else np.asarray(hot, dtype=float).max(axis=0)
    )
    table["max_incursion_m"] = (
        np.full(N, np.nan)
        if incursion is None
        else np.clip(np.asarray(incursion, dtype=float).reshape(N, -1), 0.0, None).max(axis=1)
    )
    return table


def write_blades(res, n_blades: int, out, incursion=None) -> dict:
    """Write ``blades.csv`` (one row per blade, :data:`BLADE_COLUMNS`) into ``out`` and add
    ``blades`` to ``out/summary.json``: the blade with the largest normal force, the largest
    tip displacement and (with temperatures) the hottest tip, with those values, and the
    largest-to-smallest ratio of the blades' RMS tip displacements (1 for identical
    blades), with a coating the blade that went deepest into it; return that entry."""
    out = Path(out)
    table = blade_table(res, n_blades, incursion)
    columns = list(BLADE_COLUMNS)
    data = np.column_stack([table[c] for c in columns])
    header = ",".join(columns)
    fmt = ["%d"] + ["%.8g"] * (len(columns) - 1)
    np.savetxt(out / "blades.csv", data, delimiter=",", header=header, comments="", fmt=fmt)
    rms = table["rms_tip_displacement_m"]
    entry = {
        "n_blades": int(n_blades),
        "most_loaded": _extreme(table, "max_normal_force_n"),
        "largest_tip_displacement": _extreme(table, "max_abs_tip_displacement_m"),
        "rms_tip_displacement_spread": float(rms.max() / rms.min()) if rms.min() > 0 else None,
    }
    if np.all(np.isfinite(table["max_tip_temperature_k"])):
        entry["hottest_tip"] = _extreme(table, "max_tip_temperature_k")
    if incursion is not None:
        entry["deepest_incursion"] = _extreme(table, "max_incursion_m")
    summary = read_json(out / "summary.json")
    summary["blades"] = entry
    write_json(out / "summary.json", summary)
    return entry


def _extreme(table: dict, column: str) -> dict:
    s = int(np.argmax(table[column]))
    return {"blade": s, column: float(table[column][s])}
