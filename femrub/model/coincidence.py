"""Rotation speeds at which a bladed disk's and a casing's waves of k nodal diameters coincide.

A mode of ``k`` nodal diameters of the disk, of angular frequency ``ω_d`` in the rotating
frame (angle ``θ_r``), is a pair of travelling waves ``cos(k θ_r ∓ ω_d t)``: forward
(``−``, turning with the rotor at ``+ω_d / k`` relative to it) and backward (``+``, at
``−ω_d / k``). Seen from the casing, ``θ = θ_r + Ω t``, the backward wave is::

    cos(k θ_r + ω_d t) = cos(k θ − (k Ω − ω_d) t)

a wave turning at ``Ω − ω_d / k`` with the frequency ``k Ω − ω_d``. A casing mode of ``k``
nodal diameters and frequency ``ω_c`` travels forwards as ``cos(k θ − ω_c t)``, at
``ω_c / k``. Both waves have the same shape and the same speed, so that the blades' tips
can feed the casing's wave through their contact and the casing's the disk's, when::

    k Ω = ω_d + ω_c                                                          (1)

the interaction of Legrand, Pierre, Cartraud and Lombard (J. Sound Vib. 319, 2009): the
disk's backward wave (in the rotating frame) locks onto the casing's forward wave (in the
fixed frame), at the frequency ``ω_c`` in the fixed frame. The disk's forward wave turns at
``Ω + ω_d / k`` and would meet the casing's forward wave only at ``k Ω = ω_c − ω_d``, a
speed below the casing's own wave speed that the reference does not retain; it is not
listed. ``k = 0`` has no travelling wave and no coincidence.

The disk's frequencies depend on Ω through the centrifugal prestress, so (1) is an equation
in Ω. From one table (:func:`coincidences`, ``method = "scene-speed"``) ``ω_d`` is taken
at the table's speed: a first estimate. From tables at listed speeds
``Ω_1 < ... < Ω_n`` (:func:`coincidences_over_speeds`) the function::

    g(Ω) = k Ω − ω_d(Ω) − ω_c                                                 (2)

is evaluated at every listed speed; between two consecutive speeds where it changes sign,
``ω_d²`` is interpolated linearly in ``Ω²`` (Southwell's rule: the tangent stiffness of the
linear prestress is affine in ``Ω²``, so is each Rayleigh quotient for a fixed shape)::

    ω_d(Ω)² ≈ ω_d(Ω_i)² + (ω_d(Ω_{i+1})² − ω_d(Ω_i)²) (Ω² − Ω_i²) / (Ω_{i+1}² − Ω_i²)    (3)

and the root of (2) with (3) in ``[Ω_i, Ω_{i+1}]`` (Brent's method; a root solves
``(k Ω − ω_c)² = (3)``, quadratic in Ω, so the sign change brackets exactly one) is the
coincidence (``method = "interpolated"``). A pair of modes whose ``g`` keeps its sign
over the listed speeds gets the estimate ``(ω_d + ω_c) / k`` with ``ω_d`` at the nearest end
of the list (the top speed when ``g < 0`` throughout, the bottom one when ``g > 0``):
``method = "outside-range"``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .cyclic import ModeTable

__all__ = ["METHODS", "Coincidence", "coincidences", "coincidences_over_speeds"]

#: how a coincidence speed was found (module docstring)
METHODS = ("interpolated", "outside-range", "scene-speed")


@dataclass(frozen=True)
class Coincidence:
    """One solution of Eq. (1).

    Attributes
    ----------
    nodal_diameter : int
        ``k``.
    disk_family, casing_family : int
        The families of the two modes (1: the lowest of each ``k``).
    rotation_speed : float
        ``Ω = (ω_d + ω_c) / k`` (rad/s).
    disk_frequency_hz, casing_frequency_hz : float
        ``ω_d / 2π`` (at the disk's prestress speed, or interpolated by Eq. 3 at
        ``rotation_speed``) and ``ω_c / 2π`` (Hz).
    method : str
        One of :data:`METHODS`.
    """

    nodal_diameter: int
    disk_family: int
    casing_family: int
    rotation_speed: float
    disk_frequency_hz: float
    casing_frequency_hz: float
    method: str = "scene-speed"


def _pairs(disk: ModeTable, casing: ModeTable):
    """``(k, disk family, casing family, disk row, casing frequency Hz)`` for every ``k >= 1``
    of both tables and every pair of families."""
    shared = np.intersect1d(disk.nodal_diameter, casing.nodal_diameter)
    for k in shared[shared >= 1]:
        rows = np.flatnonzero(disk.nodal_diameter == k)
        c = casing.nodal_diameter == k
        for row in rows:
            for fc, jc in zip(casing.frequency_hz[c], casing.family[c], strict=True):
                yield int(k), int(disk.family[row]), int(jc), row, float(fc)


def coincidences(disk: ModeTable, casing: ModeTable) -> list[Coincidence]:
    """Every speed of ``k Ω = ω_d + ω_c`` for the nodal diameters ``k >= 1`` of both tables.

    The disk's frequencies are those at its table's ``rotation_speed``: the speeds are
    exact where they equal it and first estimates elsewhere (the disk's frequencies change
    with Ω through the prestress). Sorted by speed.
    """
    out = [
        Coincidence(
            k,
            jd,
            jc,
            2.0 * math.pi * (disk.frequency_hz[row] + fc) / k,
            float(disk.frequency_hz[row]),
            fc,
        )
        for k, jd, jc, row, fc in _pairs(disk, casing)
    ]
    return sorted(out, key=lambda c: c.rotation_speed)


def _interval_root(k, speeds, wd, wc, i):
    """The root of Eq. (2) with Eq. (3) in ``[Ω_i, Ω_{i+1}]`` (rad/s) and ``ω_d`` there."""
    a, b = speeds[i], speeds[i + 1]

    def disk(speed):
        w2 = wd[i] ** 2 + (wd[i + 1] ** 2 - wd[i] ** 2) * (speed * speed - a * a) / (b * b - a * a)
        return math.sqrt(max(w2, 0.0))

    speed = brentq(lambda s: k * s - disk(s) - wc, a, b, xtol=1e-12 * b, rtol=1e-14)
    return speed, disk(speed)


def _crossings(k, speeds, wd, wc):
    """``(Ω, ω_d, method)`` of every root of Eq. (2) over the listed speeds, or the
    outside-range estimate (module docstring)."""
    g = k * speeds - wd - wc
    found = [(speeds[i], wd[i], "interpolated") for i in np.flatnonzero(g == 0.0)]
    for i in np.flatnonzero(g[:-1] * g[1:] < 0.0):
        found.append((*_interval_root(k, speeds, wd, wc, i), "interpolated"))
    if found:
        return found
    end = -1 if g[0] < 0.0 else 0
    return [((wd[end] + wc) / k, wd[end], "outside-range")]


def coincidences_over_speeds(disk_tables, casing: ModeTable) -> list[Coincidence]:
    """Every root of Eq. (2) from the disk's tables at increasing speeds (module docstring).

    Parameters
    ----------
    disk_tables : sequence of ModeTable
        The disk's modes at ``Ω_1 < ... < Ω_n`` (their ``rotation_speed``, rad/s), the
        same nodal diameters and families in each.
    casing : ModeTable
        The casing's modes (at rest).

    Returns
    -------
    list of Coincidence
        Sorted by speed; ``method`` ``"interpolated"`` or ``"outside-range"``.
    """
    speeds = np.array([t.rotation_speed for t in disk_tables], dtype=float)
    if speeds.size < 2 or np.any(np.diff(speeds) <= 0.0):
        raise ValueError("coincidences over speeds need two or more increasing speeds")
    hz = np.array([t.frequency_hz for t in disk_tables])  # (n_speeds, n_modes)
    out = []
    for k, jd, jc, row, fc in _pairs(disk_tables[0], casing):
        wd, wc = 2.0 * math.pi * hz[:, row], 2.0 * math.pi * fc
        for speed, w, method in _crossings(k, speeds, wd, wc):
            out.append(Coincidence(k, jd, jc, float(speed), float(w) / (2.0 * math.pi), fc, method))
    return sorted(out, key=lambda c: c.rotation_speed)
