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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cyclic import ModeTable

__all__ = ["Coincidence", "coincidences"]


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
        ``ω_d / 2π`` (at the disk's prestress speed) and ``ω_c / 2π`` (Hz).
    """

    nodal_diameter: int
    disk_family: int
    casing_family: int
    rotation_speed: float
    disk_frequency_hz: float
    casing_frequency_hz: float


def coincidences(disk: ModeTable, casing: ModeTable) -> list[Coincidence]:
    """Every speed of ``k Ω = ω_d + ω_c`` for the nodal diameters ``k >= 1`` of both tables.

    The disk's frequencies are those at its table's ``rotation_speed``: the speeds are
    exact where they equal it and first estimates elsewhere (the disk's frequencies change
    with Ω through the prestress). Sorted by speed.
    """
    out = []
    shared = np.intersect1d(disk.nodal_diameter, casing.nodal_diameter)
    for k in shared[shared >= 1]:
        d = disk.nodal_diameter == k
        c = casing.nodal_diameter == k
        for fd, jd in zip(disk.frequency_hz[d], disk.family[d], strict=True):
            for fc, jc in zip(casing.frequency_hz[c], casing.family[c], strict=True):
                speed = 2.0 * math.pi * (fd + fc) / k
                out.append(Coincidence(int(k), int(jd), int(jc), speed, float(fd), float(fc)))
    return sorted(out, key=lambda c: c.rotation_speed)
