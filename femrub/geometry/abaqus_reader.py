"""Read an Abaqus/CalculiX solid mesh into a :class:`BladeMesh` of linear tetrahedra."""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import skfem

from .abaqus_parser import SOLID_TYPES, AbaqusModel, parse_abaqus
from .blade_mesh import BladeMesh
from .cell_split import split_into_tets
from .errors import GeometryError
from .tet_ops import compact_vertices, orient_positive
from .tip_detection import detect_tip
from .units import length_scale

__all__ = ["MATERIAL_SI", "MIDSIDE_EDGES", "deck_material", "edge_midpoints", "read_abaqus"]

#: Factors to SI of the material constants of a deck in a consistent unit system chosen by
#: its length unit: m -> N-m-kg-s, mm -> N-mm-t-s (MPa, t/mm^3, mJ/(t K) = 1e-6 J/(kg K),
#: mW/(mm K) = W/(m K)). A cm deck has no standard consistent system: its material is not read.
MATERIAL_SI = {
    "m": {
        "young": 1.0,
        "poisson": 1.0,
        "density": 1.0,
        "expansion": 1.0,
        "conductivity": 1.0,
        "specific_heat": 1.0,
    },
    "mm": {
        "young": 1e6,
        "poisson": 1.0,
        "density": 1e12,
        "expansion": 1.0,
        "conductivity": 1.0,
        "specific_heat": 1e-6,
    },
}

#: Corner pair (0-based) of every mid-side node, per element node count (Abaqus order).
MIDSIDE_EDGES = {
    10: [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)],
    15: [(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)],
    20: [
        (0, 1),
        (1, 2),
        (2, 3),
        (3, 0),
        (4, 5),
        (5, 6),
        (6, 7),
        (7, 4),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ],
}


def _lookup(model: AbaqusModel) -> np.ndarray:
    ids = model.node_ids
    if np.unique(ids).size != ids.size:
        raise GeometryError("Duplicate node numbers in *NODE data; renumber the source mesh.")
    table = -np.ones(int(ids.max()) + 1, dtype=np.int64)
    table[ids] = np.arange(ids.size)
    return table


def _columns(table: np.ndarray, ids, what: str) -> np.ndarray:
    ids = np.asarray(list(ids), dtype=np.int64)
    bad = (ids < 0) | (ids >= table.size)
    cols = np.where(bad, -1, table[np.clip(ids, 0, table.size - 1)])
    if (cols < 0).any():
        raise GeometryError(
            f"{what} refers to undefined node {int(ids[np.argmax(cols < 0)])}; check node numbers."
        )
    return cols


def _named_set(model: AbaqusModel, name: str, role: str) -> list[int]:
    members = model.find_set(model.nsets, name)
    if members is None:
        available = ", ".join(model.nsets) or "none"
        raise GeometryError(
            f"Node set {name!r} for {role} not found (available NSETs: {available});"
            f" fix the {role}= argument."
        )
    return list(dict.fromkeys(members))


def _midside_map(model: AbaqusModel, table: np.ndarray) -> dict[int, tuple[int, int]]:
    """Node column of every mid-side node -> node columns of its two corners."""
    out: dict[int, tuple[int, int]] = {}
    for block in model.blocks:
        n = block.nodes.shape[0]
        if n not in MIDSIDE_EDGES:
            continue
        n_corner = SOLID_TYPES[n][1]
        for k, (a, b) in enumerate(MIDSIDE_EDGES[n]):
            mids = table[block.nodes[n_corner + k]]
            pairs = np.stack([table[block.nodes[a]], table[block.nodes[b]]])
            for mid, pa, pb in zip(mids.tolist(), *pairs.tolist(), strict=True):
                out.setdefault(mid, (pa, pb))
    return out


def _contact_edges(model, table, old_to_new, contact_cols, vertex) -> np.ndarray:
    """Vertex pair of the tetrahedral edge carrying each mid-side contact node, else -1."""
    edge = -np.ones((2, vertex.size), dtype=np.int64)
    if (vertex < 0).any():
        mids = _midside_map(model, table)
        for k in np.flatnonzero(vertex < 0):
            pair = mids.get(int(contact_cols[k]))
            if pair is not None:
                edge[:, k] = old_to_new[list(pair)]
    return edge


def deck_material(model: AbaqusModel, length_unit: str, elset: str | None = None) -> dict:
    """Material of the deck's solid section in SI (keys of :data:`MATERIAL_SI`), or ``{}``.

    The section of ``elset`` if given, else the only ``*SOLID SECTION`` (or the only
    ``*MATERIAL``). Several materials without a way to choose, or a ``cm`` deck: ``{}``.
    """
    factors = MATERIAL_SI.get(str(length_unit).strip().lower())
    if factors is None or not model.materials:
        return {}
    name = None
    if elset is not None:
        name = next((m for e, m in model.sections.items() if e.upper() == elset.upper()), None)
    if name is None and len(set(model.sections.values())) == 1:
        name = next(iter(model.sections.values()))
    if name is None and len(model.materials) == 1:
        name = next(iter(model.materials))
    mat = next((v for k, v in model.materials.items() if k.upper() == str(name).upper()), None)
    if not mat:
        return {}
    return {k: v * factors[k] for k, v in mat.items()}


