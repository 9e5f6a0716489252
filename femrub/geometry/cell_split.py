"""Conforming split of wedges (prisms) and hexahedra into tetrahedra.

Each quadrilateral face is cut along the diagonal through its vertex with the
smallest global node number. Two cells sharing a face see the same numbers, so
they cut it the same way and the resulting tetrahedral mesh is conforming.
With this rule every prism splits into 3 and every hexahedron into 5 or 6
tetrahedra without extra points (Dompierre et al., "How to subdivide pyramids,
prisms and hexahedra into tetrahedra", 1999). The split templates for every
diagonal configuration are found once by a small exact-cover search on the
reference cell.
"""

from __future__ import annotations

from functools import cache
from itertools import combinations

import numpy as np

from .errors import GeometryError

__all__ = ["CELL_KINDS", "split_into_tets"]

# Reference corners (Abaqus/gmsh/VTK order) and quadrilateral faces (cyclic order).
_REF = {
    "wedge": (
        [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1)],
        [(0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
        [(0, 1, 2), (3, 4, 5)],
    ),
    "hexahedron": (
        [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
        [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
        [],
    ),
    "tetra": ([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], [], [(0, 1, 2), (0, 1, 3)]),
}

#: Number of corner nodes of each supported cell kind.
CELL_KINDS = {kind: len(ref[0]) for kind, ref in _REF.items()}


def _signed_volume(x: np.ndarray, tet: tuple[int, ...]) -> float:
    a, b, c, d = (x[i] for i in tet)
    return float(np.dot(np.cross(b - a, c - a), d - a)) / 6.0


def _boundary_triangles(kind: str, bits: int) -> tuple[set[frozenset[int]], set[frozenset[int]]]:
    """Required boundary triangles and forbidden edges (the uncut diagonals)."""
    _, quads, tris = _REF[kind]
    out = {frozenset(tri) for tri in tris}
    forbidden = set()
    for k, (a, b, c, d) in enumerate(quads):
        if (bits >> k) & 1:
            out |= {frozenset((a, b, d)), frozenset((b, c, d))}
            forbidden.add(frozenset((a, c)))
        else:
            out |= {frozenset((a, b, c)), frozenset((a, c, d))}
            forbidden.add(frozenset((b, d)))
    return out, forbidden


def _search(x, candidates, required, open_faces, used, volume):
    """Depth-first exact cover: close every open face exactly once."""
    if not open_faces:
        return list(used) if abs(volume) < 1e-12 else None
    options = {}
    for face, side in open_faces.items():
        centre = np.mean([x[i] for i in face], axis=0)
        options[face] = [
            tet
            for tet in candidates.get(face, ())
            if tet not in used and np.dot(x[(set(tet) - face).pop()] - centre, side) > 0
        ]
        if len(options[face]) < 2:
            break
    face = min(options, key=lambda f: len(options[f]))
    for tet in options[face]:
        if abs(_signed_volume(x, tet)) > volume + 1e-12:
            continue
        new_open, ok = dict(open_faces), True
        for tri in map(frozenset, combinations(tet, 3)):
            if tri in new_open:
                del new_open[tri]
            elif tri in required:
                ok = False  # boundary face already covered
                break
            else:
                other = (set(tet) - tri).pop()
                pts = [x[i] for i in tri]
                normal = np.cross(pts[1] - pts[0], pts[2] - pts[0])
                if np.dot(x[other] - pts[0], normal) > 0:
                    normal = -normal
                new_open[tri] = normal
        if ok:
            found = _search(
                x,
                candidates,
                required,
                new_open,
                used | {tet},
                volume - abs(_signed_volume(x, tet)),
            )
            if found is not None:
                return found
    return None


@cache
def _template(kind: str, bits: int) -> tuple[tuple[int, ...], ...] | None:
    """Positively oriented tetrahedra of reference cell ``kind`` for diagonal ``bits``."""
    coords, _, _ = _REF[kind]
    x = np.array(coords, dtype=float)
    n = len(x)
    volume = 0.5 if kind == "wedge" else (1.0 if kind == "hexahedron" else 1.0 / 6.0)
    required, forbidden = _boundary_triangles(kind, bits)
    candidates: dict[frozenset[int], list[tuple[int, ...]]] = {}
    for tet in combinations(range(n), 4):
        vol = _signed_volume(x, tet)
        if abs(vol) < 1e-12 or any(frozenset(e) in forbidden for e in combinations(tet, 2)):
            continue
        tet = tet if vol > 0 else (tet[0], tet[1], tet[3], tet[2])
        for tri in map(frozenset, combinations(tet, 3)):
            candidates.setdefault(tri, []).append(tet)
    centre = x.mean(axis=0)
    open_faces = {}
    for tri in required:
        pts = [x[i] for i in tri]
        normal = np.cross(pts[1] - pts[0], pts[2] - pts[0])
        open_faces[tri] = normal if np.dot(centre - pts[0], normal) > 0 else -normal
    found = _search(x, candidates, required, open_faces, frozenset(), volume)
    return None if found is None else tuple(sorted(found))


def _diagonal_bits(kind: str, ids: np.ndarray) -> np.ndarray:
    """Per cell, bit k set when quad face k is cut along its (b, d) diagonal."""
    _, quads, _ = _REF[kind]
    bits = np.zeros(ids.shape[1], dtype=np.int64)
    for k, quad in enumerate(quads):
        which = np.argmin(ids[list(quad)], axis=0)  # local position of the smallest id
        bits |= (which % 2).astype(np.int64) << k
    return bits


def split_into_tets(
    kind: str, cells: np.ndarray, global_ids: np.ndarray | None = None
) -> np.ndarray:
    """Split cells into tetrahedra, consistently across shared faces.

    Parameters
    ----------
    kind : {"tetra", "wedge", "hexahedron"}
        Cell kind; corners in Abaqus/gmsh order (wedge: bottom 0-1-2, top 3-4-5;
        hexahedron: bottom 0-1-2-3, top 4-5-6-7).
    cells : numpy.ndarray
        Corner indices, shape ``(n_corners, n_cells)``.
    global_ids : numpy.ndarray, optional
        Global node numbers used by the diagonal rule, same shape as ``cells``
        (default: ``cells`` itself).

    Returns
    -------
    numpy.ndarray
        Tetrahedra as indices into the same numbering as ``cells``, shape
        ``(4, n_tets)``; orientation follows the reference cell (flip afterwards).

    Raises
    ------
    GeometryError
        If ``kind`` is unknown or ``cells`` has the wrong number of rows.
    """
    if kind not in _REF:
        raise GeometryError(f"Cannot split cell kind {kind!r}; supported: {', '.join(_REF)}.")
    cells = np.asarray(cells, dtype=np.int64)
    if cells.ndim != 2 or cells.shape[0] != CELL_KINDS[kind]:
        raise GeometryError(f"{kind} cells need {CELL_KINDS[kind]} corner rows, got {cells.shape}.")
    if kind == "tetra":
        return cells.copy()
    ids = cells if global_ids is None else np.asarray(global_ids)
    bits = _diagonal_bits(kind, ids)
    out = []
    for config in np.unique(bits):
        tets = _template(kind, int(config))
        if tets is None:  # pragma: no cover - impossible with the min-vertex rule
            raise GeometryError(f"No tetrahedral split of a {kind} for diagonal pattern {config}.")
        sel = cells[:, bits == config]
        out.extend(sel[list(tet)] for tet in tets)
    return np.hstack(out) if out else np.zeros((4, 0), dtype=np.int64)
