"""Compiled arithmetic of the abradable wear map (:mod:`femrub.contact.abradable`).

The map stores the wear depth ``w`` at the centres of ``n_angle × n_axial`` cells, flat
index ``j n_axial + a`` for angle centre ``j`` and axial row ``a``. A contact ``i`` at
time ``t`` sits at the unwrapped position (in cell-centre units)::

    x_i(t) = (Ω t + φ_i) n_angle / 2π − 1/2

and reads the map by periodic linear interpolation between the centres ``k = ⌊x_i⌋`` and
``k + 1`` (taken modulo ``n_angle``), ``s = x_i − k``::

    w_i(t) = (1 − s) w[k, a_i] + s w[k + 1, a_i]

A contact that yielded over a step cuts every centre ``k`` it swept, from ``x⁰`` (where
the previous step left it, reach ``r⁰``) to ``x¹`` (reach ``r¹``) and the centre beyond
each end, to the reach interpolated along the sweep::

    w[k, a] <- max(w[k, a], min(e, r⁰ + s_k (r¹ − r⁰))),   s_k = clip((k − x⁰)/(x¹ − x⁰), 0, 1)

(``s_k = 1`` for a contact that did not move). :meth:`Abradable.update` and the θ-method's
compiled blocks of steps (:mod:`femrub.contact.rub_block`) both cut through
:func:`cut_sweeps`; :func:`depth_under` is the interpolation of
:meth:`CasingGrid.interpolate` written per contact, the same operations in the same order.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import njit

__all__ = ["positions", "depth_under", "cut_sweeps"]


@njit
def positions(t, angles, omega, scale):
    """``x_i(t) = (Ω t + φ_i) scale − 1/2`` (n,), ``scale = n_angle / 2π``."""
    x = np.empty(angles.size)
    for i in range(angles.size):
        x[i] = (omega * t + angles[i]) * scale - 0.5
    return x


@njit
def depth_under(flat, x, axial_cell, n_angle, n_axial):
    """Wear depth (n,) of the flat map ``flat`` at the positions ``x`` (n,) in the axial
    rows ``axial_cell`` (n,): periodic linear interpolation between centres."""
    out = np.empty(x.size)
    for i in range(x.size):
        kf = math.floor(x[i])
        s = x[i] - kf
        k = int(kf) % n_angle
        k1 = (k + 1) % n_angle
        a = axial_cell[i]
        out[i] = (1.0 - s) * flat[k * n_axial + a] + s * flat[k1 * n_axial + a]
    return out


@njit
def cut_sweeps(flat, axial_cell, x0, x1, r0, r1, thickness, n_angle, n_axial):
    """Cut the map ``flat`` (in place) along the sweeps of the contacts given: contact ``a``
    from ``x0[a]`` (reach ``r0[a]``) to ``x1[a]`` (reach ``r1[a]``) in axial row
    ``axial_cell[a]`` (module docstring). Returns the deepest level cut (``-inf``: none)."""
    deepest = -math.inf
    for a in range(x0.size):
        lo = int(math.floor(min(x0[a], x1[a])))
        hi = int(math.floor(max(x0[a], x1[a]))) + 1
        dx = x1[a] - x0[a]
        for k in range(lo, hi + 1):
            frac = 1.0 if dx == 0.0 else min(max((k - x0[a]) / dx, 0.0), 1.0)
            level = min(thickness, r0[a] + frac * (r1[a] - r0[a]))
            c = (k % n_angle) * n_axial + axial_cell[a]
            if level > flat[c]:
                flat[c] = level
            deepest = max(deepest, level)
    return deepest