def _elset_members(model: AbaqusModel, elset: str | None):
    """Element numbers of ``elset`` (``None``: every element)."""
    if elset is None:
        return None
    members = model.find_set(model.elsets, elset)
    if members is None:
        available = ", ".join(model.elsets) or "none"
        raise GeometryError(
            f"Element set {elset!r} not found (available ELSETs: {available}); fix elset=."
        )
    return np.asarray(members, dtype=np.int64)


def _tetrahedra(model: AbaqusModel, table, keep) -> tuple[np.ndarray, dict]:
    """The (4, n) tetrahedra (columns of the node table) of the deck's solid elements
    (those of ``keep`` only, when given) and the element count per type."""
    tets, counts = [], {}
    for block in model.blocks:
        nodes = block.nodes if keep is None else block.nodes[:, np.isin(block.ids, keep)]
        kind, n_corner = SOLID_TYPES[block.nodes.shape[0]]
        corner_ids = nodes[:n_corner]
        cols = _columns(table, corner_ids.ravel(), f"*ELEMENT, TYPE={block.etype}").reshape(
            corner_ids.shape
        )
        tets.append(split_into_tets(kind, cols, global_ids=corner_ids))
        counts[block.etype] = counts.get(block.etype, 0) + nodes.shape[1]
    return np.hstack(tets), counts


def read_abaqus(
    path: str | Path,
    length_unit: str,
    *,
    radial_axis="z",
    root: str | None = None,
    tip: str | None = None,
    contact: str | Sequence[int] | None = None,
    elset: str | None = None,
) -> BladeMesh:
    """Read an Abaqus/CalculiX input deck as linear tetrahedra in metres.

    Quadratic elements keep only their corner nodes; wedges and hexahedra are
    split into tetrahedra with the global-node-number diagonal rule, which keeps
    the tetrahedral mesh conforming. Mid-side nodes stay addressable: set
    coordinates are kept in :attr:`BladeMesh.point_sets` and contact nodes may
    be mid-side nodes (``info["contact_map"]`` gives, for each contact node, its
    vertex index or the two vertices of the tetrahedral edge it sits on).

    Parameters
    ----------
    path : str or pathlib.Path
        Input deck (``*INCLUDE`` is followed).
    length_unit : str
        Length unit of the deck: ``"mm"`` (N-mm-t-s models such as Rotor 37), ``"m"``
        or ``"cm"``. Required because decks carry no unit information.
    radial_axis : str or array_like, optional
        Rotation axis of the machine.
    root : str, optional
        NSET of the clamped nodes; default: all nodes in ``*BOUNDARY`` lines.
    tip : str, optional
        NSET of the tip face; default: detected from boundary facets facing
        away from the axis (:func:`~femrub.geometry.tip_detection.detect_tip`).
    contact : str or sequence of int, optional
        NSET name or node numbers of the contact nodes (order kept); default: an
        NSET named ``contact`` if present, else none.
    elset : str, optional
        Only use elements of this ELSET.

    Returns
    -------
    BladeMesh
        Node sets ``root``, ``tip``, every NSET (restricted to vertices) and
        ``contact`` when all contact nodes are vertices; ``info["material"]``: the deck's
        ``*MATERIAL`` in SI (:func:`deck_material`); ``info["node_points"]``: every node
        number of the deck (``"ids"``) and its coordinates in metres (``"points"``, 3 × n),
        mid-side nodes included.

    Raises
    ------
    GeometryError
        Unreadable file, unsupported element, unknown unit, missing set or node.
    """
    start = time.perf_counter()
    scale = length_scale(length_unit)
    model = parse_abaqus(path)
    table = _lookup(model)
    points = model.coords * scale
    tets, counts = _tetrahedra(model, table, _elset_members(model, elset))
    p, t, old_to_new = compact_vertices(points, tets)
    t = orient_positive(p, t)

    root_ids = model.boundary if root is None else _named_set(model, root, "root")
    if not root_ids:
        raise GeometryError(f"No *BOUNDARY nodes in {str(path)!r} to clamp; pass root=NSET_NAME.")
    root_ids = list(dict.fromkeys(root_ids))
    point_sets, node_sets = {}, {}

    def add_set(name: str, ids) -> None:
        cols = _columns(table, ids, f"Node set {name!r}")
        point_sets[name] = points[:, cols]
        idx = old_to_new[cols]
        node_sets[name] = np.unique(idx[idx >= 0])

    for name, ids in model.nsets.items():
        add_set(name, list(dict.fromkeys(ids)))
    add_set("root", root_ids)
    if tip is None:
        node_sets["tip"] = detect_tip(p, t, radial_axis)
    else:
        add_set("tip", _named_set(model, tip, "tip"))

    if contact is None and model.find_set(model.nsets, "contact") is not None:
        contact = "contact"
    if contact is None:
        contact_ids = []
    elif isinstance(contact, str):
        contact_ids = _named_set(model, contact, "contact")
    else:
        contact_ids = [int(i) for i in contact]
    contact_cols = _columns(table, contact_ids, "contact")
    vertex = old_to_new[contact_cols]
    edge = _contact_edges(model, table, old_to_new, contact_cols, vertex)
    if (vertex >= 0).all():
        node_sets["contact"] = vertex
    contact_map = {
        "node_ids": np.asarray(contact_ids, dtype=np.int64),
        "vertex": vertex,
        "edge": edge,
    }

    mesh = skfem.MeshTet1(np.ascontiguousarray(p), np.ascontiguousarray(t))
    curved = None
    if any(b.nodes.shape[0] in MIDSIDE_EDGES for b in model.blocks):
        curved = edge_midpoints(model, table, old_to_new, points, p, mesh.edges)
    return BladeMesh(
        mesh=mesh,
        node_sets=node_sets,
        contact_points=points[:, contact_cols],
        radial_axis=radial_axis,
        source=f"{path} ({length_unit})",
        point_sets=point_sets,
        vertex_ids=model.node_ids[old_to_new >= 0],
        info={
            "element_counts": counts,
            "n_source_nodes": int(model.node_ids.size),
            "files": model.files,
            "contact_map": contact_map,
            "node_points": {"ids": model.node_ids, "points": points},
            "material": deck_material(model, length_unit, elset),
            "edge_midpoints": curved,
            "read_time_s": time.perf_counter() - start,
        },
    )


