"""The scene's probes (``outputs.probes``) on the built model: where each is, its row.

:func:`probe_points` turns each probe's ``node`` (the mesh's own node number) or ``point``
into coordinates right after the mesh is read, so an unknown node number is refused before
any assembly. :func:`probe_observations` then finds each probe's mesh node, its direction
and its observation row (:mod:`femrub.model.probes`) on the full model, named
``probe_<name>``; the reduction projects these rows like the model's other signals. On a
bladed disk (``rotor.sectors``) :func:`wheel_probes` finds the node on the sector's mesh
and the probe reads it on the blade ``blade`` (or on every blade), as an observation of the
wheel's coordinates (:mod:`femrub.model.wheel_probes`).

Node numbers: a CalculiX/Abaqus deck's node numbers (mid-side nodes included), a gmsh file's
node tags (corner nodes); a blade femrub builds (box, naca, sections) has the node tags of
its gmsh mesh (the vertex index + 1, the tags ``femrub mesh KIND -o blade.msh`` writes);
the paper's bar has none and its node number is the vertex index from 0 (vertex 0 is its
root, ``n_elements`` its tip); another file read through meshio: femrub's vertex index.
"""

from __future__ import annotations

import numpy as np

from ..model.probes import FIELDS, direction, mesh_nodes, node_rows, probe_rows
from ..model.wheel_probes import GLOBAL_AXES, WheelProbe
from ..output.results import PROBE_PREFIX
from ..scene.schema_run import PROBE_QUANTITIES, probe_names
from ..scene.spec import SceneError, fail
from ..scene.units import SI_LABEL

__all__ = ["probe_observations", "probe_points", "probe_unit", "wheel_probes"]
#: distance from a node number's own position to the model's node, relative to the mean edge
#: length, above which it is no node of the model (a node no element uses); a quadratic
#: deck's mid-side node is exact with P2 displacements and within this of the straight
#: edge's midpoint with P1
NODE_TOLERANCE = 0.1


def probe_unit(quantity: str) -> str:
    """SI unit of a probed quantity (``"m"``, ``"m/s"``, ``"K"``)."""
    return SI_LABEL[PROBE_QUANTITIES[quantity]]


def _node_point(blade, node: int, key: str) -> np.ndarray:
    """Coordinates (dim,) of the mesh's node number ``node`` (module docstring)."""
    table = blade.info.get("node_points")
    if table is not None:  # a deck: every node number, mid-side nodes included
        hit = np.flatnonzero(np.asarray(table["ids"]) == node)
        if hit.size:
            return np.asarray(table["points"])[:, hit[0]]
    elif blade.vertex_ids is not None:
        hit = np.flatnonzero(np.asarray(blade.vertex_ids) == node)
        if hit.size:
            return blade.mesh.p[:, hit[0]]
    elif node < blade.n_vertices:
        return blade.mesh.p[:, node]
    numbering = (
        "the mesh's node numbers"
        if table is not None or blade.vertex_ids is not None
        else f"the vertex indices 0..{blade.n_vertices - 1} (this mesh has no node numbers)"
    )
    fail(key, node, f"no such node in {blade.source}; use one of {numbering}, or give point")


def probe_points(scene, blade) -> list[np.ndarray]:
    """The position (dim,) of each probe of ``scene`` on ``blade`` (m).

    Raises
    ------
    SceneError
        A node number the mesh does not have, or a point of another dimension.
    """
    out = []
    for i, probe in enumerate(scene["outputs"]["probes"]):
        key = f"outputs.probes[{i}]"
        if "node" in probe:
            out.append(_node_point(blade, probe["node"], f"{key}.node"))
        else:
            x = np.asarray(probe["point"], dtype=float)[: blade.dim]
            if blade.dim == 1 and np.any(np.asarray(probe["point"][1:]) != 0.0):
                fail(f"{key}.point", probe["point"], "the 1D bar lies on x: give [x, 0, 0]")
            out.append(x)
    return out


def _site(probe, x, nodes, spacing, key) -> dict:
    """Where ``probe`` (at ``x``) reads: its node, the node's position, the distance."""
    node, distance = nodes.nearest(x)
    if "node" in probe and distance > NODE_TOLERANCE * spacing:
        fail(
            f"{key}.node",
            probe["node"],
            f"is {distance:.3g} m from every node of the model's mesh (a node no element "
            "uses?); give a node of an element",
        )
    return {"node": node, "position": nodes.points[:, node], "distance": distance}


