"""Tests of the Abaqus/CalculiX and gmsh readers and of the wedge/hex split."""

from __future__ import annotations

import os
from itertools import product
from pathlib import Path

import gmsh
import numpy as np
import pytest

from femrub.geometry import GeometryError, read_abaqus, read_gmsh, read_mesh, read_rotor37_mesh
from femrub.geometry.abaqus_parser import parse_abaqus
from femrub.geometry.cell_split import split_into_tets
from femrub.geometry.rotor37 import ROTOR37_CONTACT_NODES
from femrub.geometry.tet_ops import outward_boundary_facets, tet_volumes

SHARED = Path(
    os.environ.get(
        "FEMRUB_SHARED_DATA", Path(__file__).resolve().parents[1].parent / "shared" / "data"
    )
)


def _one_line_error(excinfo, *words: str) -> None:
    message = str(excinfo.value)
    assert "\n" not in message
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"


def _boundary_is_closed_sphere(p: np.ndarray, t: np.ndarray) -> tuple[bool, int]:
    """Boundary triangles form a closed 2-manifold of Euler characteristic 2."""
    facets, _ = outward_boundary_facets(p, t)
    edges = np.sort(
        np.concatenate([facets[[0, 1]], facets[[1, 2]], facets[[2, 0]]], axis=1), axis=0
    )
    uniq, counts = np.unique(edges, axis=1, return_counts=True)
    euler = np.unique(facets).size - uniq.shape[1] + facets.shape[1]
    return bool(np.all(counts == 2) and euler == 2), facets.shape[1]


# ---------------------------------------------------------------- tiny hand-written deck
WEDGE_MID = [(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)]
TET_MID = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


@pytest.fixture(scope="module")
def tiny_deck(tmp_path_factory) -> dict:
    """Two C3D15 wedges sharing a quad face (square 10x10x10 mm) plus a C3D10 on top.

    Corner and mid-side nodes get scrambled numbers; the 9 bottom nodes are 101..109
    so that the clamped set can be written with GENERATE.
    """
    rng = np.random.default_rng(7)
    corners = {
        "a0": (0, 0, 0),
        "b0": (10, 0, 0),
        "c0": (10, 10, 0),
        "d0": (0, 10, 0),
        "a1": (0, 0, 10),
        "b1": (10, 0, 10),
        "c1": (10, 10, 10),
        "d1": (0, 10, 10),
        "apex": (10, 0, 20),
    }
    wedges = [("a0", "b0", "c0", "a1", "b1", "c1"), ("a0", "c0", "d0", "a1", "c1", "d1")]
    tet = ("a1", "b1", "c1", "apex")
    edges = sorted(
        {tuple(sorted((w[i], w[j]))) for w in wedges for i, j in WEDGE_MID}
        | {tuple(sorted((tet[i], tet[j]))) for i, j in TET_MID}
    )
    bottom = [k for k in corners if k.endswith("0")] + [
        e for e in edges if all(n.endswith("0") for n in e)
    ]
    assert len(bottom) == 9
    others = [k for k in corners if k not in bottom] + [e for e in edges if e not in bottom]
    ids = dict(zip(bottom, range(101, 110), strict=True))
    ids.update(zip(others, rng.permutation(np.arange(1, 60))[: len(others)].tolist(), strict=True))
    xyz = {k: np.array(v, float) for k, v in corners.items()}
    xyz.update({e: 0.5 * (xyz[e[0]] + xyz[e[1]]) for e in edges})

    def nid(a, b=None):
        return ids[a] if b is None else ids[tuple(sorted((a, b)))]

    folder = tmp_path_factory.mktemp("deck")
    (folder / "mesh").mkdir()
    lines = ["*NODE, NSET=NALL"] + [
        f"{ids[k]}, {x:.6f}, {y:.6f}, {z:.6f}" for k, (x, y, z) in xyz.items()
    ]
    lines.append("*ELEMENT, TYPE=C3D15, ELSET=WEDGES")
    for number, w in enumerate(wedges, start=1):
        conn = [nid(n) for n in w] + [nid(w[i], w[j]) for i, j in WEDGE_MID]
        lines += [", ".join(map(str, [number, *conn[:10]])) + ",", ", ".join(map(str, conn[10:]))]
    lines.append("*ELEMENT, TYPE=C3D10, ELSET=TOP")
    lines.append(
        ", ".join(map(str, [3] + [nid(n) for n in tet] + [nid(tet[i], tet[j]) for i, j in TET_MID]))
    )
    (folder / "mesh" / "tiny_mesh.inp").write_text("\n".join(lines) + "\n")
    main = [
        "*HEADING",
        "tiny test deck",
        "** a comment",
        "*INCLUDE, INPUT=mesh/tiny_mesh.inp",
        "*NSET, NSET=BOTTOM, GENERATE",
        "101, 109, 1",
        "*ELSET, ELSET=FIRST_TWO, GENERATE",
        "1, 2",
        f"*NSET, NSET=CAP\n{nid('a1')}, {nid('b1')}, {nid('c1')}, {nid('apex')}",
        f"*NSET, NSET=RIM\n{nid('apex', 'c1')}, {nid('apex')}",
        "*MATERIAL, NAME=STEEL",
        "*ELASTIC",
        "210000., 0.3",
        "*DENSITY",
        "7.85e-9",
        "*EXPANSION",
        "1.2e-5",
        "*CONDUCTIVITY",
        "50.",
        "*SPECIFIC HEAT",
        "4.6e8",
        "*SOLID SECTION, ELSET=WEDGES, MATERIAL=STEEL",
        "*BOUNDARY",
        "BOTTOM, 1, 3",
        "*STEP",
        "*STATIC",
        "*END STEP",
    ]
    (folder / "tiny.inp").write_text("\n".join(main) + "\n")
    return {"path": folder / "tiny.inp", "ids": ids, "xyz": xyz, "nid": nid}


