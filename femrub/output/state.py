"""The state a stepper hands to output sinks after each step."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["State"]


@dataclass
class State:
    """The state after step ``k``: time, state vector and contact quantities of the step."""

    k: int
    t: float
    X: np.ndarray
    impulse: np.ndarray
    gap: np.ndarray
    gap_velocity: np.ndarray
    friction_impulse: np.ndarray | None = None
