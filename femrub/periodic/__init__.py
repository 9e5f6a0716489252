"""Periodic orbits of femrub models and their stability: shooting on the θ-method,
pseudo-arclength continuation, Floquet multipliers (``femrub periodic``; docs/periodic.md).

* :class:`PeriodMap`: the state one period after a given state (the θ-method restarted);
* :class:`Shooting`: Newton on ``Φ_T(X0) − X0 = 0`` with the monodromy matrix;
* :func:`continue_branch`: a branch in a parameter, with folds passed, each point's Floquet
  multipliers and the bifurcations between points (:class:`Branch`);
* :func:`scene_family`: the models of a scene along any numeric key;
* :func:`write_branch`: ``branch.csv``, ``branch.png``, ``summary.json``, orbits.
"""

from .continuation import Branch, BranchPoint, check_model, continue_branch, measures
from .floquet import multipliers, special_point, stable
from .period import Orbit, PeriodMap, forcing_frequency
from .shooting import Shooting, ShootingResult, state_scale

__all__ = [
    "Branch",
    "BranchPoint",
    "Orbit",
    "PeriodMap",
    "Shooting",
    "ShootingResult",
    "check_model",
    "continue_branch",
    "forcing_frequency",
    "measures",
    "multipliers",
    "special_point",
    "stable",
    "state_scale",
]