def test_tiny_deck_volume_and_units(tiny_deck):
    expected_mm3 = 2 * 500.0 + 50.0 * 10.0 / 3.0
    for unit, scale in (("mm", 1e-3), ("cm", 1e-2), ("m", 1.0)):
        blade = read_abaqus(tiny_deck["path"], unit, radial_axis="z", tip="CAP")
        assert blade.volume() == pytest.approx(expected_mm3 * scale**3, rel=1e-12)
    assert blade.n_vertices == 9 and blade.n_tets == 2 * 3 + 1
    assert np.all(tet_volumes(blade.mesh.p, blade.mesh.t) > 0)
    closed, n_facets = _boundary_is_closed_sphere(blade.mesh.p, blade.mesh.t)
    assert closed and n_facets == 14  # conforming on the shared quad face


def test_tiny_deck_material_in_si(tiny_deck):
    # N-mm-t-s deck: MPa, t/mm^3, mJ/(t K), mW/(mm K) -> Pa, kg/m^3, J/(kg K), W/(m K)
    mat = read_abaqus(tiny_deck["path"], "mm", radial_axis="z", tip="CAP").info["material"]
    expected = {
        "young": 210e9,
        "poisson": 0.3,
        "density": 7850.0,
        "expansion": 1.2e-5,
        "conductivity": 50.0,
        "specific_heat": 460.0,
    }
    assert mat == pytest.approx(expected, rel=1e-12)
    assert read_abaqus(tiny_deck["path"], "cm", radial_axis="z", tip="CAP").info["material"] == {}


def test_scene_values_override_the_deck_material():
    from femrub.app.translate import material_of
    from femrub.scene import loads_scene

    deck = {"young": 210e9, "density": 7850.0, "conductivity": 50.0}
    base = 'name = "d"\n[geometry]\nkind = "box"\n[scheme]\nh = 1e-6\nt_end = 1e-3\n'
    text = base + '[material]\nyoung = "100 GPa"\n'
    notes = []
    mat = material_of(loads_scene(text), deck, notes)
    assert mat.young == 100e9 and mat.rho == 7850.0 and mat.conductivity == 50.0
    assert any("material.young" in n and "overrides" in n for n in notes)
    assert any("density" in n and "mesh file" in n for n in notes)
    scene = loads_scene(base)
    assert material_of(scene.with_changes({"material.density": 4000.0}), deck).rho == 4000.0


