"""One cyclic sector of a flexible casing: a thin ring of solid elements clamped at its flanges.

The ring is the annulus ``inner_radius <= r <= inner_radius + thickness``,
``|x| <= axial_length / 2``, cut into ``N`` cyclic sectors as in
:mod:`femrub.geometry.cyclic_sector` (the right face meshed periodic to the left one). Its
two axial end faces (the flanges) are clamped: node set ``root``.

Out-of-roundness: the ring's inner surface is meant to carry a ``k``-lobed initial
distortion of its radius, ``r_c(φ) = inner_radius + amplitude cos(k (φ − phase))``, stored
with the sector (:class:`RingDistortion`) for the contact with the blades' tips. The
ring is meshed round: the distortion is small against the thickness and its modes are those
of the round ring.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gmsh
import numpy as np

from .cyclic_sector import (
    SectorMesh,
    classify_faces,
    cyclic_plane_distance,
    sector_angle,
    set_periodic,
)
from .errors import GeometryError, check_positive
from .gmsh_extract import to_blade_mesh
from .gmsh_session import gmsh_session
from .mesh_size import MeshSize

__all__ = ["RingDistortion", "casing_ring_sector"]


@dataclass(frozen=True)
class RingDistortion:
    """A ``lobes``-lobed out-of-roundness of the casing's inner radius.

    Attributes
    ----------
    lobes : int
        ``k``, the number of lobes (0: round).
    amplitude : float
        Radial amplitude ``a`` (m).
    phase : float
        Angle ``φ_0`` of the first lobe's crest (rad).
    """

    lobes: int
    amplitude: float = 0.0
    phase: float = 0.0

    def radial_offset(self, phi) -> np.ndarray:
        """``a cos(k (φ − φ_0))`` (m) at the angles ``phi`` (rad)."""
        return self.amplitude * np.cos(self.lobes * (np.asarray(phi, dtype=float) - self.phase))


def _ring_sector(n_sectors, inner_radius, thickness, axial_length) -> int:
    occ = gmsh.model.occ
    angle = 2.0 * math.pi / n_sectors
    x0 = -axial_length / 2
    outer = occ.addCylinder(x0, 0, 0, axial_length, 0, 0, inner_radius + thickness, angle=angle)
    inner = occ.addCylinder(x0, 0, 0, axial_length, 0, 0, inner_radius, angle=angle)
    (ring,), _ = occ.cut([(3, outer)], [(3, inner)])
    centre = np.array(occ.getCenterOfMass(3, ring[1]))
    occ.rotate([ring], 0, 0, 0, 1, 0, 0, -float(sector_angle(centre[:, None])[0]))
    return ring[1]


def casing_ring_sector(  # noqa: PLR0913 (keyword options, one per scene key)
    n_sectors: int,
    inner_radius: float,
    thickness: float,
    axial_length: float,
    *,
    distortion: RingDistortion | None = None,
    h: float | None = None,
    verbose: bool = False,
) -> SectorMesh:
    """Mesh one cyclic sector of the casing ring (module docstring).

    Parameters
    ----------
    n_sectors : int
        ``N`` (>= 3): the ring's nodal diameters are 0 .. ⌊N/2⌋.
    inner_radius, thickness, axial_length : float
        Inner radius, radial wall thickness and axial length between the flanges (m).
    distortion : RingDistortion, optional
        Out-of-roundness kept in ``info["distortion"]`` (default: round).
    h : float, optional
        Element size (m); default ``max(thickness, axial_length / 6)``.
    verbose : bool
        Show gmsh messages.

    Returns
    -------
    SectorMesh
        ``structure = "casing"``.
    """
    check_positive(
        "Casing ring", inner_radius=inner_radius, thickness=thickness, axial_length=axial_length
    )
    if int(n_sectors) != n_sectors or n_sectors < 3:
        raise GeometryError(f"a casing ring needs at least 3 sectors, got {n_sectors!r}")
    h = max(thickness, axial_length / 6) if h is None else h
    size = MeshSize(h, min(h, thickness) / 2, curvature=0)
    half = math.pi / n_sectors
    with gmsh_session(verbose, "casing-ring") as session:
        ring = _ring_sector(n_sectors, inner_radius, thickness, axial_length)
        gmsh.model.occ.synchronize()
        faces = [t for _, t in gmsh.model.getBoundary([(3, ring)], oriented=False)]
        left, right = cyclic_plane_distance(half)
        groups = classify_faces(
            faces,
            {"root": lambda p: np.abs(p[0]) - axial_length / 2, "left": left, "right": right},
            tol=1e-6 * inner_radius,
        )
        set_periodic(groups["left"], groups["right"], 2.0 * half)
        gmsh.model.addPhysicalGroup(3, [ring], name="blade")
        for name, tags in groups.items():
            gmsh.model.addPhysicalGroup(2, tags, name=name)
        size.apply(session)
        gmsh.model.mesh.generate(3)
        mesh = to_blade_mesh(
            "x",
            f"casing_ring_sector(N={n_sectors}, r={inner_radius}, thickness={thickness},"
            f" length={axial_length}, h={h})",
        )
    for name in ("root", "left", "right"):
        mesh.require(name)
    info = dict(
        inner_radius=inner_radius,
        thickness=thickness,
        axial_length=axial_length,
        distortion=distortion or RingDistortion(0),
        h=h,
    )
    return SectorMesh(mesh, int(n_sectors), "casing", info)
