"""A cyclic sector of a structure with N-fold rotational symmetry about the machine axis x.

The sector spans the angles ``−α/2 <= φ <= α/2`` (``α = 2π/N``) about the axis ``x``,
``φ`` measured from ``+z`` by the right-hand rule about ``+x``. Its two cyclic faces are
the half-planes ``φ = −α/2`` (``left``) and ``φ = +α/2`` (``right``); the right face is the
left one turned by ``R(α)``::

    R(β) = [[1, 0, 0], [0, cos β, −sin β], [0, sin β, cos β]]

(a positive turn about ``+x`` takes ``+y`` to ``+z``, so ``φ`` here grows from ``+z``
towards ``−y``). gmsh meshes the right face as a copy of the left one
(``gmsh.model.mesh.setPeriodic``), so every node of one face has its image on the other:
:func:`face_pairs` finds them, and :func:`full_wheel` turns the sector ``N`` times and
merges the shared nodes into the whole structure's mesh.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import gmsh
import numpy as np
import skfem
from scipy.spatial import cKDTree

from .blade_mesh import BladeMesh
from .errors import GeometryError

__all__ = [
    "SectorMesh",
    "axis_rotation",
    "classify_faces",
    "face_pairs",
    "full_wheel",
    "set_periodic",
    "sector_angle",
    "sector_turns",
]


def axis_rotation(beta: float) -> np.ndarray:
    """``R(β)``: the turn by ``β`` (rad) about the machine axis ``+x``, shape ``(3, 3)``."""
    c, s = np.cos(beta), np.sin(beta)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def sector_turns(n_sectors: int) -> np.ndarray:
    """``(N, 3, 3)``: ``R(sα)`` of every sector ``s`` of ``N`` (``α = 2π/N``)."""
    alpha = 2.0 * np.pi / n_sectors
    return np.stack([axis_rotation(s * alpha) for s in range(n_sectors)])


def sector_angle(points: np.ndarray) -> np.ndarray:
    """Angle ``φ`` (rad) of points ``(3, n)`` about ``+x``, from ``+z`` (module docstring)."""
    return np.arctan2(-points[1], points[2])


@dataclass
class SectorMesh:
    """The mesh of one cyclic sector and its symmetry.

    Attributes
    ----------
    mesh : BladeMesh
        Linear tetrahedra in metres; node sets ``root`` (clamped faces), ``left`` and
        ``right`` (cyclic faces), and builder-specific ones (``tip`` of a blade).
    n_sectors : int
        ``N``: the whole structure is ``N`` turned copies of the sector.
    structure : str
        ``"disk"`` (a bladed disk sector) or ``"casing"`` (a casing ring sector).
    info : dict
        Builder parameters (radii, lengths, mesh sizes, the casing's distortion).
    """

    mesh: BladeMesh
    n_sectors: int
    structure: str
    info: dict = field(default_factory=dict)

    @property
    def angle(self) -> float:
        """``α = 2π/N`` (rad)."""
        return 2.0 * np.pi / self.n_sectors

    @property
    def rotation(self) -> np.ndarray:
        """``R(α)``, which takes the left face onto the right one."""
        return axis_rotation(self.angle)


def _surface_samples(tag: int, n: int = 5) -> np.ndarray:
    """Points ``(3, n²)`` of a model surface on a grid of its parameters."""
    lo, hi = gmsh.model.getParametrizationBounds(2, tag)
    u, v = np.meshgrid(np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n))
    uv = np.column_stack([u.ravel(), v.ravel()]).ravel()
    return np.asarray(gmsh.model.getValue(2, tag, uv)).reshape(-1, 3).T


def classify_faces(volume_faces, tests: dict, tol: float) -> dict[str, list[int]]:
    """Surfaces whose sampled points all satisfy a named test.

    Parameters
    ----------
    volume_faces : iterable of int
        Surface tags of the synchronised model.
    tests : dict of str to callable
        ``name -> f(points) -> distances (n,)``: a surface is in group ``name`` when every
        sample lies within ``tol`` of zero.
    tol : float
        Distance tolerance in metres.
    """
    groups = {name: [] for name in tests}
    for tag in volume_faces:
        pts = _surface_samples(tag)
        for name, test in tests.items():
            if np.all(np.abs(test(pts)) <= tol):
                groups[name].append(tag)
    return groups


def cyclic_plane_distance(half_angle: float):
    """Signed distances ``(left, right)`` of points to the cyclic half-planes ``φ = ∓α/2``."""

    def left(p):
        d = axis_rotation(-half_angle) @ np.array([0.0, 1.0, 0.0])  # normal of φ = −α/2
        return d @ p

    def right(p):
        d = axis_rotation(half_angle) @ np.array([0.0, 1.0, 0.0])
        return d @ p

    return left, right


def set_periodic(left: list[int], right: list[int], angle: float) -> None:
    """Mesh the ``right`` surfaces as the ``left`` ones turned by ``R(angle)``."""
    if len(left) != 1 or len(right) != 1:
        raise GeometryError(
            f"the cyclic faces of the sector were not found as single surfaces (left {left},"
            f" right {right}); check that nothing but the disk crosses the sector's sides"
        )
    affine = np.eye(4)
    affine[:3, :3] = axis_rotation(angle)
    gmsh.model.mesh.setPeriodic(2, right, left, affine.ravel().tolist())


def face_pairs(points: np.ndarray, left: np.ndarray, right: np.ndarray, rotation, tol: float):
    """Match the points of the right face to the turned points of the left one.

    Parameters
    ----------
    points : numpy.ndarray
        Coordinates ``(3, n)``.
    left, right : numpy.ndarray
        Indices of the points on each cyclic face.
    rotation : numpy.ndarray
        ``R(α)``.
    tol : float
        Largest distance (m) between a turned left point and its right image.

    Returns
    -------
    numpy.ndarray
        The right-face indices ordered so that entry ``i`` is the image of ``left[i]``.

    Raises
    ------
    GeometryError
        When the faces do not hold the same number of points or a point has no image.
    """
    if left.size != right.size:
        raise GeometryError(
            f"the cyclic faces hold {left.size} and {right.size} nodes; the sector mesh is not"
            " periodic (mesh it with gmsh's periodic constraint)"
        )
    turned = rotation @ points[:, left]
    dist, idx = cKDTree(points[:, right].T).query(turned.T)
    if dist.size and (dist.max() > tol or np.unique(idx).size != idx.size):
        raise GeometryError(
            f"a node of the left cyclic face has no image on the right one (distance "
            f"{dist.max():.3g} m > {tol:.3g} m); the sector mesh is not periodic"
        )
    return right[idx]


def full_wheel(sector: SectorMesh, tol: float | None = None):
    """The whole structure: the sector turned ``N`` times, shared face nodes merged.

    Copy ``s`` is the sector turned by ``R(s α)``; its right face is merged with the left
    face of copy ``s + 1``.

    Returns
    -------
    mesh : BladeMesh
        The whole structure's tetrahedra with node sets ``root`` (and ``tip``, when the
        sector has it) of every copy.
    copies : numpy.ndarray
        ``(N, n_vertices of the sector)``: the whole mesh's vertex of each sector vertex in
        each copy.
    """
    blade = sector.mesh
    p, t = blade.mesh.p, blade.mesh.t
    n, N = p.shape[1], sector.n_sectors
    left, right = blade.require("left"), blade.require("right")
    scale = float(np.ptp(p, axis=1).max())
    tol = 1e-8 * scale if tol is None else tol
    image = face_pairs(p, left, right, sector.rotation, tol)  # right node of each left node
    # vertex numbering: every copy's own vertices, its right face taken from the next copy
    own = np.setdiff1d(np.arange(n), image)
    copies = np.empty((N, n), dtype=np.int64)
    for s in range(N):
        copies[s, own] = s * own.size + np.arange(own.size)
    for s in range(N):
        copies[s, image] = copies[(s + 1) % N, left]
    points = np.empty((3, N * own.size))
    for s in range(N):
        points[:, copies[s, own]] = axis_rotation(s * sector.angle) @ p[:, own]
    tets = np.hstack([copies[s][t] for s in range(N)])
    node_sets = {
        name: np.unique(copies[:, blade.node_sets[name]])
        for name in ("root", "tip")
        if name in blade.node_sets
    }
    mesh = BladeMesh(
        mesh=skfem.MeshTet1(np.ascontiguousarray(points), np.ascontiguousarray(tets)),
        node_sets=node_sets,
        contact_points=np.zeros((3, 0)),
        radial_axis="x",
        source=f"{N} copies of {blade.source}",
    )
    return mesh, copies
