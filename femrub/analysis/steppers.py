"""The steppers as users run them: each pure integrator of :mod:`femrub.steppers` with
:meth:`~Runs.run`.

``fr.ThetaMethod``, ``fr.Carpenter``, ``fr.Penalty`` and ``fr.ExponentialMoreau`` are these
classes: thin subclasses of the integrators that add ``run(t_end, options, **changes)``
(:func:`femrub.analysis.runner.run`, options :class:`~femrub.analysis.options.RunOptions`).
The integrators themselves (``step()``, ``iterate()``, ``advance()``) know nothing of
recording, limits or verdicts.
"""

from __future__ import annotations

from .. import steppers as pure
from ..output.results import Results
from .options import RunOptions
from .runner import run

__all__ = [
    "Carpenter",
    "ExponentialMoreau",
    "Penalty",
    "Runs",
    "SCHEMES",
    "ThetaMethod",
    "make_stepper",
]


class Runs:
    """Adds :meth:`run` to a pure integrator."""

    def run(self, t_end: float, options: RunOptions | None = None, **changes) -> Results:
        """Integrate to ``t_end`` (s) and collect judged
        :class:`~femrub.output.results.Results`.

        ``options`` (:class:`~femrub.analysis.options.RunOptions`) with ``changes``, its
        fields by name, e.g. ``run(0.4, limits={"tip_temperature": 2000.0}, progress=True)``;
        default physical stop limits are on (``default_limits=False`` turns them off).
        """
        return run(self, t_end, RunOptions.of(options, **changes))


class ThetaMethod(Runs, pure.ThetaMethod):
    __doc__ = pure.ThetaMethod.__doc__


class Carpenter(Runs, pure.Carpenter):
    __doc__ = pure.Carpenter.__doc__


class Penalty(Runs, pure.Penalty):
    __doc__ = pure.Penalty.__doc__


class ExponentialMoreau(Runs, pure.ExponentialMoreau):
    __doc__ = pure.ExponentialMoreau.__doc__


SCHEMES = {
    "theta": ThetaMethod,
    "carpenter": Carpenter,
    "penalty": Penalty,
    "exponential": ExponentialMoreau,
}


def make_stepper(scheme: str, model, h, **options):
    """A runnable stepper by name (:func:`femrub.steppers.make_stepper`).

    Parameters
    ----------
    scheme : {"theta", "carpenter", "penalty", "exponential"}
        :class:`ThetaMethod` (paper Sec. 3, Eq. 16), :class:`Carpenter`, :class:`Penalty`
        or :class:`ExponentialMoreau`.
    model : :class:`~femrub.model.first_order.FirstOrderModel`
        The model ``A Ẋ = B X + F + H λ`` of Eqs. (8)-(9), full or reduced.
    h : float
        Time step (s).
    **options
        The stepper's own options (e.g. ``gamma``, ``activation`` of the θ-method).

    Returns
    -------
    Stepper
        A stepper with ``run(t_end, options=None, **changes) -> Results``.
    """
    return pure.make_stepper(scheme, model, h, schemes=SCHEMES, **options)