def test_tiny_deck_sets_contact_and_elset(tiny_deck):
    nid = tiny_deck["nid"]
    contact = [nid("apex"), nid("apex", "c1")]
    blade = read_abaqus(tiny_deck["path"], "mm", radial_axis="z", tip="CAP", contact=contact)
    p = blade.mesh.p
    np.testing.assert_allclose(p[2, blade.require("root")], 0.0)
    assert blade.require("root").size == 4  # corner nodes of the GENERATE'd BOTTOM set
    assert blade.point_sets["root"].shape == (3, 9)  # corners and mid-side nodes
    np.testing.assert_allclose(blade.point_sets["root"][2], 0.0)
    assert blade.require("tip").size == 4
    np.testing.assert_allclose(blade.contact_points[:, 0], [0.010, 0.0, 0.020])
    np.testing.assert_allclose(blade.contact_points[:, 1], [0.010, 0.005, 0.015])
    cmap = blade.info["contact_map"]
    assert cmap["vertex"][0] >= 0 and cmap["vertex"][1] == -1
    np.testing.assert_allclose(p[:, cmap["edge"][:, 1]].mean(axis=1), blade.contact_points[:, 1])
    assert "contact" not in blade.node_sets  # one contact node is mid-side
    assert set(blade.vertex_ids) == {
        tiny_deck["ids"][k] for k in tiny_deck["xyz"] if isinstance(k, str)
    }
    wedges_only = read_abaqus(
        tiny_deck["path"], "mm", radial_axis="z", tip="CAP", elset="FIRST_TWO"
    )
    assert wedges_only.volume() == pytest.approx(1000e-9, rel=1e-12)
    rim = read_abaqus(tiny_deck["path"], "mm", radial_axis="z", tip="CAP", contact="RIM")
    np.testing.assert_allclose(rim.contact_points, blade.contact_points[:, ::-1])


def test_read_mesh_dispatch_needs_unit_for_abaqus(tiny_deck):
    with pytest.raises(GeometryError) as excinfo:
        read_mesh(tiny_deck["path"])
    _one_line_error(excinfo, "length_unit", "mm")
    blade = read_mesh(tiny_deck["path"], "mm", radial_axis="z", tip="CAP")
    assert blade.n_tets == 7


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_abaqus_errors(tiny_deck, tmp_path):
    with pytest.raises(GeometryError) as excinfo:
        read_abaqus(tiny_deck["path"], "inch")
    _one_line_error(excinfo, "'inch'", "'mm'")
    with pytest.raises(GeometryError) as excinfo:
        read_abaqus(tiny_deck["path"], "mm", root="NOPE")
    _one_line_error(excinfo, "'NOPE'", "BOTTOM", "root=")
    with pytest.raises(GeometryError) as excinfo:
        read_abaqus(tiny_deck["path"], "mm", tip="CAP", contact=[99999])
    _one_line_error(excinfo, "99999")
    with pytest.raises(GeometryError) as excinfo:
        read_abaqus(tmp_path / "absent.inp", "mm")
    _one_line_error(excinfo, "absent.inp", "check the path")
    deck = _write(
        tmp_path,
        "shell.inp",
        "*NODE\n1,0,0,0\n2,1,0,0\n3,1,1,0\n4,0,1,0\n*ELEMENT, TYPE=S4R\n1,1,2,3,4\n",
    )
    with pytest.raises(GeometryError) as excinfo:
        read_abaqus(deck, "mm")
    _one_line_error(excinfo, "'S4R'", "C3D4", "C3D15")
    deck = _write(tmp_path, "inc.inp", "*INCLUDE, INPUT=nothere.msh\n")
    with pytest.raises(GeometryError) as excinfo:
        read_abaqus(deck, "mm")
    _one_line_error(excinfo, "nothere.msh")
    deck = _write(tmp_path, "short.inp", "*NODE\n1,0,0,0\n*ELEMENT, TYPE=C3D4\n1,1,2,3\n")
    with pytest.raises(GeometryError) as excinfo:
        read_abaqus(deck, "mm")
    _one_line_error(excinfo, "multiple of 5")
    deck = _write(
        tmp_path,
        "nobc.inp",
        "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n",
    )
    with pytest.raises(GeometryError) as excinfo:
        read_abaqus(deck, "mm")
    _one_line_error(excinfo, "*BOUNDARY", "root=")


