"""Probes (``outputs.probes``): the field at a node, in full and reduced runs, saved and swept."""

from __future__ import annotations

import csv
import json
import shutil
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from femrub.app.blade import load_blade
from femrub.app.run import run_scene
from femrub.app.simulation import build
from femrub.app.sweep import _write_csv, point_metrics
from femrub.contact.points import _component_of
from femrub.fem.discretisation import discretise
from femrub.output.results import Results
from femrub.scene import SceneError, loads_scene

sys.path.insert(0, str(Path(__file__).parent))
from bar_scenes import bar_scene  # noqa: E402
from probe_deck import CELLS, write_deck  # noqa: E402

NX, NY, NZ = CELLS

SCENE = """
name = "probe-beam"
[geometry]
kind = "mesh"
path = "blade.inp"
length_unit = "mm"
axis = "z"
[material]
young = "200 GPa"
density = 8000.0
[contact]
nodes = {tip}
casing = {{ kind = "concentric", clearance = "20 um" }}
[loads]
tip_force = {{ law = "sin", amplitude = 200.0, frequency = "3000 rad/s", direction = [0, 1, 0] }}
[physics]
thermal = "{thermal}"
[scheme]
h = 2e-5
t_end = 1e-3
[reduction]
{reduction}
[outputs]
vtk_stride = 10
probes = [
  {{ name = "tip_y", node = {corner}, component = "y" }},
  {{ name = "tip_c", node = {corner}, quantity = "velocity", component = "circumferential" }},
  {{ name = "mid_r", node = {mid}, component = "radial" }},
  {{ name = "near", point = ["160 mm", "10 mm", "4.1 mm"], component = "axial" }},
{extra}]
"""
FULL = 'method = "none"'
REDUCED = 'method = "craig-bampton"\nn_uv = 12\nn_theta = 0\nprojection = "second-order"'


@pytest.fixture(scope="module")
def deck(tmp_path_factory):
    return write_deck(tmp_path_factory.mktemp("probe_deck"))


def _scene(deck, reduction=FULL, thermal="off", extra="", corner=None):
    corners = deck["corner"]
    tip = [corners[NX, j, k] for j in range(NY + 1) for k in range(NZ + 1)]
    edge = tuple(sorted((corners[NX, 0, 1], corners[NX, 1, 1])))  # a mid-side node of the tip
    text = SCENE.format(
        tip=tip,
        corner=corners[NX, 0, 0] if corner is None else corner,
        mid=deck["mid"][edge],
        reduction=reduction,
        thermal=thermal,
        extra=extra,
    )
    return loads_scene(text, "beam.toml", deck["path"].parent)


@pytest.fixture(scope="module")
def runs(deck, tmp_path_factory):
    out = {}
    for label, reduction in (("full", FULL), ("reduced", REDUCED)):
        folder = tmp_path_factory.mktemp(label)
        scene = _scene(deck, reduction)
        if label == "reduced":  # its figures are not looked at (the full run's signals are)
            scene = scene.with_changes({"outputs.plots": False})
        res, built = run_scene(scene, folder)
        out[label] = (res, built, folder)
    return out


