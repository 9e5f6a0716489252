"""The errors of the energy and heat balances from the largest magnitudes of their terms.

``Results.energy_error`` / ``heat_error`` measure them on a run's whole per-step arrays, a
lean record (:mod:`femrub.output.kept_rows`) on its rows as they pass; both read the same
maxima through the same formulas::

    energy_error = max |residual| / max(max |kinetic + elastic|, max |external work|,
                                        max |thermal work|)
    heat_error   = max |residual| / max(heat content, friction heat, heat load, outflow)
                   (0 when no heat enters or leaves)
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "BALANCE_TERMS",
    "ENERGY_TERMS",
    "HEAT_TERMS",
    "balance_maxima",
    "energy_error_of",
    "heat_error_of",
]

#: the terms whose largest magnitudes make the two errors ("mechanical": kinetic + elastic)
BALANCE_TERMS = (
    "energy_error",
    "mechanical",
    "external_work",
    "thermal_work",
    "heat_error",
    "heat_content",
    "friction_heat",
    "heat_load",
    "heat_outflow",
)
#: the terms of :func:`energy_error_of` and of :func:`heat_error_of`
ENERGY_TERMS, HEAT_TERMS = BALANCE_TERMS[:4], BALANCE_TERMS[4:]


def balance_maxima(energy: dict, rows=slice(None), terms=BALANCE_TERMS) -> dict:
    """The largest magnitude of each of ``terms`` over ``rows`` of the per-step balance
    arrays ``energy`` (the meter's keys)."""
    out = {}
    for k in terms:
        v = energy["kinetic"][rows] + energy["elastic"][rows] if k == "mechanical" else None
        out[k] = float(np.max(np.abs(energy[k][rows] if v is None else v)))
    return out


def energy_error_of(mx: dict) -> float:
    """Largest mechanical balance residual relative to the run's energy scale."""
    scale = max(mx["mechanical"], mx["external_work"], mx["thermal_work"], 1e-300)
    return float(mx["energy_error"] / scale)


def heat_error_of(mx: dict) -> float:
    """Largest heat-balance residual relative to the run's heat scale (0 without heat)."""
    scale = max(mx[k] for k in HEAT_TERMS[1:])
    return float(mx["heat_error"] / scale) if scale > 0 else 0.0
