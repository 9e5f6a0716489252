"""Probes of a bladed disk: one component of the displacement or velocity at a node of the
sector, on one blade or on every blade, as observation rows of the wheel's coordinates.

The wheel's disk moves in sector ``s`` (blade ``s``), in the sector's own axes, as
``u_s = U_s x`` (Eq. 1 of :mod:`femrub.reduction.cyclic_ritz`, ``U_s`` the field of the
coordinates ``x`` in sector ``s``). Blade ``s`` is the sector turned by ``R(s α)`` about the
machine axis ``x`` (:func:`~femrub.geometry.cyclic_sector.axis_rotation`, ``α = 2π/N``), so
its node ``n`` (the sector's node ``n`` turned) moves in global axes by ``R(s α) u_s(x_n)``.
A probe along the direction ``d`` reads, on blade ``s``::

    p_s = d_sᵀ E_n U_s x,      d_s = R(s α)ᵀ d   (global axes x, y, z)
                               d_s = d           (radial, axial, circumferential)        (1)

``E_n`` the node's displacement rows (:func:`~femrub.model.probes.node_rows`: its dofs, or
an edge midpoint's). The directions about the machine axis, taken at the sector's node, are
the same on every blade in the blade's own axes (they turn with it), so they need no turn.
The rows ``E_n U_s`` of every sector are :meth:`CyclicBasis.sector_rows
<femrub.reduction.cyclic_ritz.CyclicBasis.sector_rows>`; a velocity probe has the same row
on the velocity coordinates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry.cyclic_sector import axis_rotation
from ..reduction.cyclic_ritz import CyclicBasis

__all__ = ["GLOBAL_AXES", "UNITS", "WheelProbe", "blade_directions", "wheel_probe_rows"]

#: components read along the global axes, turned with the blade (Eq. 1)
GLOBAL_AXES = ("x", "y", "z")
#: SI unit of a probe of each state block
UNITS = {"u": "m", "v": "m/s"}


@dataclass(frozen=True)
class WheelProbe:
    """One probe of the wheel on the blades it reads.

    Attributes
    ----------
    keys : tuple of str
        The observation's name on each blade of ``blades`` (``probe_<name>``, or
        ``probe_<name>_blade<s>`` for every blade).
    blades : tuple of int
        The blades read, ``0 <= s < N``.
    field : str
        ``"u"`` (displacement) or ``"v"`` (velocity).
    rows : numpy.ndarray or scipy.sparse matrix
        ``(3, n_free)``: the node's displacement components (sector axes) on the sector's
        free dofs (``E_n``).
    direction : numpy.ndarray
        ``(3,)`` unit vector ``d``: a global axis, or the direction about the machine axis at
        the sector's node (sector axes).
    turns : bool
        Whether ``d`` is a global axis, turned to each blade's axes (Eq. 1).
    """

    keys: tuple
    blades: tuple
    field: str
    rows: object
    direction: np.ndarray
    turns: bool


def blade_directions(direction, blades, n_blades: int, turns: bool) -> np.ndarray:
    """``(len(blades), 3)``: ``d_s`` of Eq. (1) in each blade's own axes."""
    d = np.asarray(direction, dtype=float)
    if not turns:
        return np.tile(d, (len(blades), 1))
    alpha = 2.0 * math.pi / n_blades
    return np.stack([axis_rotation(s * alpha).T @ d for s in blades])


def wheel_probe_rows(probe: WheelProbe, disk: CyclicBasis) -> dict:
    """``{key: (field, (1, disk.size) row)}``: Eq. (1) for each blade of ``probe`` on the
    disk's coordinates."""
    blades = np.asarray(probe.blades, dtype=int)
    per_sector = disk.sector_rows(probe.rows)[blades]  # (B, 3, size)
    d = blade_directions(probe.direction, probe.blades, disk.n_sectors, probe.turns)
    rows = np.einsum("bj,bjn->bn", d, per_sector)
    return {key: (probe.field, rows[i : i + 1]) for i, key in enumerate(probe.keys)}
