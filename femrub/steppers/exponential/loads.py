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

__all__ = ["LoadPolynomial", "BLOCK"]

#: steps whose load polynomials are evaluated at once when every signal takes arrays
BLOCK = 64


class LoadPolynomial:
    """The load polynomials of the steps of
    :class:`~femrub.steppers.exponential.ExponentialMoreau` (module docstring).

    Parameters
    ----------
    signals : the load signals ``s(t)`` (callables of the time, s).
    rates : the casing's gap rates ``ġ0(t)`` (n_c,) (a callable of the time) appended to the
        signals for held contacts on a moving casing, or ``None``.
    h : time step (s); t0 : the stepper's first time; t : its current time (s).
    degree : the polynomial's degree ``p`` (``p + 1`` Chebyshev–Lobatto points).

    ``sk`` holds the signals at the start of the next step (the end of the last one).
    """

    def __init__(self, signals, rates, h: float, t0: float, t: float, degree: int):
        p = degree
        self.signals, self.rates, self.h, self.t0 = list(signals), rates, h, t0
        self.n_s = len(self.signals)
        self._nodes = 0.5 * (1.0 - np.cos(np.pi * np.arange(p + 1) / max(p, 1)))  # Lobatto
        self._Vinv = np.linalg.inv(self._nodes[:, None] ** np.arange(p + 1))
        #: ``w = T01 b``: the chain inputs ``w_i = i! b_i`` of the flows
        self.T01 = np.diag([float(math.factorial(i)) for i in range(p + 1)])
        self.sk = self.values(t)
        # signals that take an array of times (checked once against one call per time)
        probe = t + h * self._nodes[1:]
        self._vector = [_vectorised(sig, probe) for sig in self.signals]
        self._blocks: dict = {}  # step start time -> (s at it, b, s at its end)

    def values(self, t):
        """Load signals, then the casing's gap rates ``ġ0`` (moving casing, held contacts)."""
        s = [float(sig(t)) for sig in self.signals]
        if self.rates is not None:
            return np.r_[s, self.rates(t)]
        return np.array(s)

    def poly(self, t):
        """Monomial coefficients ``b`` (p+1, m) of the step's load, ``s = Σ b_i σ^i``: from
        the polynomials of :data:`BLOCK` steps evaluated at once (:meth:`_block_polys`) when
        every signal takes arrays and the step starts where the previous one ended."""
        if all(self._vector) and self.rates is None:
            hit = self._blocks.get(t)
            if hit is None:
                hit = self._block_polys(t)
            if hit is not None and np.array_equal(hit[0], self.sk):
                self.sk = hit[2]
                return hit[1]
        return self._step_poly(t)

    def _block_polys(self, t):
        """The load polynomials of the :data:`BLOCK` steps from ``t`` (a step start
        ``t0 + k h``, times computed as the stepper's), cached by start time; the entry of
        ``t``, or ``None`` when ``t`` is not a step start."""
        h, nodes = self.h, self._nodes
        k = round((t - self.t0) / h)
        if self.t0 + k * h != t:
            return None
        starts = self.t0 + (k + np.arange(BLOCK)) * h
        times = starts[:, None] + nodes[1:] * h
        S = np.empty((BLOCK, nodes.size, self.n_s))
        for j, sig in enumerate(self.signals):
            S[:, 1:, j] = np.asarray(sig(times.ravel()), dtype=float).reshape(times.shape)
        S[0, 0] = self.sk
        S[1:, 0] = S[:-1, -1]
        b = self._Vinv @ S
        self._blocks = {float(tk): (S[i, 0], b[i], S[i, -1]) for i, tk in enumerate(starts)}
        return self._blocks[t]

    def _step_poly(self, t):
        """:meth:`poly` of one step, its signals evaluated here."""
        h, nodes, m0 = self.h, self._nodes, self.n_s
        times = t + nodes[1:] * h
        S = np.empty((nodes.size, self.sk.size))
        S[0] = self.sk
        for k, sig in enumerate(self.signals):
            S[1:, k] = sig(times) if self._vector[k] else [sig(tj) for tj in times]
        if self.rates is not None:
            S[1:, m0:] = self.rates(times)
        self.sk = S[-1]
        b = self._Vinv @ S
        if self.rates is not None:  # g̈0 = dġ0/dt: the derivative of the rates' interpolant
            i = np.arange(1, b.shape[0])[:, None]
            rates = b[:, m0:].copy()
            b[:, m0:] = 0.0
            b[:-1, m0:] = i * rates[1:] / h
        return b

    def u(self, b, sigma):
        """Load signals at the fraction ``sigma`` of the step."""
        return (sigma ** np.arange(b.shape[0])) @ b

    def du(self, b, sigma):
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
