"""Probes on the blades of a bladed disk (``outputs.probes`` with ``rotor.sectors``).

The 6-blade wheel of ``small_wheel.py`` against a rigid 3-lobed casing. A probe reads the
node of the sector's mesh on blade ``s``: the sector field of sector ``s`` at that node,
turned by ``R(s α)`` to global axes. The tests read the run's states through
``CyclicBasis.sector_field`` at the node's dofs (found by their position), independently of
the probe's rows, and check the cyclic symmetry of a tuned wheel under a load on one blade.
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
import tomli_w
from small_wheel import N, scene_tables

from femrub.app.cli import main
from femrub.app.probes import probe_points, wheel_probes
from femrub.app.scheme import bare_stepper
from femrub.app.sweep import _write_csv, point_metrics
from femrub.app.wheel import _bases, _model, wheel_parts
from femrub.geometry.cyclic_sector import axis_rotation
from femrub.model.cyclic import _dof_components
from femrub.scene import SceneError, loads_scene

ALPHA = 2.0 * math.pi / N
SPEED = 1000.0  # rad/s
REVOLUTION = 2.0 * math.pi / SPEED
TIP = [0.0, 0.0, 0.074]  # near the blade's tip (rim 45 mm, span 30 mm), on the +z axis
MID = [0.0, 0.002, 0.06]
PROBES = [
    {"name": "tip_y", "point": TIP, "component": "y", "blade": 2},
    {"name": "tip_z", "point": TIP, "component": "z", "blade": "all"},
    {"name": "tip_y_all", "point": TIP, "component": "y", "blade": "all"},
    {"name": "tip_r", "point": TIP, "component": "radial", "blade": "all"},
    {"name": "mid_c", "point": MID, "component": "circumferential", "blade": 4},
    {"name": "tip_v", "point": TIP, "quantity": "velocity", "component": "radial", "blade": 5},
    {"name": "tip_x", "point": TIP, "component": "x"},  # blade 0
]


def _data(probes=PROBES, sectors=N) -> dict:
    """The wheel's scene: rigid casing 20 um away, 3 lobes of 200 um, no prestress."""
    tables = scene_tables(families=3, contacts=2, damping_ratio=0.01)
    if sectors is None:
        del tables["rotor"]["sectors"]
    return {
        "name": "wheel6-probes",
        **tables,
        "casing": {"ring": {"clearance": 2e-5, "lobes": 3, "distortion": 2e-4}},
        "loads": {"rotation_speed": SPEED, "centrifugal": "off"},
        "scheme": {"h": REVOLUTION / 600, "t_end": REVOLUTION},
        "outputs": {"plots": False, "probes": probes},
    }


def _scene(probes=PROBES, sectors=N):
    return loads_scene(tomli_w.dumps(_data(probes, sectors)))


@pytest.fixture(scope="module")
def wheel():
    """The scene's parts, its run's model (rigid casing) and a run of one revolution with
    every state stored."""
    scene = _scene()
    parts = wheel_parts(scene)
    ((disk, _, _),) = _bases(parts, [(3, 0)])
    model, _ = _model(parts, disk, None)
    res = bare_stepper(scene, model).run(REVOLUTION, store_every=1)
    return scene, parts, disk, model, res


def _node_positions(parts, position) -> np.ndarray:
    """Positions in the sector's free dofs of the x, y, z displacement at ``position``."""
    structure = parts.disk
    basis = structure.basis
    at = np.flatnonzero(np.linalg.norm(basis.doflocs.T - position, axis=1) < 1e-12)
    comp = _dof_components(basis)[at]
    assert sorted(comp) == [0, 1, 2]
    dofs = at[np.argsort(comp)]
    where = np.searchsorted(structure.free, dofs)
    assert np.array_equal(structure.free[where], dofs), "the probed node is clamped"
    return where


def _blade_vector(disk, x, where, s) -> np.ndarray:
    """``(3, n)`` global displacement of blade ``s`` at the node (coordinates ``x`` ``(size, n)``):
    the sector field of sector ``s`` turned by ``R(s α)``."""
    return axis_rotation(s * ALPHA) @ disk.sector_field(x, s)[where]


def _entry(parts, name) -> dict:
    entries, _ = parts.probe_report
    return next(e for e in entries if e["name"] == name)