def probe_observations(scene, built, points):
    """The probes' observation rows on ``built.model`` and what to report of them.

    Returns ``(observations, report, warnings)``: ``{"probe_<name>": (1, N) row}``, one dict
    per probe (name, quantity, component, unit, node or point asked, position of the node
    probed, its distance in m) and a warning per probe farther from its node than the mesh's
    mean edge length, or on clamped dofs (it reads 0).

    Raises
    ------
    SceneError
        A temperature probe on a model without temperature dofs.
    """
    if not scene["outputs"]["probes"]:
        return {}, [], []
    disc, mats, model = built.disc, built.mats, built.model
    nodes = mesh_nodes(disc)
    spacing = _mean_edge(disc)
    obs, report, warnings = {}, [], []
    for i, (probe, x) in enumerate(zip(scene["outputs"]["probes"], points, strict=True)):
        key, quantity = f"outputs.probes[{i}]", probe["quantity"]
        site = _site(probe, x, nodes, spacing, key)
        component = probe.get("component")
        d = (
            None
            if FIELDS[quantity] == "theta"
            else direction(disc.blade, site["position"], component)
        )
        try:
            row = probe_rows(model, disc, mats, nodes, site["node"], quantity, d)
        except ValueError as exc:
            raise SceneError(
                f"{key}.quantity = 'temperature': {exc} ({built.thermal[1]}); probe a "
                "displacement, or set physics.thermal = 'on'"
            ) from None
        obs[PROBE_PREFIX + probe["name"]] = row
        report.append(_entry(probe, x, site, d))
        warnings += _warnings(key, probe["name"], site, spacing, row.nnz == 0)
    return obs, report, warnings


def _entry(probe, x, site, d) -> dict:
    """What a probe reads and where (the build's report, ``--explain``)."""
    quantity = probe["quantity"]
    return {
        "name": probe["name"],
        "quantity": quantity,
        "component": probe.get("component"),
        "unit": probe_unit(quantity),
        **({"node": probe["node"]} if "node" in probe else {"point": list(map(float, x))}),
        "position": site["position"].tolist(),
        "distance": site["distance"],
        "direction": None if d is None else d.tolist(),
    }


def _warnings(key, name, site, spacing, clamped) -> list[str]:
    """A probe far from its node (a point in the wrong unit?) or on a clamped node."""
    out = []
    if site["distance"] > spacing:
        out.append(
            f"{key} ({name!r}): the nearest node is {site['distance']:.3g} m away, more "
            f"than the mesh's mean edge length {spacing:.3g} m; check the point's unit"
        )
    if clamped:
        out.append(f"{key} ({name!r}): the node is clamped, the probe reads 0")
    return out


def wheel_probes(scene, structure, points):
    """The probes of a bladed disk's scene on its sector (:mod:`femrub.model.wheel_probes`)
    and what to report of them.

    Parameters
    ----------
    scene : Scene
        Its ``outputs.probes`` (checked when loaded: a displacement or velocity, ``blade``
        below ``rotor.sectors``).
    structure : CyclicStructure
        The disk's sector (:mod:`femrub.model.cyclic`): its mesh is blade 0's, in the
        sector's axes.
    points : list of numpy.ndarray
        Each probe's position on the sector (:func:`probe_points`).

    Returns
    -------
    tuple
        ``(probes, report, warnings)``: a :class:`~femrub.model.wheel_probes.WheelProbe` per
        probe, one dict per probe as :func:`probe_observations` reports (its position on the
        sector, blade 0's) with its ``blade`` (an integer or ``"all"``) and the history
        ``keys`` it writes, and the warnings.
    """
    disc, n = structure.disc, structure.n_sectors
    nodes, spacing = mesh_nodes(disc), _mean_edge(disc)
    probes, report, warnings = [], [], []
    for i, (probe, x) in enumerate(zip(scene["outputs"]["probes"], points, strict=True)):
        key = f"outputs.probes[{i}]"
        site = _site(probe, x, nodes, spacing, key)
        component, blade = probe["component"], probe.get("blade", 0)
        d = direction(disc.blade, site["position"], component)
        rows = node_rows(structure.basis, nodes, site["node"], np.eye(3))[:, structure.free]
        keys = tuple(PROBE_PREFIX + name for name in probe_names(probe, n))
        blades = tuple(range(n)) if blade == "all" else (blade,)
        field = FIELDS[probe["quantity"]]
        probes.append(WheelProbe(keys, blades, field, rows, d, component in GLOBAL_AXES))
        report.append({**_entry(probe, x, site, d), "blade": blade, "keys": list(keys)})
        warnings += _warnings(key, probe["name"], site, spacing, rows.nnz == 0)
    return tuple(probes), report, warnings


def _mean_edge(disc) -> float:
    """Mean edge length of the mesh (m)."""
    p = disc.mesh.p
    if disc.dim == 1:
        return float(np.mean(np.diff(np.sort(p[0]))))
    e = disc.mesh.edges
    return float(np.mean(np.linalg.norm(p[:, e[0]] - p[:, e[1]], axis=0)))
