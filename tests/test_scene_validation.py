"""Every scene error is one line naming the key, the value and what is allowed."""

import copy
import math
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from femrub.app import build
from femrub.scene import SceneError, load_scene
from femrub.scene.scene import Scene, tomllib
from femrub.scene.validate import normalize

BASE = {
    "name": "base",
    "geometry": {"kind": "bar", "n_elements": 5},
    "contact": {"casing": {"kind": "concentric", "clearance": "15 um"}, "heat_coefficient": 3.0},
    "loads": {"rotation_speed": 200.0, "tip_force": {"law": "sin", "amplitude": 7.0}},
    "scheme": {"name": "theta", "h": 1e-4, "t_end": 2e-3},
}


def _doc(key, value):
    doc = copy.deepcopy(BASE)
    *path, last = key.split(".")
    node = doc
    for part in path:
        node = node.setdefault(part, {})
    if value is _DELETE:
        node.pop(last, None)
    else:
        node[last] = value
    return doc


_DELETE = object()

CASES = [  # (key, value, words that must be in the message)
    ("geometry.lenght", 0.3, ["unknown key geometry.lenght", "did you mean 'length'"]),
    ("geometri", {}, ["unknown key geometri", "'geometry'"]),
    ("scheme.h", "1 m", ["scheme.h = '1 m'", "not a unit of time", "ms"]),
    ("scheme.h", "fast", ["scheme.h = 'fast'", "number"]),
    ("scheme.h", 0.0, ["scheme.h = 0.0", "must be > 0"]),
    ("scheme.h", -1e-5, ["scheme.h = -1e-05", "> 0"]),
    ("scheme.h", math.nan, ["scheme.h", "finite"]),
    ("scheme.t_end", _DELETE, ["scheme.t_end is required"]),
    ("scheme.t_end", 1e-5, ["scheme.t_end = 1e-05", ">= scheme.h"]),
    ("scheme.name", "rk4", ["scheme.name = 'rk4'", "theta, carpenter, penalty"]),
    ("scheme.gamma", 0.2, ["scheme.gamma = 0.2", ">= 0.5"]),
    ("geometry.n_elements", 2.5, ["geometry.n_elements = 2.5", "integer"]),
    ("geometry.n_elements", True, ["geometry.n_elements = True", "integer"]),
    ("geometry.kind", "sphere", ["geometry.kind = 'sphere'", "bar, box, naca"]),
    ("contact.casing.clearance", -1e-6, ["contact.casing.clearance = -1e-06", ">= 0"]),
    ("contact.casing.clearance", "-2 um", ["contact.casing.clearance", ">= 0"]),
    ("contact.casing.kind", "lobed", ["contact.casing.kind = 'lobed'", "'concentric'"]),
    ("contact.restitution", 1.5, ["contact.restitution = 1.5", "<= 1"]),
    ("contact.friction", 0.2, ["contact.friction = 0.2", "heat_coefficient"]),
    ("contact.reach", "sometimes", ["contact.reach = 'sometimes'", "'auto'"]),
    ("physics.thermal", "maybe", ["physics.thermal = 'maybe'", "'auto', 'on', 'off'"]),
    ("physics.strain_heating", "yes", ["physics.strain_heating = 'yes'", "true or false"]),
    ("material.poisson", 0.7, ["material.poisson = 0.7", "< 0.5"]),
    ("material.young", "110 GPA", ["material.young", "unit 'GPA'", "GPa"]),
    ("outputs.vtk_stride", 10, ["outputs.vtk_stride = 10", "3D geometry"]),
    ("outputs.signals", ["tip_heat"], ["outputs.signals = 'tip_heat'", "tip_temperature"]),
    ("limits.tip_heat", 1.0, ["unknown key limits.tip_heat"]),
    ("limits.contact_temperature", 1.0, ["limits.contact_temperature", "no such signal"]),
    ("loads.rotation_speed", 0.0, ["loads.tip_force.frequency = 'rotation'", "vanish"]),
    ("loads.tip_force.law", "square", ["loads.tip_force.law = 'square'", "sin"]),
    ("loads.tip_force.amplitude", _DELETE, ["loads.tip_force.amplitude is required"]),
    ("reduction.method", "pod", ["reduction.method = 'pod'", "craig-bampton"]),
    ("reduction.n_uv", 4, ["unknown key reduction.n_uv", "reduction.method = 'none'"]),
    ("name", 3, ["name = 3", "string"]),
]


