"""The analysis layer above the steppers: it runs them, records, judges and compares runs.

* :mod:`~femrub.analysis.options`: :class:`RunOptions`, how a run is recorded and judged;
* :mod:`~femrub.analysis.runner`: :func:`run`, a stepper driven into a
  :class:`~femrub.output.recorder.Recorder` with stop limits and the verdict;
* :mod:`~femrub.analysis.steppers`: the runnable steppers (``fr.ThetaMethod``, ...);
* the checks that run steppers: the reduction error estimate and automatic sizes
  (:mod:`~femrub.analysis.reduction_check`) and the time-step check
  (:mod:`~femrub.analysis.step_check`).

The steppers (:mod:`femrub.steppers`) never import this package nor :mod:`femrub.output`.
"""

from .options import RunOptions
from .runner import run
from .steppers import SCHEMES, Carpenter, ExponentialMoreau, Penalty, ThetaMethod, make_stepper

__all__ = [
    "Carpenter",
    "ExponentialMoreau",
    "Penalty",
    "RunOptions",
    "SCHEMES",
    "ThetaMethod",
    "make_stepper",
    "run",
]