# ---------------------------------------------------------------- hexahedra
def test_hex_grid_split_is_conforming(tmp_path):
    rng = np.random.default_rng(3)
    n = 4  # 3x3x3 cells
    grid = np.array(list(product(range(n), repeat=3)), dtype=float)[:, ::-1]  # x fastest
    grid[:, 2] += 10.0  # root at radius 10 from the rotation axis x
    interior = np.all((grid > 0) & (grid < n - 1), axis=1)
    grid[interior] += rng.uniform(-0.3, 0.3, size=(interior.sum(), 3))
    numbers = rng.permutation(np.arange(1, grid.shape[0] + 1) * 7)

    def node(i, j, k):
        return numbers[i + n * j + n * n * k]

    lines = ["*NODE"] + [f"{numbers[q]}, {x}, {y}, {z}" for q, (x, y, z) in enumerate(grid)]
    lines.append("*ELEMENT, TYPE=C3D8R, ELSET=ALL")
    for e, (i, j, k) in enumerate(product(range(n - 1), repeat=3), start=1):
        corners = [
            (0, 0, 0),
            (1, 0, 0),
            (1, 1, 0),
            (0, 1, 0),
            (0, 0, 1),
            (1, 0, 1),
            (1, 1, 1),
            (0, 1, 1),
        ]
        conn = [node(i + a, j + b, k + c) for a, b, c in corners]
        lines.append(", ".join(map(str, [e, *conn])))
    bottom = [node(i, j, 0) for i in range(n) for j in range(n)]
    lines += ["*NSET, NSET=BASE", ", ".join(map(str, bottom))]
    deck = _write(tmp_path, "hex.inp", "\n".join(lines) + "\n")
    blade = read_abaqus(deck, "m", root="BASE", radial_axis="x")
    assert blade.n_tets == 27 * 6
    assert blade.volume() == pytest.approx(27.0, rel=1e-12)
    assert np.all(tet_volumes(blade.mesh.p, blade.mesh.t) > 0)
    closed, n_facets = _boundary_is_closed_sphere(blade.mesh.p, blade.mesh.t)
    assert closed and n_facets == 6 * 9 * 2
    np.testing.assert_allclose(blade.mesh.p[2, blade.require("root")], 10.0)
    np.testing.assert_allclose(blade.mesh.p[2, blade.require("tip")], 13.0)  # detected about x


def test_split_templates_fill_reference_cells():
    wedge = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]], float).T
    hexa = np.array(list(product((0, 1), repeat=3)), float)[:, ::-1][[0, 1, 3, 2, 4, 5, 7, 6]].T
    rng = np.random.default_rng(0)
    for p, kind, vol in ((wedge, "wedge", 0.5), (hexa, "hexahedron", 1.0)):
        for _ in range(50):
            ids = rng.permutation(p.shape[1])[:, None]
            t = split_into_tets(kind, np.arange(p.shape[1])[:, None], global_ids=ids)
            assert np.abs(tet_volumes(p, t)).sum() == pytest.approx(vol)
            assert np.all(np.abs(tet_volumes(p, t)) > 1e-12)


