"""Compiled arithmetic of the abradable wear map (:mod:`femrub.contact.abradable`).

The map stores ``n_angle × n_axial`` coefficients ``c`` of the worn surface, one per cell,
flat index ``j n_axial + a`` for angle centre ``j`` and axial row ``a``. A contact ``i`` at
time ``t`` sits at the unwrapped position (in cell-centre units)::

    x_i(t) = (Ω t + φ_i) n_angle / 2π − 1/2

and reads the wear depth as the periodic quadratic B-spline of the coefficients of its
row: with ``k = ⌊x_i + 1/2⌋`` the nearest centre and ``u = x_i − k ∈ [−1/2, 1/2)``
(indices modulo ``n_angle``)::

    w_i(t) = (1/2 − u)²/2 c[k − 1, a_i] + (3/4 − u²) c[k, a_i] + (1/2 + u)²/2 c[k + 1, a_i]

The surface is continuous with a continuous slope (C¹) in ``ψ``: a contact sliding over it
meets no slope jump at the centres (a piecewise-linear surface asks for a velocity jump,
an impact, at every centre it crosses). The weights are ``>= 0`` and sum to 1, so
``0 <= c <= e`` keeps ``0 <= w <= e``, and the volume under the surface is ``Σ c`` times
the cell areas.

A contact that stands for a footprint of the tip ``β`` cells wide (``contact.abradable.
footprint``) reads the surface's mean over it, ``[x_i − β/2, x_i + β/2]``::

    W_i = Σ_k c[k, a_i] (Φ(x_i + β/2 − k) − Φ(x_i − β/2 − k)) / β

with ``Φ`` the antiderivative of the quadratic B-spline (``β = 0``: the point read above):
weights ``>= 0`` summing to 1 over ``β + 3`` coefficients at most. The map keeps the worn
surface; the footprint is how a finite tip reads it, so detail of the surface shorter than
the footprint (the step-to-step jitter a point contact would carve and meet again) does not
act on the blade, and the map's cell size is again a numerical parameter.

A contact that yielded over a step cuts its sweep from ``x⁰`` (where the previous step
left it, reach ``r⁰``) to ``x¹`` (reach ``r¹``), the reach linear along the sweep: every
coefficient whose support ``(k − 3/2, k + 3/2)``, widened by ``β/2`` each side, meets the
sweep is raised to the largest reach of the sweep over that widened support::

    c[k, a] <- max(c[k, a], min(e, max_{x in sweep, |x − k| <= 3/2 + β/2} r(x)))

(``r¹`` for a contact that did not move), so that afterwards ``w >= r`` all along the sweep
(every weight that is non-zero at a point of the sweep multiplies a coefficient at least
the reach there; ``W >= r`` with a footprint): the contact ends on its own cut, and
retracing the path it cut does not meet the coating again. A cut goes beyond the reach by
the reach's slope over up to one and a half cells (and half the footprint, as a flat tip
of that width does); two rules that do not, measured on the coated Rotor 37 rub, converged
worse (``docs/abradable.md``, "The cut rule"). :meth:`Abradable.update` and the θ-method's
compiled blocks of steps (:mod:`femrub.contact.rub_block`) both cut through
:func:`cut_sweeps`; :func:`depth_under` is :meth:`CasingGrid.interpolate` written per
contact, the same operations in the same order.

The bound of a step's normal impulse is the yield force times the time the contact spends
on the coating within the step: ``U = h F_y`` for a contact closed at ``t_k``, and for one
open at ``t_k`` (``g_k > 0``) whose free motion ends the step inside the worn surface
(``g_p < 0``) the part of the step after it reaches it, the gap linear over the step
(:func:`entry_bounds`)::

    U = h F_y (−g_p) / (g_k − g_p)

A first cutting step no longer carries the yield force over the part of the step the
blade spent in the air (``docs/abradable.md``).
"""

from __future__ import annotations

import math

import numpy as np

from .jit import njit

__all__ = [
    "positions",
    "depth_under",
    "cut_sweeps",
    "entry_bounds",
    "piece_max",
    "spline_integral",
    "surface_max",
]


@njit
def positions(t, angles, omega, scale):
    """``x_i(t) = (Ω t + φ_i) scale − 1/2`` (n,), ``scale = n_angle / 2π``."""
    x = np.empty(angles.size)
    for i in range(angles.size):
        x[i] = (omega * t + angles[i]) * scale - 0.5
    return x


@njit
def spline_integral(t):
    """``Φ(t) = ∫_{-∞}^t B(s) ds`` of the centred quadratic B-spline ``B`` (0 below −3/2, 1
    above 3/2)."""
    if t <= -1.5:
        return 0.0
    if t <= -0.5:
        return (t + 1.5) ** 3 / 6.0
    if t <= 0.5:
        return 1.0 / 6.0 + 0.75 * (t + 0.5) - (t**3 + 0.125) / 3.0
    if t < 1.5:
        return 1.0 - (1.5 - t) ** 3 / 6.0
    return 1.0


