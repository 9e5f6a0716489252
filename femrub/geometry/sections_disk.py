"""One cyclic sector of a bladed disk whose blade is lofted through section files.

The disk sector is that of :mod:`femrub.geometry.bladed_disk` (the annulus
``hub_radius <= r <= rim_radius``, ``|x| <= thickness / 2``, between the cyclic half-planes
``φ = ∓π/N``). The blade is real geometry (e.g. the NASA Rotor 37 profiles): its sections
are never scaled, only moved rigidly into the sector's frame (:func:`place_sections`):

* the rotation axis given for the files becomes ``x`` (a cyclic permutation of the
  coordinates, which keeps the handedness);
* the blade is turned about ``x`` by ``−φ_c``, ``φ_c`` the angle of the root section's
  area centroid, so that the root centroid lies at ``φ = 0`` (on ``+z``);
* it is shifted along ``x`` so that the root section's axial extent is centred on the
  disk (``x = 0``).

Below its root (hub) section the blade is extended into the rim: an extra section, the root
section projected along ``−z`` (radially inwards at ``φ = 0``) onto the plane
``z = z_b`` below the rim surface under the root (``z_b = rim_radius cos φ_r − d``, ``φ_r``
the root's largest ``|φ|``, ``d`` 2 % of the span), is lofted with the files' sections in one
``addThruSections`` through every section. The loft passes through every given section
(between the root and the next one its smooth surface differs slightly from the single
sections blade's, as it continues below the root; a ruled loft does not differ). Its
bottom cap is planar and cuts through the rim's cylinder, as the NACA disk's sunk root
does: the fuse meets no coincident faces. A separate shank fused onto the blade would
share the root's non-planar (filled) face exactly with it, a coincident-face fuse, which
this construction avoids.

The blade must fit the sector (:func:`fit_problem`): the rim below the root section, the
root within the disk's thickness, and every section and the extension within the sector,
``|φ| <= 0.95 π/N``. A compressor blade of solidity above one, like Rotor 37, spans more
than its pitch ``2π/N`` about the axis and so does not fit the sector of its own blade
count (Rotor 37: 36 blades; it fits up to ``N = 24`` on a rim at 17 to 17.5 cm): such a
wheel is refused, not altered.

Node sets: ``root`` (the hub bore, clamped), ``left`` and ``right`` (cyclic faces, meshed
periodic), ``tip`` (the blade's tip face, non-planar for a real blade).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gmsh
import numpy as np

from .axes import axis_vector
from .bladed_disk import disk_sector_solid, mesh_disk_sector
from .cyclic_sector import SectorMesh, axis_rotation, sector_angle
from .errors import GeometryError
from .gmsh_session import gmsh_session
from .loft import _add_wire, _cap, _is_planar
from .mesh_size import MeshSize
from .section_blade import MAX_TETS, estimate_section_tets
from .sections import orient_sides, split_section

__all__ = [
    "PlacedBlade",
    "fit_problem",
    "place_sections",
    "root_centroid",
    "sections_disk_sector",
]

#: Share of the sector's half angle ``π/N`` the blade may take on either side of ``φ = 0``.
CIRCUMFERENTIAL_FILL = 0.95
#: How far the extension's bottom lies below the rim surface under the root, in spans.
ROOT_OVERLAP = 0.02

# the cyclic permutation of the coordinates that makes the given axis x (right-handed)
_TO_X = {"x": (0, 1, 2), "y": (1, 2, 0), "z": (2, 0, 1)}


def _flattened(points: np.ndarray, z: float) -> np.ndarray:
    """Points ``(3, m)`` projected along ``z`` onto the plane ``z``."""
    return np.vstack([points[:2], np.full(points.shape[1], z)])


@dataclass(frozen=True)
class PlacedBlade:
    """The sections of a blade in the sector's frame and how they fit.

    Attributes
    ----------
    sections : list of numpy.ndarray
        Closed sections ``(3, m)`` in metres, hub to tip, axis ``x``, root centroid at
        ``φ = 0``, root's axial extent centred on ``x = 0``.
    sides : list of tuple
        Each section split into its two sides from the leading to the trailing edge
        (:func:`~femrub.geometry.sections.split_section`).
    turn : float
        Angle (rad) the blade was turned about ``x`` (``−φ_c``).
    axial_shift : float
        Shift (m) along ``x``.
    phi : tuple of float
        Smallest and largest ``φ`` (rad) of the sections.
    root_radius : float
        Smallest radius (m) of the root section.
    root_phi : float
        Largest ``|φ|`` (rad) of the root section.
    root_axial : float
        Axial extent (m) of the root section.
    span : float
        Radial extent (m) of the blade (largest radius of the tip less the smallest of the
        root).
    """

    sections: list
    sides: list
    turn: float
    axial_shift: float
    phi: tuple
    root_radius: float
    root_phi: float
    root_axial: float
    span: float

    def bottom(self, rim_radius: float) -> float:
        """``z_b`` (m): the plane of the extension's bottom under a rim of ``rim_radius``."""
        return rim_radius * math.cos(self.root_phi) - ROOT_OVERLAP * self.span

    def extension(self, rim_radius: float) -> np.ndarray:
        """The extension's bottom section ``(3, m)``: the root projected onto ``z = z_b``."""
        return _flattened(self.sections[0], self.bottom(rim_radius))

    def extent(self, rim_radius: float) -> tuple[float, float]:
        """Smallest and largest ``φ`` (rad) of the sections and the extension under a rim of
        ``rim_radius`` (projected along ``−z``, the extension spreads wider in ``φ``)."""
        phi = sector_angle(self.extension(rim_radius))
        return min(self.phi[0], float(phi.min())), max(self.phi[1], float(phi.max()))


