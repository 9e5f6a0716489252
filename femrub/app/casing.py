"""The casing a scene's contacts rub: the cells they sweep, the abradable coating on them and
the lumped casing thermal model (``contact.abradable``, ``contact.casing_heat``).
"""

from __future__ import annotations

import numpy as np

from ..contact.abradable import Abradable, CasingGrid
from ..contact.casing_heat import CasingHeat
from ..scene.spec import fail

__all__ = ["abradable_of", "casing_grid", "casing_heat_of", "footprint_warning"]


def casing_grid(scene, blade, points, omega, growth):
    """Casing cells swept by the kept contacts (wear map, casing heat), or ``None``."""
    c = scene["contact"]
    a, h = c["abradable"], c["casing_heat"]
    if points.n == 0 or (a["thickness"] <= 0.0 and h["thickness"] <= 0.0):
        return None
    n = a if a["thickness"] > 0.0 else h
    axial = blade.axis @ points.points if blade.dim == 3 else np.zeros(points.n)
    foot = a["footprint"] if a["thickness"] > 0.0 else 0.0
    return CasingGrid(
        points.angles,
        axial,
        float(np.max(points.radii + growth)),
        omega,
        n_angle=n["n_angle"],
        n_axial=n["n_axial"],
        footprint=foot,
    )


def abradable_of(scene, grid):
    """The coating of ``contact.abradable`` over the kept contacts, or ``None``."""
    a = scene["contact"]["abradable"]
    if grid is None or a["thickness"] <= 0.0:
        return None
    return Abradable(a["thickness"], a["yield"], grid)


def footprint_warning(scene, grid) -> str | None:
    """A one-line warning when several contacts read a coating at points
    (``contact.abradable.footprint = 0``), naming the width each stands for: their span
    around the casing (the shortest arc holding them all) over their number less one."""
    if grid is None or scene["contact"]["abradable"]["thickness"] <= 0.0 or grid.footprint:
        return None
    phi = np.unique(np.mod(grid.angles, 2 * np.pi))
    if phi.size < 2:
        return None
    span = 2 * np.pi - np.diff(np.r_[phi, phi[0] + 2 * np.pi]).max()
    width = span / (phi.size - 1) * grid.radius
    return (
        f"contact.abradable.footprint = 0: each of the {grid.angles.size} contacts reads the "
        "coating at a point, so the wear of later revolutions keeps changing with "
        "contact.abradable.n_angle (docs/abradable.md); set it to the tip width a contact "
        f"stands for, about {1e3 * width:.3g} mm here"
    )


def casing_heat_of(scene, grid, eta, alpha, mu):
    """The lumped casing thermal model of ``contact.casing_heat``, or ``None``; ``mu``: the
    Coulomb coefficient of the ``"power"`` heat law (0 with the ``"alpha"`` law)."""
    h = scene["contact"]["casing_heat"]
    if grid is None or h["thickness"] <= 0.0:
        return None
    if not 0.0 < eta < 1.0 or not (mu > 0.0 or np.any(alpha > 0)):
        fail(
            "contact.casing_heat.thickness",
            h["thickness"],
            f"no frictional heat reaches the casing (heat_partition {eta:g}, no heat "
            "coefficient); set contact.friction / heat_coefficient and heat_partition < 1",
        )
    return CasingHeat(
        grid,
        h["thickness"],
        h["density"],
        h["specific_heat"],
        h["conductivity"],
        h["expansion"],
        eta,
        alpha,
    )