# ---------------------------------------------------------------- gmsh files
@pytest.fixture(scope="module")
def gmsh41_file(tmp_path_factory) -> Path:
    """Second-order MSH 4.1 box (1 x 2 x 3, z from 10 to 13) with groups blade/root/top."""
    path = tmp_path_factory.mktemp("gmsh") / "box41.msh"
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        vol = gmsh.model.occ.addBox(0, 0, 10, 1, 2, 3)
        gmsh.model.occ.synchronize()
        faces = {
            tuple(np.round(gmsh.model.occ.getCenterOfMass(2, s), 6)): s
            for _, s in gmsh.model.getEntities(2)
        }
        gmsh.model.addPhysicalGroup(3, [vol], name="blade")
        gmsh.model.addPhysicalGroup(2, [faces[(0.5, 1.0, 10.0)]], name="root")
        gmsh.model.addPhysicalGroup(2, [faces[(0.5, 1.0, 13.0)]], name="top")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.8)
        gmsh.option.setNumber("Mesh.ElementOrder", 2)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


def test_read_gmsh_41_second_order(gmsh41_file):
    blade = read_gmsh(gmsh41_file, "m", radial_axis="x", tip="top")
    assert blade.volume() == pytest.approx(6.0, rel=1e-12)
    np.testing.assert_allclose(blade.mesh.p[2, blade.require("root")], 10.0)
    np.testing.assert_allclose(blade.mesh.p[2, blade.require("tip")], 13.0)
    assert np.all(tet_volumes(blade.mesh.p, blade.mesh.t) > 0)
    assert blade.mesh.p.shape[1] == np.unique(blade.mesh.t).size  # no mid-side nodes left
    in_mm = read_mesh(gmsh41_file, "mm", radial_axis="x", tip=None)  # detect the tip
    assert in_mm.volume() == pytest.approx(6.0e-9, rel=1e-12)
    np.testing.assert_allclose(in_mm.mesh.p[2, in_mm.require("tip")], 13.0e-3)


def test_read_gmsh_missing_group(gmsh41_file):
    with pytest.raises(GeometryError) as excinfo:
        read_gmsh(gmsh41_file, "m", radial_axis="x")
    _one_line_error(excinfo, "'tip'", "available", "root", "top")


# ---------------------------------------------------------------- Rotor 37 CalculiX model
@pytest.fixture(scope="module")
def rotor37():
    if not (SHARED / "rotor37-fe-mesh" / "blade.inp").is_file():
        pytest.skip(
            f"Rotor 37 mesh not found under {SHARED}"
            " (set FEMRUB_SHARED_DATA to the shared data folder)"
        )
    return read_rotor37_mesh(SHARED)


def test_rotor37_sizes_and_sets(rotor37):
    assert rotor37.info["n_source_nodes"] == 20831
    assert rotor37.info["element_counts"] == {"C3D15": 6732}
    assert rotor37.n_tets == 3 * 6732
    r = rotor37.radius()
    assert r.min() == pytest.approx(0.4515, abs=1e-4)
    assert r.max() == pytest.approx(0.6409, abs=1e-4)
    assert rotor37.point_sets["root"].shape == (3, 465)  # *BOUNDARY nodes, corners and mid-side
    root = rotor37.require("root")
    assert r[root].max() < r.min() + 0.15 * (r.max() - r.min())
    assert rotor37.contact_points.shape == (3, 16)


def test_rotor37_contact_nodes_are_corner_nodes_on_tip(rotor37):
    cmap = rotor37.info["contact_map"]
    np.testing.assert_array_equal(cmap["node_ids"], ROTOR37_CONTACT_NODES)
    assert np.all(cmap["vertex"] >= 0)
    contact = rotor37.require("contact")
    np.testing.assert_array_equal(rotor37.vertex_ids[contact], ROTOR37_CONTACT_NODES)
    assert set(contact) <= set(rotor37.require("tip"))
    r_c = rotor37.radius(rotor37.contact_points)
    assert r_c.min() > 0.62


