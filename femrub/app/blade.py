"""The blade of a scene: the paper's bar, a gmsh parametric blade, sections or a mesh file.

:func:`load_blade` returns a :class:`~femrub.geometry.BladeMesh` whose ``root`` node set is
the clamped face (``boundary.root``) and whose contact points are the scene's candidates
(``contact.group`` or ``contact.nodes``). Missing groups, nodes or units are reported as a
one-line :class:`~femrub.scene.spec.SceneError` naming the scene key, and so are, before
any meshing, a gmsh blade whose estimated element count exceeds :data:`MAX_ELEMENTS`
(:func:`estimate_elements`), and after reading, a degenerate mesh (coincident nodes or
flat tetrahedra) and repeated contact points.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..geometry import GeometryError, box_blade, naca_blade, read_mesh, sections_blade
from ..geometry.bar import bar_mesh
from ..geometry.readers import detect_format
from ..geometry.tet_ops import tet_volumes
from ..scene.spec import SceneError, fail

__all__ = ["MAX_ELEMENTS", "estimate_elements", "load_blade"]

#: largest number of tetrahedra a gmsh blade may have (the model's size grows with it)
MAX_ELEMENTS = 2_000_000
# tetrahedra per h³ of volume in a gmsh mesh of size h (regular tetrahedra: 6 √2)
_TETS_PER_H3 = 8.5
# coincident nodes: closer than this fraction of the blade size
_SAME_POINT = 1e-9


def estimate_elements(g: dict) -> float | None:
    """Tetrahedra of a gmsh blade of size ``geometry.h`` (``None``: cannot estimate)."""
    h = g.get("h")
    if g["kind"] == "box":
        h = h or g["thickness"]
        t = min(g["thickness"], h)  # at least one element through the thickness
        return _TETS_PER_H3 * g["span"] * g["chord"] * g["thickness"] / (h * h * t)
    if g["kind"] == "naca" and h is not None:
        ratio = int(str(g["code"])[2:]) / 100.0
        t = min(ratio * g["root_chord"], h)
        area = 0.685 * ratio * 0.5 * (g["root_chord"] ** 2 + g["tip_chord"] ** 2)
        return _TETS_PER_H3 * g["span"] * area / (h * h * t)
    return None


def _check_size(scene) -> None:
    g = scene["geometry"]
    n = estimate_elements(g)
    if n is not None and n > MAX_ELEMENTS:
        fail(
            "geometry.h",
            g.get("h"),
            f"gives about {n:.2g} tetrahedra (at most {MAX_ELEMENTS:.0e} before meshing); "
            "raise geometry.h",
        )


def _check_mesh(scene, blade) -> None:
    """Refuse coincident nodes and flat tetrahedra (a degenerate mesh)."""
    if blade.dim != 3:
        return
    p = blade.mesh.p
    size = float(np.ptp(p, axis=1).max()) or 1.0
    keys = np.round(p.T / (_SAME_POINT * size)).astype(np.int64)
    _, first, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
    if (counts > 1).any():
        i = first[np.argmax(counts > 1)]
        where = ", ".join(f"{x:.6g}" for x in p[:, i])
        raise SceneError(
            f"geometry: degenerate mesh {blade.source}: {int((counts - 1).sum())} duplicate "
            f"node(s), e.g. at ({where}) m; merge coincident nodes"
        )
    vol = np.abs(tet_volumes(p, blade.mesh.t))
    flat = vol <= 1e-12 * size**3
    if flat.any():
        raise SceneError(
            f"geometry: degenerate mesh {blade.source}: {int(flat.sum())} flat tetrahedra "
            f"(zero volume), e.g. element {int(np.argmax(flat))}; repair the mesh"
        )


def _check_contacts(scene, pts) -> None:
    """Refuse repeated contact nodes or points (the same contact counted twice)."""
    contact = scene["contact"]
    nodes = contact.get("nodes")
    key = "contact.nodes" if nodes is not None else "contact.group"
    if nodes is not None and len(set(nodes)) < len(nodes):
        dup = next(n for n in nodes if nodes.count(n) > 1)
        fail(key, nodes, f"node {dup} is listed twice; list each contact node once")
    if pts.shape[1] > 1:
        size = float(np.ptp(pts, axis=1).max()) or 1.0
        keys = np.round(pts.T / (_SAME_POINT * max(size, 1e-3))).astype(np.int64)
        if len(np.unique(keys, axis=0)) < pts.shape[1]:
            fail(
                key,
                nodes if nodes is not None else contact["group"],
                "two contact points coincide; give each contact point once",
            )


#: largest blade taken (m): a bigger one is a millimetre mesh read as metres
MAX_BLADE_SIZE = 5.0
#: largest offset of a mid-side node from its edge's middle, in edge lengths (beyond a
#: quarter the quadratic element's Jacobian changes sign)
MAX_MIDSIDE_OFFSET = 0.25


def _check_scale(scene, blade) -> None:
    """Refuse a blade larger than :data:`MAX_BLADE_SIZE` (a unit slip)."""
    if scene["geometry"]["kind"] != "mesh":
        return
    size = float(np.ptp(blade.mesh.p, axis=1).max())
    if size > MAX_BLADE_SIZE:
        unit = scene["geometry"].get("length_unit") or "m"
        fail(
            "geometry.length_unit",
            unit,
            f"the blade spans {size:.4g} m (more than {MAX_BLADE_SIZE:g} m): a millimetre "
            f"mesh declared in {unit}? give length_unit = 'mm' if its numbers are millimetres",
        )


def _check_midside(scene, blade) -> None:
    """Refuse mid-side nodes more than :data:`MAX_MIDSIDE_OFFSET` edge lengths off their
    edge's middle (a distorted quadratic element)."""
    mid = blade.info.get("edge_midpoints")
    if mid is None:
        return
    p, edges = blade.mesh.p, blade.mesh.edges
    length = np.linalg.norm(p[:, edges[1]] - p[:, edges[0]], axis=0)
    off = np.linalg.norm(mid - 0.5 * (p[:, edges[0]] + p[:, edges[1]]), axis=0)
    ratio = off / np.where(length > 0, length, np.inf)
    worst = int(np.argmax(ratio))
    if ratio[worst] > MAX_MIDSIDE_OFFSET:
        where = ", ".join(f"{x:.6g}" for x in mid[:, worst])
        fail(
            "geometry.path",
            scene["geometry"]["path"],
            f"{int((ratio > MAX_MIDSIDE_OFFSET).sum())} distorted mid-side node(s), e.g. at "
            f"({where}) m, {ratio[worst]:.2f} edge lengths off the edge's middle (at most "
            f"{MAX_MIDSIDE_OFFSET:g}); repair the mesh",
        )