@pytest.mark.parametrize("key,value,words", CASES, ids=[c[0] for c in CASES])
def test_schema_errors(key, value, words):
    with pytest.raises(SceneError) as err:
        normalize(_doc(key, value))
    msg = str(err.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def _built_error(doc_changes: dict, base=None, tmp=None) -> str:
    doc = copy.deepcopy(base or BASE)
    for k, v in doc_changes.items():
        doc = _merge(doc, k, v)
    scene = Scene(normalize(doc), "test", tmp or Path.cwd())
    with pytest.raises(SceneError) as err:
        build(scene)
    msg = str(err.value)
    assert "\n" not in msg
    return msg


def _merge(doc, key, value):
    *path, last = key.split(".")
    node = doc
    for part in path:
        node = node.setdefault(part, {})
    node[last] = value
    return doc


MESH = {
    "name": "mesh",
    "geometry": {"kind": "mesh", "path": "box_blade.msh"},
    "scheme": {"h": 1e-6, "t_end": 1e-5},
}


@pytest.fixture()
def mesh_dir(tmp_path):
    import shutil

    root = Path(__file__).resolve().parents[1]
    shutil.copy(root / "meshes" / "box_blade.msh", tmp_path / "box_blade.msh")
    return tmp_path


def test_carpenter_step_above_stability_limit():
    msg = _built_error({"scheme.name": "carpenter", "scheme.h": 4e-5, "geometry.n_elements": 20})
    assert "scheme.h = 4e-05" in msg and "stability limit 2.6" in msg and "theta" in msg
    assert (
        build(
            Scene(
                normalize(
                    _merge(
                        _merge(copy.deepcopy(BASE), "scheme.name", "carpenter"), "scheme.h", 1e-6
                    )
                )
            )
        ).stepper.name
        == "carpenter"
    )


@pytest.mark.parametrize(
    "changes,words",
    [
        ({"contact.group": "nope"}, ["contact.group = 'nope'", "missing mesh group", "tip"]),
        ({"boundary.root": "nope"}, ["boundary.root = 'nope'", "missing mesh group"]),
        ({"geometry.path": "absent.msh"}, ["geometry.path = 'absent.msh'", "not found"]),
        ({"contact.nodes": [10**9]}, ["contact.nodes", "not a mesh vertex"]),
    ],
)
def test_build_errors_name_the_key(mesh_dir, changes, words):
    msg = _built_error(changes, MESH, mesh_dir)
    for w in words:
        assert w in msg, msg


def test_reduction_larger_than_the_model():
    msg = _built_error(
        {"reduction.method": "craig-bampton", "reduction.n_uv": 100, "reduction.n_theta": 0}
    )
    assert msg.startswith("reduction.n_uv: n_uv must be an integer in [0, 8]"), msg


def test_reduction_of_a_non_conducting_blade():
    msg = _built_error({"reduction.method": "auto", "material.conductivity": 0.0})
    assert msg.startswith("material.conductivity = 0.0: the thermal Craig-Bampton"), msg


def test_abaqus_deck_needs_a_length_unit(tmp_path):
    (tmp_path / "blade.inp").write_text("*HEADING\nblade\n")
    doc = {**MESH, "geometry": {"kind": "mesh", "path": "blade.inp"}}
    msg = _built_error({}, doc, tmp_path)
    assert "geometry.length_unit = None" in msg and "'mm'" in msg


def test_rotor37_without_reference_data(monkeypatch, tmp_path):
    monkeypatch.setenv("FEMRUB_SHARED_DATA", str(tmp_path / "absent"))
    with pytest.raises(SceneError) as err:
        build(load_scene("rotor37"))
    msg = str(err.value)
    assert msg.startswith("geometry.path = '{shared}/rotor37-fe-mesh/blade.inp'")
    assert "absent" in msg and "FEMRUB_SHARED_DATA" in msg and "\n" not in msg


def test_3d_only_and_bar_only_keys():
    doc = {"geometry": {"kind": "naca", "code": "12"}, "scheme": {"h": 1e-6, "t_end": 1e-5}}
    with pytest.raises(SceneError, match="geometry.code = '12': NACA code must be four digits"):
        normalize(doc)
    doc = {
        "geometry": {"kind": "box"},
        "contact": {"heat_coefficient": 1.0},
        "scheme": {"h": 1e-6, "t_end": 1e-5},
    }
    with pytest.raises(SceneError, match="contact.heat_coefficient = 1.0: 3D contacts"):
        normalize(doc)


# -- property tests --------------------------------------------------------------------


@st.composite
def valid_bar_docs(draw):
    scheme = draw(st.sampled_from(["theta", "carpenter"]))
    h = 1e-7 if scheme == "carpenter" else draw(st.sampled_from([1e-5, 1e-4]))
    # Carpenter on a reduced model may have a much smaller stability limit: full model only
    red = (
        "none"
        if scheme == "carpenter"
        else draw(st.sampled_from(["none", "craig-bampton", "auto"]))
    )
    reduction = {"method": red}
    if red == "craig-bampton":
        reduction.update(n_uv=draw(st.integers(0, 4)), n_theta=draw(st.integers(0, 3)))
    elif red == "auto":
        reduction.update(max_n_uv=4, max_n_theta=3, modes=draw(st.integers(1, 2)))
    return {
        "name": "random",
        "geometry": {
            "kind": "bar",
            "n_elements": draw(st.integers(5, 12)),
            "length": draw(st.floats(0.05, 1.0)),
            "total_mass": draw(st.sampled_from([0.1, "density"])),
        },
        "material": {
            "young": draw(st.floats(5e10, 2e11)),
            "conductivity": draw(st.floats(0.1, 20.0)),
        },
        "contact": {
            "casing": {"kind": "concentric", "clearance": draw(st.floats(0.0, 1e-4))},
            "heat_coefficient": draw(st.floats(0.0, 5.0)),
            "restitution": draw(st.floats(0.0, 1.0)) if scheme == "theta" else 0.0,
            "reach": draw(st.sampled_from(["auto", "all", 1e-5])),
        },
        "loads": {
            "rotation_speed": draw(st.floats(1.0, 3000.0)),
            "tip_force": {
                "law": draw(st.sampled_from(["sin", "constant", "ramp"])),
                "amplitude": draw(st.floats(0.0, 10.0)),
                "ramp_time": 0.01,
            },
        },
        "physics": {
            "thermal": draw(st.sampled_from(["auto", "on", "off", True, False])),
            "coupling": draw(st.sampled_from(["auto", "none", "paper", "physical"])),
            "strain_heating": draw(st.booleans()),
        },
        "scheme": {"name": scheme, "h": h, "t_end": 10 * h},
        "reduction": reduction,
    }


def _clean(doc):
    """Drop keys the chosen variants do not have (ramp_time outside 'ramp', ...)."""
    tf = doc["loads"]["tip_force"]
    if tf["law"] != "ramp":
        tf.pop("ramp_time")
    return doc


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(valid_bar_docs())
def test_random_valid_scenes_build_and_run(doc):
    scene = Scene(normalize(_clean(doc)))
    assert Scene(normalize(tomllib.loads(scene.dumps()))) == scene
    built = build(scene)
    res = built.stepper.run(scene["scheme.t_end"])
    assert res.status in ("ok", "inaccurate", "unstable"), res.message
    assert built.explain().count("\n") > 5


JUNK = st.one_of(
    st.text(max_size=8),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**12), 10**12),
    st.booleans(),
    st.lists(st.integers(-5, 5), max_size=4),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)