def test_rotor37_tets_valid_and_volume_stable(rotor37):
    vol = tet_volumes(rotor37.mesh.p, rotor37.mesh.t)
    assert np.all(vol > 0)
    assert rotor37.volume() == pytest.approx(1.32068e-4, rel=1e-5)
    closed, _ = _boundary_is_closed_sphere(rotor37.mesh.p, rotor37.mesh.t)
    assert closed
    # the opposite (max-number) diagonal rule changes the volume only at second order
    model = parse_abaqus(SHARED / "rotor37-fe-mesh" / "blade.inp")
    lookup = {int(n): k for k, n in enumerate(model.node_ids)}
    corners = model.blocks[0].nodes[:6]
    cols = np.vectorize(lookup.get)(corners)
    t = split_into_tets("wedge", cols, global_ids=-corners)
    other = np.abs(tet_volumes(model.coords * 1e-3, t)).sum()
    assert other == pytest.approx(rotor37.volume(), rel=1e-3)


def _edge_mid(blade, xa, xb):
    """Stored curved midpoint of the tetrahedral edge between the vertices at xa, xb."""
    p, e = blade.mesh.p, blade.mesh.edges
    va = int(np.argmin(np.linalg.norm(p - xa[:, None], axis=0)))
    vb = int(np.argmin(np.linalg.norm(p - xb[:, None], axis=0)))
    k = np.flatnonzero((np.minimum(*e) == min(va, vb)) & (np.maximum(*e) == max(va, vb)))
    assert k.size == 1
    return blade.info["edge_midpoints"][:, k[0]]


def test_quadratic_geometry_kept(tiny_deck, tmp_path):
    import skfem

    from femrub.fem.discretisation import discretise

    xyz, nid = tiny_deck["xyz"], tiny_deck["nid"]
    blade = read_abaqus(tiny_deck["path"], "m", radial_axis="z", tip="CAP")
    straight = 0.5 * (blade.mesh.p[:, blade.mesh.edges[0]] + blade.mesh.p[:, blade.mesh.edges[1]])
    assert np.allclose(blade.info["edge_midpoints"], straight, atol=1e-12)  # straight deck
    # bend: move the mid-side node of the wedge edge a0-b0 by d (the deck is in metres here)
    d = np.array([0.0, -1.0, 0.0])
    text = (tiny_deck["path"].parent / "mesh" / "tiny_mesh.inp").read_text()
    old = f"{nid('a0', 'b0')}, " + ", ".join(f"{v:.6f}" for v in xyz[("a0", "b0")])
    new_xyz = xyz[("a0", "b0")] + d
    assert old in text
    bent = tmp_path / "mesh"
    bent.mkdir()
    (bent / "tiny_mesh.inp").write_text(
        text.replace(old, f"{nid('a0', 'b0')}, " + ", ".join(f"{v:.6f}" for v in new_xyz))
    )
    deck = tmp_path / "tiny.inp"
    deck.write_text(tiny_deck["path"].read_text())
    blade = read_abaqus(deck, "m", radial_axis="z", tip="CAP")
    a0, b0, a1, b1 = (xyz[k] for k in ("a0", "b0", "a1", "b1"))
    assert np.allclose(_edge_mid(blade, a0, b0), new_xyz, atol=1e-9)
    # a diagonal of the quad face a0-b0-b1-a1: serendipity centre, moved by d / 2
    try:
        diag = _edge_mid(blade, a0, b1)
    except AssertionError:
        diag = _edge_mid(blade, b0, a1)
    assert np.allclose(diag, 0.25 * (a0 + b0 + a1 + b1) + 0.5 * d, atol=1e-9)
    # the P2 basis maps the curved cells: the face bulges out by d times the serendipity
    # shape function of that mid-side node, which adds |d| A / 3 (A: area of the face)
    disc = discretise(blade, 2, clamped=False)
    one = skfem.Functional(lambda w: 1.0 + 0.0 * w.x[0])
    vol = one.assemble(disc.basis_t)
    flat = one.assemble(skfem.Basis(blade.mesh, skfem.ElementTetP1()))
    area = np.linalg.norm(b0 - a0) * np.linalg.norm(a1 - a0)
    assert vol - flat == pytest.approx(np.linalg.norm(d) * area / 3.0, rel=1e-9)
    # linear displacement keeps straight cells
    assert one.assemble(discretise(blade, 1, clamped=False).basis_t) == pytest.approx(flat)
