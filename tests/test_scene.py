"""Scene files: load, dump, reload; units; dotted changes; built-in scenes."""

import pytest

from femrub.app import build
from femrub.scene import (
    SceneError,
    builtin_scenes,
    builtin_text,
    load_scene,
    loads_scene,
    parse_value,
    resolve_key,
)
from femrub.scene.units import to_si

TINY = """
name = "tiny"
description = "five-element bar"
[geometry]
kind = "bar"
n_elements = 5
[contact]
casing = { kind = "concentric", clearance = "15 um" }
heat_coefficient = 3.0
[loads]
rotation_speed = "2000 rpm"
tip_force = { law = "sin", amplitude = 7.0 }
[scheme]
h = 1e-4
t_end = 0.02
"""


@pytest.mark.parametrize("name", sorted(builtin_scenes()))
def test_builtin_round_trip(name):
    scene = load_scene(name)
    again = loads_scene(scene.dumps())
    assert again == scene
    assert loads_scene(again.dumps()).dumps() == scene.dumps()


def test_round_trip_keeps_every_key():
    scene = loads_scene(TINY)
    text = scene.dumps()
    assert "[contact.casing]" in text and "clearance = 1.5e-05" in text
    assert loads_scene(text) == scene
    assert scene["loads.rotation_speed"] == pytest.approx(2000 * 3.141592653589793 / 30)


def test_builtins_listed_and_shown():
    names = builtin_scenes()
    assert {"paper", "twisted-naca", "rotor37"} <= set(names)
    assert all(names.values())
    assert 'kind = "bar"' in builtin_text("paper")
    with pytest.raises(SceneError, match="no built-in scene 'nope'; built-ins: "):
        builtin_text("nope")


@pytest.mark.parametrize(
    "value,dim,si",
    [
        ("15 um", "length", 15e-6),
        ("2 mm", "length", 2e-3),
        (0.3, "length", 0.3),
        ("2000 rpm", "angular_speed", 209.43951023932),
        ("110 GPa", "pressure", 110e9),
        ("10 us", "time", 1e-5),
        ("0.5 rad", "angle", 28.6478897565412),
        (3, "force", 3.0),
    ],
)
def test_units(value, dim, si):
    assert to_si(value, dim) == pytest.approx(si)


def test_changes_and_keys():
    scene = loads_scene(TINY)
    changed = scene.with_changes({"rotation_speed": "1000 rpm", "scheme.h": 5e-5})
    assert changed["loads.rotation_speed"] == pytest.approx(104.71975511966)
    assert changed["scheme.h"] == 5e-5 and scene["scheme.h"] == 1e-4
    assert resolve_key("t_end") == "scheme.t_end"
    with pytest.raises(SceneError, match="ambiguous"):
        resolve_key("h")
    assert parse_value("1e-5") == 1e-5 and parse_value("lobed") == "lobed"
    assert parse_value("[1, 2]") == [1, 2] and parse_value("true") is True


def test_selector_change_drops_other_variant_keys():
    scene = load_scene("twisted-naca", {"reduction.method": "none"})
    concentric = scene.with_changes({"contact.casing.kind": "concentric"})
    assert concentric["contact.casing"] == {"kind": "concentric", "clearance": 2e-05}
    theta = scene.with_changes({"scheme.name": "carpenter"})
    assert "gamma" not in theta["scheme"]


def test_paper_scene_is_the_paper_case():
    import femrub as fr

    built = build(load_scene("paper"))
    ref = fr.bar_model(alpha=3.0)
    assert built.model.n_dofs == ref.n_dofs == 60
    assert abs(built.model.A - ref.A).max() == 0 and abs(built.model.B - ref.B).max() == 0
    assert built.model.contact.gap_at(0.0)[0] == pytest.approx(15e-6)
    t = 0.0123
    assert built.model.load(t) == pytest.approx(ref.load(t))


def test_docs_list_every_key():
    from pathlib import Path

    from femrub.scene import schema_rows

    text = (Path(__file__).resolve().parents[1] / "docs" / "scenes.md").read_text()
    missing = sorted({k for k, _, _ in schema_rows() if f"`{k}`" not in text})
    assert not missing, f"docs/scenes.md lacks {missing}"