KEYS = st.sampled_from(
    [
        "name",
        "geometry.kind",
        "geometry.n_elements",
        "geometry.length",
        "geometry.total_mass",
        "material.young",
        "material.poisson",
        "material.conductivity",
        "contact.casing",
        "contact.casing.kind",
        "contact.casing.clearance",
        "contact.reach",
        "contact.restitution",
        "contact.heat_coefficient",
        "contact.group",
        "loads.rotation_speed",
        "loads.tip_force",
        "loads.tip_force.law",
        "loads.tip_force.frequency",
        "physics.thermal",
        "physics.rayleigh",
        "physics.coupling",
        "scheme.name",
        "scheme.h",
        "scheme.t_end",
        "reduction.method",
        "outputs.signals",
        "limits.tip_temperature",
        "geometry",
        "unknown.key",
        "scheme.extra",
    ]
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(KEYS, JUNK)
def test_random_invalid_scenes_fail_cleanly(key, value):
    doc = _merge(copy.deepcopy(BASE), key, value)
    try:
        scene = Scene(normalize(doc))
        built = build(scene)
    except SceneError as exc:
        msg = str(exc)
        assert msg and "\n" not in msg
        assert key.split(".")[0] in msg or "unknown key" in msg, msg
        return
    assert built.model.n_dofs > 0  # the junk happened to be a valid value


def test_cli_never_prints_a_traceback(tmp_path, capsys):
    from femrub.app.cli import main

    bad = tmp_path / "bad.toml"
    bad.write_text('[scheme]\nh = "1 m"\nt_end = 0.1\n')
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "scheme.h = '1 m'" in err and "Traceback" not in err
    bad.write_text("[scheme\n")
    assert main(["run", str(bad), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not valid TOML" in err
    assert main(["run", "no-such-scene", "-q"]) == 2
    assert "no such file and no built-in scene" in capsys.readouterr().err
    assert sys.exc_info() == (None, None, None)


ALL_KEYS = sorted({k for k, _, _ in __import__("femrub.scene", fromlist=["x"]).schema_rows()})
KINDS = st.sampled_from(["bar", "box", "naca", "sections", "mesh"])


@settings(max_examples=200, deadline=None)
@given(KINDS, st.sampled_from(ALL_KEYS), JUNK)
def test_any_key_any_junk_gives_a_scene_error_or_a_scene(kind, key, value):
    doc = {"geometry": {"kind": kind}, "scheme": {"h": 1e-6, "t_end": 1e-5}}
    if kind == "mesh":
        doc["geometry"]["path"] = "blade.msh"
    elif kind == "sections":
        doc["geometry"]["path"] = "sections"
    doc = _merge(doc, key, value)
    try:
        normalize(doc)
    except SceneError as exc:
        assert str(exc) and "\n" not in str(exc)