def root_centroid(points: np.ndarray) -> np.ndarray:
    """Area centroid ``(3,)`` (m) of a closed, possibly non-planar section ``(3, m)``.

    The section is fanned into triangles ``(c, p_i, p_{i+1})`` about the mean point ``c``;
    with ``a_i`` their vector areas and ``n = Σ a_i / |Σ a_i|`` the mean normal, the
    centroid is ``Σ (a_i · n) g_i / Σ (a_i · n)``, ``g_i`` the triangles' centroids.
    """
    c = points.mean(axis=1, keepdims=True)
    p, q = points - c, np.roll(points, -1, axis=1) - c
    a = 0.5 * np.cross(p.T, q.T)
    n = a.sum(axis=0)
    w = a @ (n / max(np.linalg.norm(n), 1e-300))
    g = (p + q) / 3.0
    return c[:, 0] + (g @ w) / w.sum()


def _sides(points: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    try:
        return split_section(points)
    except GeometryError as exc:
        raise GeometryError(f"section {k + 1} (counted from the hub): {exc}") from None


def place_sections(sections: list[np.ndarray], axis="x") -> PlacedBlade:
    """Move closed sections ``(3, m)`` (m, hub to tip, rotation axis ``axis``) rigidly into
    the sector's frame (module docstring) and measure them."""
    vec = axis_vector(axis)
    named = next((k for k, v in (("x", 0), ("y", 1), ("z", 2)) if vec[v] == 1.0), None)
    if named is None:
        raise GeometryError(f"the sections' rotation axis must be x, y or z, got {axis!r}")
    order = list(_TO_X[named])
    moved = [np.asarray(s, dtype=float)[order] for s in sections]
    turn = -float(sector_angle(root_centroid(moved[0])[:, None])[0])
    rot = axis_rotation(turn)
    moved = [rot @ s for s in moved]
    x = moved[0][0]
    shift = -0.5 * float(x.min() + x.max())
    moved = [s + np.array([[shift], [0.0], [0.0]]) for s in moved]
    phi = np.hstack([sector_angle(s) for s in moved])
    radius = [np.hypot(s[1], s[2]) for s in moved]
    return PlacedBlade(
        moved,
        orient_sides([_sides(s, k) for k, s in enumerate(moved)]),
        turn,
        shift,
        (float(phi.min()), float(phi.max())),
        float(radius[0].min()),
        float(np.abs(sector_angle(moved[0])).max()),
        float(np.ptp(moved[0][0])),
        float(radius[-1].max() - radius[0].min()),
    )


def largest_sectors(extent: float) -> int:
    """The largest ``N`` whose sector holds a blade reaching ``|φ| = extent`` (rad)."""
    return int(math.floor(CIRCUMFERENTIAL_FILL * math.pi / extent))


def fit_problem(
    blade: PlacedBlade, n_sectors: int, hub_radius: float, rim_radius: float, thickness: float
):
    """Why the blade does not fit the disk sector, or ``None``.

    Returns
    -------
    tuple or None
        ``(parameter, value, reason)``: the disk parameter at fault (``"rim_radius"``,
        ``"thickness"``, ``"hub_radius"`` or ``"sectors"``), its value and a one-line
        reason with the fix.
    """
    if not rim_radius < blade.root_radius:
        return (
            "rim_radius",
            rim_radius,
            f"the blade's root section reaches down to r = {blade.root_radius:.6g} m; the rim "
            f"must lie below it (rim_radius < {blade.root_radius:.6g} m)",
        )
    if blade.root_axial > thickness:
        return (
            "thickness",
            thickness,
            f"the blade's root section spans {blade.root_axial:.6g} m along the axis; the disk "
            f"must hold it (thickness >= {blade.root_axial:.6g} m)",
        )
    if not blade.bottom(rim_radius) > hub_radius:
        return (
            "hub_radius",
            hub_radius,
            f"the blade's root extends into the rim down to z = {blade.bottom(rim_radius):.6g}"
            " m; the bore must lie below it",
        )
    lo, hi = blade.extent(rim_radius)
    extent = max(-lo, hi)
    if extent > CIRCUMFERENTIAL_FILL * math.pi / n_sectors:
        return (
            "sectors",
            n_sectors,
            f"the blade (its root extended into the rim) spans φ = {math.degrees(lo):.3g}° to "
            f"{math.degrees(hi):.3g}° about the axis, its root centroid at 0°: more than "
            f"{100 * CIRCUMFERENTIAL_FILL:g} % of the sector's ±{180 / n_sectors:.3g}°; the "
            f"largest N that fits is {largest_sectors(extent)}",
        )
    return None


def _blade_volume(wires, tip_planar: bool, ruled: bool) -> tuple[int, int]:
    """The lofted blade (planar bottom cap, tip cap planar or filled) and its tip cap."""
    occ = gmsh.model.occ
    lateral = [t for d, t in occ.addThruSections(wires, makeSolid=False, makeRuled=ruled) if d == 2]
    caps = [_cap(wires[0], True), _cap(wires[-1], tip_planar)]
    loop = occ.addSurfaceLoop(lateral + caps, sewing=True)
    return occ.addVolume([loop]), caps[1]


def _tip_face(faces: list[int], centre: np.ndarray, span: float) -> list[int]:
    """The surface of ``faces`` whose centre of mass lies nearest to the tip cap's
    ``centre`` (sewing and the fuse rebuild a filled cap to within a fraction of a per
    cent); none when even the nearest one lies farther than 1 % of the ``span``."""
    occ = gmsh.model.occ
    gap = [np.linalg.norm(np.array(occ.getCenterOfMass(2, f)) - centre) for f in faces]
    best = int(np.argmin(gap))
    return [faces[best]] if gap[best] <= 0.01 * span else []


def sections_disk_sector(  # noqa: PLR0913 (keyword options, one per scene key)
    n_sectors: int,
    hub_radius: float,
    rim_radius: float,
    thickness: float,
    blade: PlacedBlade,
    *,
    h: float,
    h_min: float | None = None,
    interpolate: bool = False,
    ruled: bool = False,
    verbose: bool = False,
) -> SectorMesh:
    """Mesh one cyclic sector of a bladed disk with a blade lofted through sections.

    Parameters
    ----------
    n_sectors : int
        Number of blades ``N`` (>= 3).
    hub_radius, rim_radius, thickness : float
        Bore radius, rim radius and axial thickness of the disk (m).
    blade : PlacedBlade
        The sections in the sector's frame (:func:`place_sections`).
    h, h_min : float
        Target and smallest element size (m).
    interpolate, ruled : bool
        Interpolating splines through the points (else B-splines with the points as control
        points) and a ruled loft, as for the single sections blade.
    verbose : bool
        Show gmsh messages.

    Returns
    -------
    SectorMesh
        ``structure = "disk"``; ``info``: the radii, ``turn`` (rad) and ``axial_shift`` (m)
        of the placement, ``root_depth`` (m, from the root's lowest point to the extension's
        bottom), ``tip_radius`` (the largest radius of the blade's tip face, m).

    Raises
    ------
    GeometryError
        When the blade does not fit the sector (:func:`fit_problem`), before meshing.
    """
    problem = fit_problem(blade, n_sectors, hub_radius, rim_radius, thickness)
    if problem is not None:
        name, value, reason = problem
        raise GeometryError(f"{name} = {value!r}: {reason}")
    size = MeshSize(h, h_min)
    n = estimate_section_tets(blade.sections, size.h)
    if n > MAX_TETS:
        raise GeometryError(
            f"h = {size.h:.4g} m gives about {min(n, 1e300):.2g} tetrahedra in the blade "
            f"(at most {MAX_TETS:.0e}, estimated before meshing); raise h"
        )
    sides = list(blade.sides)
    bottom = blade.bottom(rim_radius)
    sides.insert(0, tuple(_flattened(side, bottom) for side in sides[0]))
    disk = (n_sectors, hub_radius, rim_radius, thickness)
    with gmsh_session(verbose, "sections-disk") as session:
        sector = disk_sector_solid(*disk)
        wires = [_add_wire(a, b, interpolate) for a, b in sides]
        volume, cap = _blade_volume(wires, _is_planar(*sides[-1]), ruled)
        occ = gmsh.model.occ
        centre = np.array(occ.getCenterOfMass(2, cap))

        def tip(faces):
            return _tip_face(faces, centre, blade.span)

        mesh = mesh_disk_sector(
            session,
            disk,
            sector,
            [volume],
            tip,
            size,
            f"sections_disk_sector(N={n_sectors}, hub={hub_radius}, rim={rim_radius},"
            f" thickness={thickness}, h={h})",
        )
    tip_radius = float(mesh.radius(mesh.mesh.p[:, mesh.node_sets["tip"]]).max())
    info = dict(
        hub_radius=hub_radius,
        rim_radius=rim_radius,
        thickness=thickness,
        turn=blade.turn,
        axial_shift=blade.axial_shift,
        root_depth=blade.root_radius - blade.bottom(rim_radius),
        tip_radius=tip_radius,
        h=size.h,
    )
    return SectorMesh(mesh, int(n_sectors), "disk", info)