def _check_material(scene, blade) -> None:
    """Refuse a deck without a material when the scene gives none (no silent titanium)."""
    g = scene["geometry"]
    if g["kind"] != "mesh" or "material" not in blade.info or blade.info["material"]:
        return
    if any(k.startswith("material.") for k in scene.given):
        return
    fail(
        "material",
        None,
        f"{g['path']} has no *MATERIAL for its elements and the scene gives no [material]; "
        "give material.young, .poisson, .density, ... in the scene (or a *MATERIAL in the deck)",
    )


def _check_clamped_contacts(scene, blade, pts) -> None:
    """Refuse a contact point on a clamped node (its force would always be 0)."""
    root = blade.node_sets.get("root")
    if root is None or root.size == 0 or pts.shape[1] == 0:
        return
    size = float(np.ptp(blade.mesh.p, axis=1).max()) or 1.0
    scale = _SAME_POINT * size * 1e3
    clamped = {tuple(k) for k in np.round(blade.mesh.p[:, root].T / scale).astype(np.int64)}
    keys = np.round(pts.T / scale).astype(np.int64)
    hit = [i for i, k in enumerate(keys) if tuple(k) in clamped]
    if hit:
        contact = scene["contact"]
        key, value = (
            ("contact.nodes", contact["nodes"])
            if contact.get("nodes")
            else (
                "contact.group",
                contact["group"],
            )
        )
        where = ", ".join(f"{x:.6g}" for x in pts[:, hit[0]])
        fail(
            key,
            value,
            f"{len(hit)} contact point(s) on clamped nodes of boundary.root, e.g. at ({where}) m:"
            " a clamped node never moves and its contact force stays 0; choose free nodes",
        )


def _groups(blade) -> str:
    return ", ".join(f"{k} ({v.size} nodes)" for k, v in sorted(blade.node_sets.items())) or "none"


def _build(scene):
    g = scene["geometry"]
    kind = g["kind"]
    size = {k: g[k] for k in ("h", "h_min") if g.get(k) is not None}
    tips = {"n_contact": g.get("n_contact"), "contact_margin": g.get("contact_margin")}
    if kind == "bar":
        return bar_mesh(g["length"], g["n_elements"], g["grading"])
    if kind == "box":
        return box_blade(
            g["span"], g["chord"], g["thickness"], hub_radius=g["hub_radius"], **tips, **size
        )
    if kind == "naca":
        return naca_blade(
            g["code"],
            g["span"],
            g["root_chord"],
            g["tip_chord"],
            g["twist"],
            g["n_sections"],
            hub_radius=g["hub_radius"],
            stacking=g["stacking"],
            n_points=g["n_points"],
            **tips,
            **size,
        )
    if kind == "sections":
        paths = [scene.path(f) for f in g["files"]] if g.get("files") else scene.path(g["path"])
        return sections_blade(
            paths,
            length_unit=g["length_unit"],
            pattern=g["pattern"],
            radial_axis=g["axis"],
            interpolate=g["interpolate"],
            ruled=g["ruled"],
            **tips,
            **size,
        )
    return _read(scene)