#: Quadrilateral faces (corner cycles, Abaqus order) of the quadratic solids.
_QUADS = {
    15: [(0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
    20: [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
}


def edge_midpoints(model: AbaqusModel, table, old_to_new, points, p, edges) -> np.ndarray:
    """Curved positions of the midpoints of the tetrahedral ``edges`` (quadratic geometry).

    An edge of a quadratic source element takes its mid-side node; a diagonal of a
    quadrilateral face (wedge or hexahedron split) takes the face centre of the 8-node
    serendipity face, ``−¼ Σ corners + ½ Σ mid-side nodes``; a hexahedron's interior
    diagonal its centre, ``−¼ Σ corners + ¼ Σ mid-side nodes``; every other edge (linear
    elements) its straight midpoint. ``edges`` (2, n_e) are vertex pairs of ``p`` as in
    ``skfem.MeshTet1.edges``.
    """
    nv = p.shape[1]
    lo, hi = np.minimum(*edges), np.maximum(*edges)
    keys = lo * nv + hi
    order = np.argsort(keys)
    mid = 0.5 * (p[:, edges[0]] + p[:, edges[1]])
    set_keys, set_pos = [], []

    def put(va, vb, pos):
        set_keys.append(np.minimum(va, vb) * nv + np.maximum(va, vb))
        set_pos.append(pos)

    for block in model.blocks:
        n = block.nodes.shape[0]
        if n not in MIDSIDE_EDGES:
            continue
        n_corner = SOLID_TYPES[n][1]
        corner = old_to_new[table[block.nodes[:n_corner]]]
        xc = points[:, table[block.nodes[:n_corner]]]  # (3, n_corner, n_el)
        xm = points[:, table[block.nodes[n_corner:]]]
        index = {frozenset(e): k for k, e in enumerate(MIDSIDE_EDGES[n])}
        for k, (a, b) in enumerate(MIDSIDE_EDGES[n]):
            put(corner[a], corner[b], xm[:, k])
        for quad in _QUADS.get(n, []):
            sides = [index[frozenset((quad[i], quad[(i + 1) % 4]))] for i in range(4)]
            centre = -0.25 * xc[:, list(quad)].sum(axis=1) + 0.5 * xm[:, sides].sum(axis=1)
            put(corner[quad[0]], corner[quad[2]], centre)
            put(corner[quad[1]], corner[quad[3]], centre)
        if n == 20:
            centre = -0.25 * xc.sum(axis=1) + 0.25 * xm.sum(axis=1)
            for a, b in ((0, 6), (1, 7), (2, 4), (3, 5)):
                put(corner[a], corner[b], centre)
    if set_keys:
        k = np.concatenate(set_keys)
        pos = np.hstack(set_pos)
        at = np.searchsorted(keys, k, sorter=order)
        at = np.clip(at, 0, keys.size - 1)
        found = keys[order[at]] == k
        mid[:, order[at[found]]] = pos[:, found]
    return mid
