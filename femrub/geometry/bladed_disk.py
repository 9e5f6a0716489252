"""One cyclic sector of a bladed disk: an annular disk sector with a twisted NACA blade on its rim.

The disk sector is the annulus ``hub_radius <= r <= rim_radius``, ``|x| <= thickness / 2``
between the cyclic half-planes ``φ = ∓π/N`` (:mod:`femrub.geometry.cyclic_sector`); the
blade of :func:`~femrub.geometry.naca_blade.naca_sections` stands on the rim at ``φ = 0``
(span along ``+z``, chord along the axis ``x`` at the root, centred on the disk), its root
section sunk below the rim by the rim's sagitta under the root section so that the two
solids fuse into one. The blade's chords are scaled down (both by one factor, recorded
as ``info["chord_scale"]``) when the root section is longer than 90 % of the disk's
thickness or a section reaches within 10 % of a cyclic plane.

Node sets: ``root`` (the hub bore, clamped), ``left`` and ``right`` (cyclic faces, meshed
periodic), ``tip`` (the blade's tip face).
"""

from __future__ import annotations

import math

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
from .loft import _add_wire
from .mesh_size import MeshSize
from .naca import naca4_parameters
from .naca_blade import naca_sections

__all__ = [
    "bladed_disk_sector",
    "disk_sector_solid",
    "fitted_blade_sections",
    "mesh_disk_sector",
]

#: Share of the disk's thickness the blade's root chord may take.
AXIAL_FILL = 0.9
#: Share of the half-width of the sector (at each section's radius) the blade may take.
CIRCUMFERENTIAL_FILL = 0.9


def _sections(blade: dict, root_z: float, chord_scale: float):
    b = dict(blade)
    span = b.pop("span")
    sections = naca_sections(
        b.pop("code"),
        span,
        b.pop("root_chord") * chord_scale,
        b.pop("tip_chord") * chord_scale,
        b.pop("twist"),
        b.pop("n_sections"),
        hub_radius=root_z,
        **b,
    )
    x0, x1 = (f(np.hstack(sections[0])[0]) for f in (np.min, np.max))
    shift = np.array([[-(x0 + x1) / 2], [0.0], [0.0]])
    return [(a + shift, c + shift) for a, c in sections]


def fitted_blade_sections(blade: dict, n_sectors: int, rim_radius: float, thickness: float):
    """The blade's sections on the rim, chords scaled to fit the sector.

    Parameters
    ----------
    blade : dict
        Keyword arguments of :func:`~femrub.geometry.naca_blade.naca_sections` (``code``,
        ``span``, ``root_chord``, ``tip_chord``, ``twist``, ``n_sections``, optional
        ``stacking``, ``n_points``), lengths in metres, twist in degrees.
    n_sectors : int
        ``N``.
    rim_radius, thickness : float
        The disk's rim radius and axial thickness (m).

    Returns
    -------
    sections : list
        Sides ``(3, m)`` of each section, root section at ``z = rim_radius − depth``.
    chord_scale : float
        Factor applied to both chords (1 when the blade fits).
    depth : float
        How far the root section lies below the rim (m): the rim's sagitta under it plus
        2 % of the span.
    """
    half = math.pi / n_sectors
    trial = _sections(blade, rim_radius, 1.0)
    axial = float(np.ptp(np.hstack(trial[0])[0]))
    scale = min(1.0, AXIAL_FILL * thickness / axial)
    for a, c in trial:
        pts = np.hstack([a, c])
        room = CIRCUMFERENTIAL_FILL * pts[2].min() * math.tan(half)
        scale = min(scale, room / max(np.abs(pts[1]).max(), 1e-300))
    root = np.hstack(_sections(blade, rim_radius, scale)[0])
    y = np.abs(root[1]).max()
    if y >= rim_radius:
        raise GeometryError("the blade's root section is wider than the rim; use fewer sectors")
    depth = rim_radius - math.sqrt(rim_radius**2 - y**2) + 0.02 * blade["span"]
    sections = _sections({**blade, "span": blade["span"] + depth}, rim_radius - depth, scale)
    return sections, scale, depth


def disk_sector_solid(n_sectors, hub_radius, rim_radius, thickness) -> int:
    """The annular disk sector as an OpenCASCADE volume centred on ``φ = 0``; its tag."""
    occ = gmsh.model.occ
    angle = 2.0 * math.pi / n_sectors
    outer = occ.addCylinder(-thickness / 2, 0, 0, thickness, 0, 0, rim_radius, angle=angle)
    inner = occ.addCylinder(-thickness / 2, 0, 0, thickness, 0, 0, hub_radius, angle=angle)
    (disk,), _ = occ.cut([(3, outer)], [(3, inner)])
    centre = np.array(occ.getCenterOfMass(3, disk[1]))
    occ.rotate([disk], 0, 0, 0, 1, 0, 0, -float(sector_angle(centre[:, None])[0]))
    return disk[1]


def _check(n_sectors, hub_radius, rim_radius, thickness) -> None:
    check_positive("Bladed disk", hub_radius=hub_radius, thickness=thickness)
    if not rim_radius > hub_radius:
        raise GeometryError(
            f"the disk's rim_radius {rim_radius!r} m must exceed its hub_radius {hub_radius!r} m"
        )
    if int(n_sectors) != n_sectors or n_sectors < 3:
        raise GeometryError(f"a bladed disk needs at least 3 sectors, got {n_sectors!r}")