def _read(scene):
    g, contact = scene["geometry"], scene["contact"]
    path = scene.path(g["path"])
    fmt = detect_format(path)
    kw = {}
    if g.get("axis") is not None:
        kw["radial_axis"] = g["axis"]
    root = scene["boundary"].get("root")
    if root is not None:
        kw["root"] = root
    if g.get("tip") is not None:
        kw["tip"] = None if g["tip"] == "detect" else g["tip"]
    if fmt == "abaqus":
        if g.get("length_unit") is None:
            fail(
                "geometry.length_unit",
                None,
                f"{path.name} is an Abaqus/CalculiX deck without "
                "unit information; give 'mm' (N-mm-t-s models), 'cm' or 'm'",
            )
        if contact.get("nodes") is not None:
            kw["contact"] = contact["nodes"]
    try:
        blade = read_mesh(path, g.get("length_unit"), **kw)
        blade.info["contact_from_nodes"] = "contact" in kw
    except GeometryError as exc:
        _reader_error(scene, exc)
    for key, name in (("boundary.root", root), ("geometry.tip", g.get("tip"))):
        if name not in (None, "detect", "root", "tip") and name not in blade.node_sets:
            fail(key, name, f"missing mesh group in {path.name}; groups: {_groups(blade)}")
    return blade


def _reader_error(scene, exc):
    """Re-raise a reader's :class:`GeometryError` under the scene key at fault."""
    g, contact = scene["geometry"], scene["contact"]
    root = scene["boundary"].get("root")
    msg = str(exc)
    if "Node set 'root'" in msg or (root is not None and repr(root) in msg):
        fail("boundary.root", root or "root", f"missing mesh group: {msg}")
    if "Node set 'tip'" in msg or "tip face" in msg:
        fail("geometry.tip", g.get("tip"), f"missing mesh group: {msg}")
    if "contact" in msg and contact.get("nodes") is not None:
        fail("contact.nodes", contact["nodes"], msg)
    raise SceneError(f"geometry.path = {g['path']!r}: {msg}") from None


def _contact_points(scene, blade) -> np.ndarray:
    contact = scene["contact"]
    nodes, group = contact.get("nodes"), contact["group"]
    if nodes is not None:
        if blade.info.get("contact_from_nodes"):
            return blade.contact_points
        ids = blade.vertex_ids
        if ids is None:
            fail("contact.nodes", nodes, f"{blade.source} has no node numbers; use contact.group")
        lookup = {int(v): i for i, v in enumerate(ids)}
        missing = [n for n in nodes if n not in lookup]
        if missing:
            fail("contact.nodes", nodes, f"node {missing[0]} is not a mesh vertex")
        return blade.mesh.p[:, [lookup[n] for n in nodes]]
    if group == "contact" and blade.contact_points.shape[1]:
        return blade.contact_points
    idx = blade.node_sets.get(group)
    if idx is None or idx.size == 0:
        fail(
            "contact.group",
            group,
            f"missing mesh group: no nodes in group {group!r} of "
            f"{blade.source}; groups: {_groups(blade)}",
        )
    return blade.mesh.p[:, idx]


def load_blade(scene, log=None):
    """Mesh or read the scene's blade; return it with the candidate contact points set.

    Parameters
    ----------
    scene : :class:`~femrub.scene.scene.Scene`.
    log : optional callable for progress messages.

    Returns
    -------
    BladeMesh
    """
    if log:
        log(f"geometry: {scene['geometry']['kind']} ...")
    _check_size(scene)
    try:
        blade = _build(scene)
    except GeometryError as exc:
        raise SceneError(f"geometry ({scene['geometry']['kind']}): {exc}") from None
    _check_mesh(scene, blade)
    _check_scale(scene, blade)
    _check_midside(scene, blade)
    _check_material(scene, blade)
    root = scene["boundary"].get("root")
    if root is not None and scene["geometry"]["kind"] != "mesh" and root != "root":
        if root not in blade.node_sets:
            fail("boundary.root", root, f"missing mesh group; groups: {_groups(blade)}")
        blade.node_sets["root"] = blade.node_sets[root]
    pts = _contact_points(scene, blade)
    _check_contacts(scene, pts)
    _check_clamped_contacts(scene, blade, pts)
    return replace(blade, contact_points=pts, node_sets=dict(blade.node_sets))
