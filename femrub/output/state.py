"""The state a stepper hands to output sinks after each step (:mod:`femrub.steppers.record`)."""

from __future__ import annotations

from ..steppers.record import State

__all__ = ["State"]