def bladed_disk_sector(  # noqa: PLR0913 (keyword options, one per scene key)
    n_sectors: int,
    hub_radius: float,
    rim_radius: float,
    thickness: float,
    blade: dict,
    *,
    h: float,
    h_min: float | None = None,
    verbose: bool = False,
) -> SectorMesh:
    """Mesh one cyclic sector of a bladed disk with periodic cyclic faces (module docstring).

    Parameters
    ----------
    n_sectors : int
        Number of blades ``N`` (>= 3).
    hub_radius, rim_radius, thickness : float
        Bore radius, rim radius and axial thickness of the disk (m).
    blade : dict
        The NACA blade (see :func:`fitted_blade_sections`).
    h, h_min : float
        Target and smallest element size (m).
    verbose : bool
        Show gmsh messages.

    Returns
    -------
    SectorMesh
        ``structure = "disk"``; ``info``: the radii, ``chord_scale``, ``root_depth``,
        ``tip_radius`` (the largest radius of the blade's tip face, m).
    """
    _check(n_sectors, hub_radius, rim_radius, thickness)
    naca4_parameters(blade["code"])
    sections, scale, depth = fitted_blade_sections(blade, n_sectors, rim_radius, thickness)
    size = MeshSize(h, h_min)
    occ = gmsh.model.occ
    z_tip = float(sections[-1][0][2, 0])
    disk = (n_sectors, hub_radius, rim_radius, thickness)
    with gmsh_session(verbose, "bladed-disk") as session:
        sector = disk_sector_solid(*disk)
        wires = [_add_wire(a, c, True) for a, c in sections]
        loft = [t for d, t in occ.addThruSections(wires, makeSolid=True) if d == 3]
        mesh = mesh_disk_sector(
            session,
            disk,
            sector,
            loft,
            lambda faces: classify_faces(
                faces, {"tip": lambda p: p[2] - z_tip}, tol=1e-6 * rim_radius
            )["tip"],
            size,
            f"bladed_disk_sector(N={n_sectors}, hub={hub_radius}, rim={rim_radius},"
            f" thickness={thickness}, h={h})",
        )
    tip_radius = float(mesh.radius(mesh.mesh.p[:, mesh.node_sets["tip"]]).max())
    info = dict(
        hub_radius=hub_radius,
        rim_radius=rim_radius,
        thickness=thickness,
        chord_scale=scale,
        root_depth=depth,
        tip_radius=tip_radius,
        h=size.h,
    )
    return SectorMesh(mesh, int(n_sectors), "disk", info)


def mesh_disk_sector(  # noqa: PLR0913 (the parts of one gmsh model)
    session, disk: tuple, sector: int, blade: list[int], tip, size: MeshSize, source: str
):
    """Fuse a blade with the disk sector and mesh the sector with periodic cyclic faces.

    Parameters
    ----------
    session : GmshSession
        The open gmsh session holding the disk sector's and the blade's volumes.
    disk : tuple
        ``(n_sectors, hub_radius, rim_radius, thickness)`` (lengths in m).
    sector : int
        The disk sector's volume tag (:func:`disk_sector_solid`).
    blade : list of int
        The blade's volume tags.
    tip : callable
        ``faces -> tags``: the fused solid's surfaces that form the blade's tip face.
    size : MeshSize
        Element sizes.
    source : str
        Description stored in the mesh.

    Returns
    -------
    BladeMesh
        Node sets ``root`` (the bore), ``left``, ``right`` and ``tip``.
    """
    n_sectors, hub_radius, rim_radius, thickness = disk
    occ = gmsh.model.occ
    half = math.pi / n_sectors
    fused, _ = occ.fuse([(3, sector)], [(3, t) for t in blade])
    occ.synchronize()
    volumes = [t for d, t in fused if d == 3]
    if len(volumes) != 1:
        raise GeometryError(
            f"the blade and the disk sector did not fuse into one solid ({len(volumes)});"
            " check the blade's span and chords against the rim"
        )
    faces = [t for _, t in gmsh.model.getBoundary([(3, volumes[0])], oriented=False)]
    left, right = cyclic_plane_distance(half)
    groups = classify_faces(
        faces,
        {"root": lambda p: np.hypot(p[1], p[2]) - hub_radius, "left": left, "right": right},
        tol=1e-6 * rim_radius,
    )
    groups["tip"] = tip(faces)
    set_periodic(groups["left"], groups["right"], 2.0 * half)
    gmsh.model.addPhysicalGroup(3, volumes, name="blade")
    for name, tags in groups.items():
        gmsh.model.addPhysicalGroup(2, tags, name=name)
    size.apply(session)
    gmsh.model.mesh.generate(3)
    if not any(len(t) for t in gmsh.model.mesh.getElements(3)[1]):
        raise GeometryError(
            f"gmsh could not mesh the bladed disk sector with h = {size.h:g} m, h_min ="
            f" {size.h_min:g} m; use a smaller element size (rotor.h, geometry.h_min)"
        )
    mesh = to_blade_mesh("x", source)
    for name in ("root", "left", "right", "tip"):
        mesh.require(name)
    return mesh
