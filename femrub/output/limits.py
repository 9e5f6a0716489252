"""Physical stop criteria of a run: ``{signal name or "contact_force": max |value|}``.

Every run is judged with stop limits, whichever entry point started it (``femrub run``, a
Python ``stepper.run(t_end)``, the reduction estimate, the time-step check): unless turned
off, :func:`default_limits` bounds the model's observed signals physically,

* a temperature signal (name ending in ``temperature``, K above ambient) by
  :data:`MAX_TEMPERATURE_RISE` (titanium melts about 1650 K above ambient),
* a displacement signal (name ending in ``displacement``, m) by :data:`MAX_DISPLACEMENT_RATIO`
  times the model's ``length_scale`` (m, its blade's size); a model that does not know its
  size (``length_scale`` NaN or absent) gets no displacement limit: no bound on a
  displacement can be justified without a length, and a run that blows up is still stopped
  by its non-finite states and its energy balance.

A given limit replaces the default of its signal; ``inf`` turns one off; the run option
``default_limits=False`` keeps only the given ones. Reaching a limit ends the run with status
``"diverged-physically"``. :class:`~femrub.output.recorder.Recorder` checks each chunk of
rows against them.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "MAX_DISPLACEMENT_RATIO",
    "MAX_TEMPERATURE_RISE",
    "default_limits",
    "limit_hit",
    "limit_index",
    "model_limits",
    "run_limits",
]

#: default stop limit on temperature signals (K above ambient; titanium melts ~1650 K above)
MAX_TEMPERATURE_RISE = 1500.0
#: default stop limit on displacement signals, relative to the blade's size
MAX_DISPLACEMENT_RATIO = 0.1


def default_limits(observed, size: float) -> dict[str, float]:
    """Physical stop limits on the ``observed`` signal names for a blade of ``size`` (m;
    NaN: no displacement limit), see the module docstring."""
    out = {}
    for name in observed:
        if name.endswith("temperature"):
            out[name] = MAX_TEMPERATURE_RISE
        elif name.endswith("displacement") and math.isfinite(size):
            out[name] = MAX_DISPLACEMENT_RATIO * size
    return out


def model_limits(model) -> dict[str, float]:
    """:func:`default_limits` of ``model``'s observations and ``length_scale`` (m)."""
    size = float(getattr(model, "length_scale", math.nan))
    return default_limits(model.observations, size)


def run_limits(model, limits=None, defaults: bool = True) -> dict[str, float]:
    """The stop limits a run of ``model`` checks: the given ``limits`` over the model's
    defaults (``defaults=False``: the given ones only); an infinite bound is no limit."""
    out = model_limits(model) if defaults else {}
    out.update(limits or {})
    return {k: float(v) for k, v in out.items() if not math.isinf(float(v))}


def limit_index(limits, names, sizes):
    """Columns of each observed signal in the observation rows; checks the limit names."""
    idx, col = {}, 0
    for name, size in zip(names, sizes):
        idx[name] = slice(col, col + size)
        col += size
    for key in limits:
        if key != "contact_force" and key not in idx:
            raise ValueError(f"stop limit on unknown signal {key!r}; use one of {names}")
    return idx


def limit_hit(limits, idx, rows, force):
    """First ``(row, message)`` where a stop limit is exceeded in a block, or ``None``."""
    first = None
    for key, bound in limits.items():
        vals = force if key == "contact_force" else rows[:, idx[key]]
        if vals.size:
            over = np.any(np.abs(vals) > bound, axis=1)
            if over.any() and (first is None or np.argmax(over) < first[0]):
                first = (int(np.argmax(over)), f"{key} exceeded {bound:g}")
    return first