def _vtk_at(folder: Path, res, x) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``res`` at its VTK frames and the displacement (frames, 3) at the vertex ``x``."""
    frames = sorted((folder / "vtk").glob("*.vtu"))
    meshes = [meshio.read(f) for f in frames]
    i = int(np.argmin(np.linalg.norm(meshes[0].points - x, axis=1)))
    assert np.linalg.norm(meshes[0].points[i] - x) < 1e-9
    stride = 10
    rows = np.arange(len(frames)) * stride
    return rows, np.array([m.point_data["displacement"][i] for m in meshes])


@pytest.mark.parametrize("label", ["full", "reduced"])
def test_a_node_probe_is_the_vtk_field_at_that_node(runs, deck, label):
    res, built, folder = runs[label]
    x = np.array(deck["xyz"][deck["corner"][NX, 0, 0]]) * 1e-3
    rows, u = _vtk_at(folder, res, x)
    assert rows[-1] < res.t.size
    probe = res.probe("tip_y")[rows]
    scale = np.abs(u[:, 1]).max()
    assert scale > 1e-7  # the tip moves
    np.testing.assert_allclose(probe, u[:, 1], atol=1e-5 * scale)
    if label == "reduced":
        assert built.model.n_dofs < built.full.n_dofs  # the reduced run recorded it
        assert built.model.observations["probe_tip_y"].shape == (1, built.model.n_dofs)


def test_reduced_and_full_probes_agree(runs):
    """The reduced model's probe is the same quantity (its bending response, within the
    reduction's error)."""
    a, b = runs["full"][0].probe("tip_y"), runs["reduced"][0].probe("tip_y")
    assert np.abs(a - b).max() < 0.05 * np.abs(a).max()


def test_probe_rows_read_an_affine_field_exactly(deck):
    """On an affine displacement u = A x (and temperature θ = c·x), which P2 (P1)
    reproduces, each probe reads dᵀ A x_node: the node, its component and direction."""
    node = deck["mid"][tuple(sorted((deck["corner"][NX, 0, 1], deck["corner"][NX, 1, 1])))]
    extra = f'  {{ name = "temp", node = {node}, quantity = "temperature" }},\n'
    scene = _scene(deck, thermal="on", extra=extra)
    built = build(scene, stepper=False)
    model = built.model
    disc = discretise(load_blade(scene, None), 2)  # the same mesh's bases (not kept by a build)
    A = np.array([[1.0, 2.0, -0.5], [0.3, -1.0, 4.0], [2.5, 0.7, 1.5]])
    c = np.array([3.0, -2.0, 5.0])
    bu = disc.basis_u
    comp = _component_of(bu)
    u_all = (A @ bu.doflocs)[comp, np.arange(bu.N)]
    theta_all = c @ disc.basis_t.doflocs
    X = model.to_full.T @ np.concatenate([u_all, 2.0 * u_all, theta_all])  # the free dofs
    axis = np.array([0.0, 0.0, 1.0])
    for entry in built.report["probes"]:
        x = np.array(entry["position"])
        value = float((model.observations["probe_" + entry["name"]] @ X)[0])
        if entry["quantity"] == "temperature":
            assert value == pytest.approx(c @ x, rel=1e-12)
            continue
        r = np.array([x[0], x[1], 0.0]) / np.hypot(x[0], x[1])
        d = {"y": np.eye(3)[1], "radial": r, "axial": axis, "circumferential": np.cross(axis, r)}
        factor = 2.0 if entry["quantity"] == "velocity" else 1.0
        expected = factor * d[entry["component"]] @ (A @ x)
        assert value == pytest.approx(expected, rel=1e-12), entry["name"]
    mid = next(e for e in built.report["probes"] if e["name"] == "mid_r")
    np.testing.assert_allclose(mid["position"], np.array(deck["xyz"][node]) * 1e-3, atol=1e-12)
    near = next(e for e in built.report["probes"] if e["name"] == "near")
    assert near["distance"] == pytest.approx(1e-4, rel=1e-9)