def _reading(parts, disk, states, name, s) -> np.ndarray:
    """The probe ``name`` on blade ``s`` from the states ``(n, 2 size)``, independently."""
    entry = _entry(parts, name)
    position = np.asarray(entry["position"])
    where = _node_positions(parts, position)
    half = states.shape[1] // 2
    x = states[:, half:] if entry["quantity"] == "velocity" else states[:, :half]
    vector = _blade_vector(disk, x.T, where, s)  # (3, n)
    component = entry["component"]
    if component in ("x", "y", "z"):
        return vector["xyz".index(component)]
    turned = axis_rotation(s * ALPHA) @ position
    radial = np.array([0.0, turned[1], turned[2]]) / math.hypot(turned[1], turned[2])
    axis = np.array([1.0, 0.0, 0.0])
    d = {"radial": radial, "axial": axis, "circumferential": np.cross(axis, radial)}[component]
    return d @ vector


def test_probe_histories_are_the_blades_sector_fields_at_the_node(wheel):
    _, parts, disk, model, res = wheel
    assert res.impulse.sum() > 0.0  # the blades touch the casing
    rows = np.searchsorted(res.t, res.state_times - 1e-12)
    np.testing.assert_allclose(res.t[rows], res.state_times, rtol=0, atol=1e-15)
    states = res.states
    reads = [("tip_y", 2, "probe_tip_y"), ("mid_c", 4, "probe_mid_c")]
    reads += [("tip_v", 5, "probe_tip_v"), ("tip_x", 0, "probe_tip_x")]
    reads += [(name, s, f"probe_{name}_blade{s}") for name in ("tip_z", "tip_r") for s in range(N)]
    for name, s, key in reads:
        expected = _reading(parts, disk, states, name, s)
        got = res.signals[key][rows, 0]
        scale = np.abs(expected).max()
        assert scale > 0.0, key
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-10 * scale, err_msg=key)
    assert model.info["signal_units"]["probe_tip_v"] == "m/s"
    assert model.info["signal_units"]["probe_tip_r_blade3"] == "m"


def test_the_same_node_on_one_blade_or_on_every_blade_reads_alike(wheel):
    _, _, _, _, res = wheel
    np.testing.assert_array_equal(res.probe("tip_y"), res.probe("tip_y_all_blade2"))
    assert "probe_tip_z" not in res.signals  # "all": one history per blade only


def test_a_load_on_one_blade_shows_on_its_probe_turned_with_the_blade(wheel):
    """Tuned wheel, a static tip load on blade ``b``: what blade ``s`` reads
    is what blade ``s − b`` reads under the load on blade 0 (the radial component as such,
    the global ``y`` turned by ``R(b α)``), and the loaded blade reads the most."""
    _, parts, disk, model, _ = wheel
    n = disk.size
    K = model.blocks.K.toarray()
    nc = parts.contacts.n
    # contact 0's normal and circumferential tangent: 1 N along each
    tip = parts.rows[[0, nc + 1]].sum(axis=0)
    loads = disk.sector_rows(tip)[:, 0, :]  # (N, size): the load on blade b
    x = np.linalg.solve(K, loads.T)  # (size, N): column b, the load on blade b

    def read(name):
        keys = [f"probe_{name}_blade{s}" for s in range(N)]
        return np.vstack([model.observations[k][:, :n].toarray() for k in keys]) @ x

    r, y, z = read("tip_r"), read("tip_y_all"), read("tip_z")  # (blade, loaded blade)
    assert np.abs(r).max() > 0.0
    for b in range(N):
        back = (np.arange(N) - b) % N
        np.testing.assert_allclose(r[:, b], r[back, 0], rtol=0, atol=1e-9 * np.abs(r).max())
        c, s = math.cos(b * ALPHA), math.sin(b * ALPHA)
        turned = c * y[back, 0] - s * z[back, 0]
        np.testing.assert_allclose(y[:, b], turned, rtol=0, atol=1e-9 * np.abs(y).max())
        assert np.argmax(np.abs(r[:, b])) == b


