"""Reading work–precision rows at an error level (``benchmarks/exponential*.py``)."""

from __future__ import annotations

TARGET = 3.0  # the target: 3x cheaper than both θ and Carpenter at 1 %
#: the blade's θ on its compiled friction blocks, μ = 1e-9 (benchmarks/exponential.py::blade)
THETA_BLOCKS = "θ compiled (μ = 1e-9)"
OTHERS = ("θ paper", THETA_BLOCKS, "Carpenter")


def cheapest(rows, key, level):
    """Per method: the cheapest run with ``key <= level``."""
    out = {}
    for r in rows:
        if r[key] <= level and (r["method"] not in out or r["cpu"] < out[r["method"]]["cpu"]):
            out[r["method"]] = r
    return out


def steadily(rows, key, level):
    """Per method: its run at the coarsest step from which every finer step of the method
    is within ``level`` (where the error does not fall monotonically with the step, the
    cheapest run within ``level`` may be a lucky one; this one is not)."""
    out = {}
    for method in dict.fromkeys(r["method"] for r in rows):
        runs = sorted((r for r in rows if r["method"] == method), key=lambda r: r["h"])
        for r in runs:  # finest first: stop at the first step above the level
            if not (r.get(key) is not None and r[key] <= level):
                break
            out[method] = r
    return out
