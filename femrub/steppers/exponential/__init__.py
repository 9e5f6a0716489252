"""The exponential Moreau stepper, composed of its parts.

* :mod:`.stepper`: :class:`ExponentialMoreau`, the step (exact flight, impulses at events);
* :mod:`.flows`: exact flows ``e^{hL}`` of the free and held sets;
* :mod:`.events`: event location inside a step (first zero of a gap or a multiplier);
* :mod:`.work`: exact works and heats of the flights (the energy balance);
* :mod:`.loads`: the load signals as polynomials over a step;
* :mod:`.friction`, :mod:`.slide`: Coulomb friction and the slip directions of held slides;
* :mod:`.kernels`: their compiled arithmetic.
"""

from .stepper import MAX_COORDINATES, ExponentialMoreau

__all__ = ["MAX_COORDINATES", "ExponentialMoreau"]