@njit
def depth_under(flat, x, axial_cell, n_angle, n_axial, beta):
    """Wear depth (n,) of the flat map ``flat`` at the positions ``x`` (n,) in the axial
    rows ``axial_cell`` (n,): the periodic quadratic B-spline of the coefficients, or its
    mean over a footprint ``beta`` cells wide (module docstring)."""
    out = np.empty(x.size)
    for i in range(x.size):
        a = axial_cell[i]
        if beta > 0.0:
            lo, hi = x[i] - 0.5 * beta, x[i] + 0.5 * beta
            acc = 0.0
            for k in range(int(math.floor(lo - 1.5)), int(math.floor(hi + 1.5)) + 1):
                wk = spline_integral(hi - k) - spline_integral(lo - k)
                acc += wk * flat[(k % n_angle) * n_axial + a]
            out[i] = acc / beta
            continue
        kf = math.floor(x[i] + 0.5)
        u = x[i] - kf
        k = int(kf) % n_angle
        km = (k - 1) % n_angle
        kp = (k + 1) % n_angle
        bm = 0.5 * (0.5 - u) * (0.5 - u)
        b0 = 0.75 - u * u
        bp = 0.5 * (0.5 + u) * (0.5 + u)
        out[i] = (bm * flat[km * n_axial + a] + b0 * flat[k * n_axial + a]) + bp * flat[
            kp * n_axial + a
        ]
    return out


@njit
def piece_max(flat, k, row, n_angle, n_axial):
    """Deepest point of the surface of row ``row`` over the piece ``|x − k| <= 1/2``: its
    ends ``(c[k−1] + c[k]) / 2``, ``(c[k] + c[k+1]) / 2`` or, where the piece is concave,
    its vertex ``u* = (c[k−1] − c[k+1]) / 2(c[k−1] − 2c[k] + c[k+1])``."""
    cm = flat[((k - 1) % n_angle) * n_axial + row]
    c0 = flat[(k % n_angle) * n_axial + row]
    cp = flat[((k + 1) % n_angle) * n_axial + row]
    best = max(0.5 * (cm + c0), 0.5 * (c0 + cp))
    curv = cm - 2.0 * c0 + cp
    if curv < 0.0:
        u = 0.5 * (cm - cp) / curv
        if -0.5 < u < 0.5:
            vertex = 0.5 * (0.5 - u) ** 2 * cm + (0.75 - u * u) * c0 + 0.5 * (0.5 + u) ** 2 * cp
            best = max(best, vertex)
    return best


@njit
def surface_max(flat, n_angle, n_axial):
    """Deepest point of the whole worn surface: the largest :func:`piece_max` (0: empty)."""
    best = 0.0
    for row in range(n_axial):
        for k in range(n_angle):
            best = max(best, piece_max(flat, k, row, n_angle, n_axial))
    return best


@njit
def cut_sweeps(flat, axial_cell, x0, x1, r0, r1, thickness, n_angle, n_axial, beta):
    """Cut the map ``flat`` (in place) along the sweeps of the contacts given: contact ``a``
    from ``x0[a]`` (reach ``r0[a]``) to ``x1[a]`` (reach ``r1[a]``) in axial row
    ``axial_cell[a]``, for a footprint ``beta`` cells wide (module docstring). Returns the
    deepest point of the surface over the pieces whose coefficients it raised (``-inf``:
    none raised)."""
    deepest = -math.inf
    for a in range(x0.size):
        lo, hi = min(x0[a], x1[a]), max(x0[a], x1[a])
        dx = x1[a] - x0[a]
        hw = 1.5 + 0.5 * beta  # half the width of a coefficient's widened support
        k0 = int(math.floor(lo - 0.5 * beta + 0.5)) - 1
        for k in range(k0, int(math.floor(hi + 0.5 * beta + 0.5)) + 2):
            if dx == 0.0:
                level = r1[a]
            else:  # the largest reach of the sweep over the support of coefficient k
                fa = min(max((max(lo, k - hw) - x0[a]) / dx, 0.0), 1.0)
                fb = min(max((min(hi, k + hw) - x0[a]) / dx, 0.0), 1.0)
                level = (
                    r0[a] + max(fa, fb) * (r1[a] - r0[a])
                    if r1[a] >= r0[a]
                    else (r0[a] + min(fa, fb) * (r1[a] - r0[a]))
                )
            level = min(thickness, level)
            c = (k % n_angle) * n_axial + axial_cell[a]
            if level > flat[c]:
                flat[c] = level
                for j in range(k - 1, k + 2):  # the pieces that read c[k]
                    deepest = max(deepest, piece_max(flat, j, axial_cell[a], n_angle, n_axial))
    return deepest


@njit
def entry_bounds(U, g_k, g_p):
    """The bounds ``U`` (n,) of a step's normal impulses, in place, for the contacts that
    enter the coating within the step (module docstring): finite ``U``, ``g_k > 0`` (open at
    ``t_k``) and ``g_p < 0`` (the free motion ends inside) take ``U (−g_p) / (g_k − g_p)``.
    Returns ``U``."""
    for i in range(U.size):
        if U[i] < math.inf and g_k[i] > 0.0 and g_p[i] < 0.0:
            U[i] = U[i] * (-g_p[i] / (g_k[i] - g_p[i]))
    return U