def test_history_files_carry_the_probes_in_si(runs):
    res, built, folder = runs["full"]
    with np.load(folder / "history.npz") as h:
        assert {"probe_tip_y", "probe_tip_c", "probe_mid_r", "probe_near"} <= set(h.files)
        assert not any(k.startswith("signal_probe") for k in h.files)
        np.testing.assert_array_equal(h["probe_tip_y"][:, 0], res.probe("tip_y"))
        units = json.loads(str(h["meta"]))["units"]
    assert units["probe_tip_y"] == "m" and units["probe_tip_c"] == "m/s"
    header = (folder / "history.csv").read_text().splitlines()[0].split(",")
    assert "probe_tip_y [m]" in header and "probe_tip_c [m/s]" in header
    with open(folder / "history.csv") as fh:
        rows = list(csv.DictReader(fh))
    column = np.array([float(r["probe_tip_y [m]"]) for r in rows])
    np.testing.assert_allclose(column, res.probe("tip_y"), rtol=1e-12)
    again = Results.load_npz(folder / "history.npz")
    np.testing.assert_array_equal(again.probe("mid_r"), res.probe("mid_r"))
    with pytest.raises(KeyError, match="probes of this run: tip_y"):
        again.probe("nope")
    assert (folder / "signals.png").stat().st_size > 0
    explained = (folder / "explain.txt").read_text()
    assert "probe_tip_y: y displacement (m) at node" in explained
    assert "probe_near: axial displacement (m) at point (0.16, 0.01, 0.0041) m" in explained
    assert "0.0001 m away" in explained


def test_signal_returns_every_component(runs):
    res = runs["full"][0]
    contact = res.signal("contact_displacement")
    assert contact.shape == (res.t.size, 6)
    np.testing.assert_array_equal(res.signal("contact_displacement", 3), contact[:, 3])
    assert res.signal("tip_displacement").shape == (res.t.size,)
    with pytest.raises(IndexError, match="6 components"):
        res.signal("contact_displacement", 6)


def test_interaction_csv_has_probe_columns(runs, tmp_path):
    res, _, folder = runs["full"]
    metrics = point_metrics(folder)
    probes = metrics["probes"]
    x = res.probe("tip_y")
    assert probes["rms_probe_tip_y_m"] == pytest.approx(np.sqrt(np.mean(x**2)), rel=1e-12)
    assert probes["max_probe_tip_y_m"] == pytest.approx(np.abs(x).max(), rel=1e-12)
    assert "max_probe_tip_c_m_s" in probes
    # a folder written before the summary held the measures: read from its history.npz
    older = tmp_path / "older"
    older.mkdir()
    summary = json.loads((folder / "summary.json").read_text())
    del summary["signals_rms"]
    (older / "summary.json").write_text(json.dumps(summary))
    shutil.copy(folder / "history.npz", older / "history.npz")
    assert point_metrics(older)["probes"] == probes
    assert point_metrics(older)["rms_tip_displacement"] == metrics["rms_tip_displacement"]
    row = {"point": 0, "params": {}, "x": 1.0, "skipped": False, "folder": str(folder), **metrics}
    _write_csv([row], ["loads.rotation_speed"], tmp_path / "interaction.csv")
    with open(tmp_path / "interaction.csv") as fh:
        written = next(csv.DictReader(fh))
    assert float(written["rms_probe_tip_y_m"]) == pytest.approx(probes["rms_probe_tip_y_m"])


def test_bar_probe_at_the_tip_is_the_tip_displacement(tmp_path):
    text = bar_scene(t_end=0.005).replace(
        "[loads]", '[outputs]\nprobes = [{ name = "tip", node = 5, component = "x" }]\n[loads]'
    )
    res, _ = run_scene(loads_scene(text), tmp_path / "bar")
    np.testing.assert_allclose(res.probe("tip"), res.signal("tip_displacement"), rtol=1e-12)


@pytest.mark.parametrize(
    ("probe", "words"),
    [
        ('{ name = "a", node = 5 }', ["outputs.probes[0].component is required"]),
        ('{ name = "a", node = 5, point = [0, 0, 0], component = "x" }', ["point", "node"]),
        ('{ name = "a", component = "x" }', ["outputs.probes[0]", "node", "point"]),
        ('{ name = "a", node = 5, component = "up" }', ["component", "'up'", "radial"]),
        ('{ name = "a", node = 5, quantity = "strain", component = "x" }', ["quantity"]),
        ('{ name = "a b", node = 5, component = "x" }', ["name", "'a b'", "letters"]),
        ('{ name = "a", node = 5, component = "y" }', ["1D bar", "'x'"]),
        ('{ name = "a", node = 5, quantity = "temperature", component = "x" }', ["no component"]),
        ('{ name = "a", node = 5, cmp = "x" }', ["unknown key outputs.probes[0].cmp"]),
        (
            '{ name = "a", node = 1, component = "x" }, { name = "a", node = 2, component = "x" }',
            ["outputs.probes[1].name", "another probe"],
        ),
    ],
)
def test_bad_probes_are_one_line_scene_errors(probe, words):
    text = bar_scene().replace("[loads]", f"[outputs]\nprobes = [{probe}]\n[loads]")
    with pytest.raises(SceneError) as err:
        loads_scene(text)
    message = str(err.value)
    assert "\n" not in message
    for word in words:
        assert word in message, message


