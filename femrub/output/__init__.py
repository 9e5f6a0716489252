"""Output: recording a run (results, energy balance), VTK, plots, run folders, interaction maps."""

from .results import ENERGY_KEYS, Results

__all__ = ["ENERGY_KEYS", "Results"]
