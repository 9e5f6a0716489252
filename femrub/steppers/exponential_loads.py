"""The load signals of the exponential stepper over a step, as a polynomial in its time.

Over a step ``[t, t + h]`` the load signals (and, for held contacts on a moving casing, the
casing's gap rates ``ġ0``) are interpolated at ``p + 1`` Chebyshev–Lobatto points of the
normalised time ``σ ∈ [0, 1]`` by ``s(t + σ h) = Σ_i b_i σ^i``; the exact flows of
:mod:`~.flows` integrate that polynomial exactly (their chain inputs ``w_i = i! b_i``). The
casing's accelerations ``g̈0`` enter as the derivative of the rates' interpolant.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["LoadPolynomial"]


class LoadPolynomial:
    """Load polynomials of :class:`~femrub.steppers.exponential.ExponentialMoreau` (mixin: it
    reads the stepper's model, ``h``, ``t``, ``_signals``, ``_m0`` and ``_n_a``)."""

    def _loads_setup(self, p: int) -> None:
        """Interpolation points and matrices for degree ``p``; the signals at ``t``."""
        self._nodes = 0.5 * (1.0 - np.cos(np.pi * np.arange(p + 1) / max(p, 1)))  # Lobatto
        self._Vinv = np.linalg.inv(self._nodes[:, None] ** np.arange(p + 1))
        self._T01 = np.diag([float(math.factorial(i)) for i in range(p + 1)])
        self._Dinv = np.linalg.inv(self._T01)
        self._sk = self._signal_values(self.t)
        # signals that take an array of times (checked once against one call per time)
        probe = self.t + self.h * self._nodes[1:]
        self._vector = [_vectorised(sig, probe) for sig in self._signals]

    def _signal_values(self, t):
        """Load signals, then the casing's gap rates ``ġ0`` (moving casing, held contacts)."""
        s = [float(sig(t)) for sig in self._signals]
        if self._n_a:
            return np.r_[s, self.model.contact.rate_at(t)]
        return np.array(s)

    def _load_poly(self, t):
        """Monomial coefficients ``b`` (p+1, m) of the step's load, ``s = Σ b_i σ^i``."""
        h, nodes = self.h, self._nodes
        S = np.empty((nodes.size, self._m0 + self._n_a))
        S[0] = self._sk
        times = t + nodes[1:] * h
        for k, sig in enumerate(self._signals):
            S[1:, k] = sig(times) if self._vector[k] else [sig(tj) for tj in times]
        if self._n_a:
            S[1:, self._m0 :] = self.model.contact.rate_at(times)
        self._sk = S[-1]
        b = self._Vinv @ S
        if self._n_a:  # g̈0 = dġ0/dt: the derivative of the rates' interpolant
            i = np.arange(1, b.shape[0])[:, None]
            rates = b[:, self._m0 :].copy()
            b[:, self._m0 :] = 0.0
            b[:-1, self._m0 :] = i * rates[1:] / h
        return b

    def _u(self, b, sigma):
        """Load signals at the fraction ``sigma`` of the step."""
        return (sigma ** np.arange(b.shape[0])) @ b

    def _du(self, b, sigma):
        """Their time derivative (1/s) at the fraction ``sigma`` of the step."""
        i = np.arange(1, b.shape[0])
        return ((i * sigma ** (i - 1)) @ b[1:]) / self.h


def _vectorised(sig, times) -> bool:
    """``sig`` evaluated on the array ``times`` gives, bit for bit, its values one by one."""
    try:
        vals = np.asarray(sig(times), dtype=float)
    except (TypeError, ValueError):
        return False
    return vals.shape == times.shape and np.array_equal(vals, [float(sig(t)) for t in times])