def test_temperature_probe_without_temperature_dofs(deck):
    extra = '  { name = "t", node = 1, quantity = "temperature" },\n'
    with pytest.raises(SceneError, match=r"probes\[4\].quantity.*physics.thermal = 'off'"):
        _scene(deck, extra=extra)
    scene = _scene(deck, thermal="auto", extra=extra)  # no heat source: dofs dropped
    with pytest.raises(SceneError, match=r"outputs.probes\[4\].quantity = 'temperature'.*'on'"):
        build(scene, stepper=False)


def test_unknown_node_is_refused_before_the_assembly(deck):
    lines = []
    with pytest.raises(SceneError, match=r"outputs.probes\[0\].node = 99999: no such node"):
        build(_scene(deck, corner=99999), log=lines.append, stepper=False)
    assert not any("assembl" in line for line in lines), lines


@pytest.mark.parametrize("name", ["rotor37", "rotor37-thermal"])
def test_rotor37_scenes_probe_node_1353_along_y(name):
    """The published response: the y displacement of deck node 1353, found in the deck."""
    from femrub.app.blade import load_blade
    from femrub.app.probes import probe_points
    from femrub.geometry.rotor37 import shared_data_dir
    from femrub.scene import load_scene

    scene = load_scene(name)
    assert scene["outputs"]["probes"] == [
        {"name": "node1353_y", "node": 1353, "quantity": "displacement", "component": "y"}
    ]
    if not (shared_data_dir() / "rotor37-fe-mesh" / "blade.inp").is_file():
        pytest.skip("Rotor 37 deck not found (set FEMRUB_SHARED_DATA to the shared data folder)")
    (x,) = probe_points(scene, load_blade(scene))
    np.testing.assert_allclose(x * 1e3, [600.4710848100, -32.156503437, 73.046422877], rtol=1e-12)


def test_a_node_no_element_uses_is_refused(deck, tmp_path):
    text = deck["path"].read_text().replace("*NODE\n", "*NODE\n5000, 131, 3, 1\n", 1)
    (tmp_path / "blade.inp").write_text(text)
    scene = _scene({**deck, "path": tmp_path / "blade.inp"}, corner=5000)
    with pytest.raises(SceneError, match=r"probes\[0\].node = 5000: is .* from every node"):
        build(scene, stepper=False)


def test_a_point_far_from_every_node_is_probed_with_a_warning(deck):
    """Millimetres written as plain numbers (metres): the nearest node, and a warning."""
    extra = '  { name = "far", point = [160, 10, 4], component = "x" },\n'
    with pytest.warns(UserWarning, match=r"probes\[4\] \('far'\): the nearest node is .* check"):
        built = build(_scene(deck, extra=extra), stepper=False)
    far = built.report["probes"][4]
    assert far["distance"] > 100.0
    assert any("'far'" in w for w in built.report["warnings"])


def test_the_bar_numbers_its_vertices_from_the_root(tmp_path):
    text = bar_scene().replace(
        "[loads]", '[outputs]\nprobes = [{ name = "tip", node = 6, component = "x" }]\n[loads]'
    )
    with pytest.raises(SceneError, match=r"node = 6: no such node .* indices 0\.\.5"):
        build(loads_scene(text), stepper=False)