@pytest.mark.parametrize(
    ("probe", "says"),
    [
        ({"blade": 6}, "outputs.probes[0].blade = 6: the wheel has 6 blades (rotor.sectors = 6)"),
        ({"blade": -1}, "outputs.probes[0].blade = -1: must be >= 0"),
        ({"blade": 1.5}, "outputs.probes[0].blade = 1.5: must be an integer >= 0, or 'all'"),
        ({"blade": "every"}, "outputs.probes[0].blade = 'every': use one of 'all' or an integer"),
        (
            {"quantity": "temperature", "component": None},
            "outputs.probes[0].quantity = 'temperature': a bladed disk (rotor.sectors) probes "
            "displacements and velocities",
        ),
    ],
)
def test_bad_blade_values_are_refused_in_one_line_when_loaded(probe, says):
    table = {"name": "tip", "point": TIP, "component": "y", **probe}
    table = {k: v for k, v in table.items() if v is not None}
    with pytest.raises(SceneError) as err:
        _scene([table])
    assert str(err.value).startswith(says), str(err.value)
    assert "\n" not in str(err.value)


def test_a_blade_without_a_wheel_and_a_name_taken_twice_are_refused():
    with pytest.raises(SceneError, match=r"^outputs.probes\[0\].blade = 1: a single-blade scene"):
        _scene([{"name": "tip", "point": TIP, "component": "y", "blade": 1}], sectors=None)
    probes = [
        {"name": "tip", "point": TIP, "component": "y", "blade": "all"},
        {"name": "tip_blade3", "point": TIP, "component": "x"},
    ]
    with pytest.raises(SceneError, match=r"^outputs.probes\[1\].name = 'tip_blade3': .*probe_tip"):
        _scene(probes)


def test_run_writes_the_probes_of_every_blade(tmp_path):
    probes = [PROBES[0], PROBES[3]]
    path = tmp_path / "wheel6.toml"
    path.write_text(tomli_w.dumps(_data(probes)))
    out = tmp_path / "run"
    assert main(["run", str(path), "-o", str(out), "-q"]) in (0, 1)
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] in ("ok", "inaccurate"), s["message"]
    keys = ["probe_tip_y", *[f"probe_tip_r_blade{b}" for b in range(N)]]
    with np.load(out / "history.npz") as h:
        for key in keys:
            assert h[key].shape == (601, 1), key
            assert s["units"][key] == "m"
    assert np.abs(s["signals_max_abs"]["probe_tip_r_blade1"]) > 0.0
    explained = (out / "explain.txt").read_text()
    assert "probe_tip_y: y displacement (m) at point (0, 0, 0.074) m" in explained
    assert "read on blade 2 (the sector's node turned by 2 sectors)" in explained
    assert "read on every blade (probe_tip_r_blade0 .. probe_tip_r_blade5)" in explained
    with open(out / "history.csv") as fh:
        header = next(csv.reader(fh))
    assert "probe_tip_r_blade5 [m]" in header
    metrics = point_metrics(out)
    with np.load(out / "history.npz") as h:
        x = h["probe_tip_r_blade4"]
    assert metrics["probes"]["rms_probe_tip_r_blade4_m"] == pytest.approx(
        np.sqrt(np.mean(x**2)), rel=1e-12
    )
    row = {"point": 0, "params": {}, "x": SPEED, "skipped": False, "folder": str(out), **metrics}
    _write_csv([row], ["loads.rotation_speed"], tmp_path / "interaction.csv")
    with open(tmp_path / "interaction.csv") as fh:
        written = next(csv.DictReader(fh))
    assert float(written["max_probe_tip_y_m"]) == pytest.approx(
        metrics["probes"]["max_probe_tip_y_m"]
    )


def test_a_node_number_is_the_sector_meshs_node_tag(wheel):
    """``node`` names the sector mesh's gmsh node tag: the same rows as ``point`` there; an
    unknown number is refused by key (``wheel_parts`` asks right after meshing the sector,
    before assembling it)."""
    _, parts, _, _, _ = wheel
    mesh = parts.disk.sector.mesh
    tip = int(mesh.require("tip")[0])
    tag = int(mesh.vertex_ids[tip])
    position = mesh.mesh.p[:, tip].tolist()
    probes = [
        {"name": "by_node", "node": tag, "component": "z", "blade": "all"},
        {"name": "by_point", "point": position, "component": "z", "blade": "all"},
    ]
    scene = _scene(probes)
    at = probe_points(scene, mesh)
    (a, b), entries, _ = wheel_probes(scene, parts.disk, at)
    assert entries[0]["distance"] == 0.0 and entries[1]["distance"] < 1e-12
    assert (a.rows != b.rows).nnz == 0 and np.array_equal(a.direction, b.direction)
    bad = _scene([{"name": "far", "node": 10**7, "component": "x"}])
    with pytest.raises(SceneError, match=r"^outputs.probes\[0\].node = 10000000: no such node"):
        probe_points(bad, mesh)
