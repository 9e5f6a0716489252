"""The casing a scene's contacts rub: what the build says of the cells they sweep (the cells,
the coating and the casing heat themselves are built by :mod:`femrub.model.builder`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["footprint_warning"]


def footprint_warning(scene, grid, per_blade: int | None = None) -> str | None:
    """A one-line warning when several contacts read a coating at points
    (``contact.abradable.footprint = 0``), naming the width each stands for: their span
    around the casing (the shortest arc holding them all) over their number less one; on a
    bladed disk (``per_blade`` contacts on each blade, blade by blade) the span of one
    blade's contacts."""
    if grid is None or scene["contact"]["abradable"]["thickness"] <= 0.0 or grid.footprint:
        return None
    phi = np.unique(np.mod(grid.angles[:per_blade], 2 * np.pi))
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
