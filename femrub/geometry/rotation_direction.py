"""Which way a blade turns, from its tip section: a blade moves towards its pressure side.

The rule (``loads.rotation_direction = "auto"``). The tip face of the blade is projected
on the plane of the machine axis ``a`` and the circumferential direction ``e_φ = a × e_r``
at the face (``e_r``: the radial direction of its centroid), giving the section's outline in
coordinates ``(z, s) = (a · p, e_φ · p)`` (m). Its chord is the longest segment between two
of its points (leading to trailing edge, in either order), of length ``c`` and unit vector
``t``, with the in-plane normal ``n = (−t_s, t_z)``. The area centroid of the face lies at
the signed distance ``d = n · (x̄ − x_0)`` from the chord: on the convex side of the camber
line, the suction side (a section whose thickness is laid symmetrically about a camber line
``y_c(x) >= 0`` has its centroid at ``∫ t y_c / ∫ t > 0``). The pressure side is the other
one, ``−sign(d) n``, and the blade moves towards it (the relative flow presses on the side
that leads), so its circumferential component

    ``σ = −sign(d) t_z``

is the direction of motion along ``e_φ``: ``σ > 0`` counterclockwise about ``a`` (the
angle ``φ`` of :func:`femrub.contact.points.locate_contacts` increases: Ω along ``+a`` by
the right-hand rule), ``σ < 0`` clockwise.

The rule cannot decide, and the direction stays counterclockwise (the direction of the
casing phase ``θ = Ω t + φ`` with Ω > 0), when the blade has no airfoil: the paper's 1D bar,
a blade without a tip face, a section without camber (``|d| < CAMBER_MIN c``: a flat box
blade, a symmetric NACA 00xx), or a chord across the axis (``|t_z| < AXIAL_MIN``: the
pressure side faces along the axis).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "AXIAL_MIN",
    "CAMBER_MIN",
    "DEFAULT_DIRECTION",
    "ROTATION_DIRECTIONS",
    "RotationDirection",
    "TipSection",
    "derive_rotation_direction",
    "tip_section",
]

#: the two directions, as the sign of the rotation about the machine axis (right-hand rule)
ROTATION_DIRECTIONS = {"counterclockwise": 1.0, "clockwise": -1.0}
#: the direction when the geometry does not decide (the casing phase θ = Ω t + φ, Ω > 0)
DEFAULT_DIRECTION = "counterclockwise"
#: smallest centroid offset from the chord, as a fraction of the chord, that is a camber
CAMBER_MIN = 0.005
#: smallest axial component of the chord's unit vector that decides the direction
AXIAL_MIN = 0.1


@dataclass(frozen=True)
class RotationDirection:
    """A rotation direction, ``"counterclockwise"`` or ``"clockwise"`` about the machine
    axis, and where it comes from (``source``: ``"scene"``, ``"geometry"`` or ``"default"``;
    ``reason``: one line for ``--explain``)."""

    direction: str
    source: str
    reason: str

    @property
    def sign(self) -> float:
        """+1 counterclockwise, −1 clockwise."""
        return ROTATION_DIRECTIONS[self.direction]


def _default(why: str) -> RotationDirection:
    return RotationDirection(
        DEFAULT_DIRECTION, "default", f"{DEFAULT_DIRECTION} (not derived: {why})"
    )


def _tip_faces(blade) -> np.ndarray:
    """Vertex indices (3, n_f) of the boundary triangles whose vertices are all tip nodes."""
    tip = blade.node_sets.get("tip")
    if tip is None or tip.size < 3:
        return np.zeros((3, 0), dtype=int)
    facets = blade.mesh.facets[:, blade.mesh.boundary_facets()]
    on_tip = np.isin(facets, tip).all(axis=0)
    return facets[:, on_tip]


def _section(blade, faces: np.ndarray):
    """The tip faces' corners in ``(z, s)`` (m, shape (3, n_f, 2)) and their areas (m²)."""
    a = blade.axis
    p = blade.mesh.p
    centre = p[:, np.unique(faces)].mean(axis=1)
    radial = centre - (a @ centre) * a
    e_phi = np.cross(a, radial / np.linalg.norm(radial))
    corners = np.einsum("dk,dcf->cfk", np.stack([a, e_phi], axis=1), p[:, faces])
    u, v = corners[1] - corners[0], corners[2] - corners[0]
    areas = 0.5 * np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    return corners, areas


def _chord(points: np.ndarray):
    """The longest segment between two of ``points`` (n, 2): start and unit vector, length."""
    from scipy.spatial import ConvexHull

    hull = points[ConvexHull(points).vertices]
    dist = np.linalg.norm(hull[:, None, :] - hull[None, :, :], axis=-1)
    i, j = np.unravel_index(np.argmax(dist), dist.shape)
    length = float(dist[i, j])
    return hull[i], (hull[j] - hull[i]) / length, length


@dataclass(frozen=True)
class TipSection:
    """The blade's tip face unrolled on the plane ``(z, s) = (a · p, e_φ · p)`` (m).

    ``points`` (n, 2): the corners of its triangles; ``start``, ``tangent``, ``chord``: the
    chord's first end, unit vector and length (m); ``offsets`` (n,): the signed distances of
    ``points`` from the chord along ``n = (−t_s, t_z)`` (m); ``centroid_offset``: that of the
    face's area centroid (m).
    """

    points: np.ndarray
    start: np.ndarray
    tangent: np.ndarray
    chord: float
    offsets: np.ndarray
    centroid_offset: float


def tip_section(blade) -> TipSection | None:
    """The tip section of a 3D ``blade`` (:class:`TipSection`), ``None`` without a tip face."""
    faces = _tip_faces(blade) if blade.dim == 3 else np.zeros((3, 0), dtype=int)
    if faces.shape[1] == 0:
        return None
    corners, areas = _section(blade, faces)
    points = corners.reshape(-1, 2)
    start, t, chord = _chord(points)
    centroid = (areas @ corners.mean(axis=0)) / areas.sum()
    normal = np.array([-t[1], t[0]])
    offsets = (points - start) @ normal
    return TipSection(points, start, t, chord, offsets, float(normal @ (centroid - start)))


def derive_rotation_direction(blade) -> RotationDirection:
    """The direction ``blade`` (a :class:`~femrub.geometry.BladeMesh`) turns in by the
    pressure-side rule (module docstring), or the default with the reason it was not derived.
    """
    if blade.dim != 3:
        return _default("the 1D bar has no airfoil section")
    section = tip_section(blade)
    if section is None:
        return _default("the blade has no tip face")
    offset, chord, t = section.centroid_offset, section.chord, section.tangent
    if abs(offset) < CAMBER_MIN * chord:
        return _default(
            f"the tip section has no camber: centroid {100 * abs(offset) / chord:.2g} % of "
            f"the chord from it, below {100 * CAMBER_MIN:g} %"
        )
    if abs(t[0]) < AXIAL_MIN:
        return _default("the tip chord lies across the axis: the pressure side faces axially")
    sigma = -np.sign(offset) * t[0]
    direction = "counterclockwise" if sigma > 0 else "clockwise"
    return RotationDirection(
        direction,
        "geometry",
        f"{direction} (derived: the blade moves towards its pressure side; tip camber "
        f"{100 * abs(offset) / chord:.2g} % of the {1e3 * chord:.4g} mm chord)",
    )
