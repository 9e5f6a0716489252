"""Bad input refused before any work with one line naming the key, the value, the bound and
the fix."""

from __future__ import annotations

import re

import pytest

from femrub.app.cli import main
from femrub.app.sweep import parse_param
from femrub.scene import SceneError, load_scene


def test_a_unit_after_the_last_value_applies_to_every_value():
    key, values = parse_param("rotation_speed=1000,2000rpm")
    scenes = [load_scene("twisted-naca", {key: v}) for v in values]
    speeds = [s["loads.rotation_speed"] for s in scenes]
    assert speeds == pytest.approx([1000 * 0.10471975511965977, 2000 * 0.10471975511965977])
    with pytest.raises(SceneError, match="a unit on some values"):
        parse_param("rotation_speed=1000rpm,2000")


def test_a_key_swept_twice_is_refused(tmp_path, capsys):
    argv = ["sweep", "twisted-naca", "-o", str(tmp_path / "s"), "-q"]
    argv += ["--param", "friction=0.1,0.2", "--param", "contact.friction=0.3"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "contact.friction is given twice" in err and "A,B,C" in err
    assert not (tmp_path / "s" / "runs").exists()


def test_a_friction_coefficient_of_100_is_refused(tmp_path, capsys):
    assert main(["check", "twisted-naca", "--set", "contact.friction=100", "-q"]) == 2
    err = capsys.readouterr().err
    assert "contact.friction = 100" in err and "above 2" in err and "percentage" in err


def test_a_step_that_does_not_divide_t_end_is_refused_before_any_work(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["run", "twisted-naca", "-o", str(out), "-q"]
    assert main([*argv, "--set", "scheme.h=2e-6", "--set", "scheme.t_end=1.1e-5"]) == 2
    err = capsys.readouterr().err
    assert "scheme.t_end = 1.1e-05" in err and "5.5 steps" in err
    assert "scheme.t_end = 1.2e-05 s (6 steps)" in err and "scheme.h = 1.83333e-06 s" in err
    assert not out.exists()


def _deck_text(material=True, contact=None, scale=1.0, midside_push=0.0):
    """Two C3D10 tetrahedra (mm); ``midside_push``: mm moved off the middle of one edge."""
    from test_cache_keys import _deck

    folder = _deck_text.folder
    path = _deck(folder, nudge=(11, 2, midside_push) if midside_push else None)
    lines = path.read_text().splitlines()
    if scale != 1.0:
        out = []
        node = False
        for line in lines:
            if line.startswith("*"):
                node = line.startswith("*NODE")
            elif node:
                k, *xyz = line.split(",")
                line = ", ".join([k, *(f"{float(v) * scale:.9g}" for v in xyz)])
            out.append(line)
        lines = out
    if contact is not None:
        lines += ["*NSET, NSET=CONTACT", ", ".join(map(str, contact))]
    if material:
        lines += ["*MATERIAL, NAME=TI", "*ELASTIC", "110000., 0.3", "*DENSITY", "4.5e-9"]
        lines += ["*SOLID SECTION, ELSET=ALL, MATERIAL=TI"]
    path.write_text("\n".join(lines) + "\n")
    return path


def _check(tmp_path, unit="mm", extra="", **deck):
    _deck_text.folder = tmp_path
    _deck_text(**deck)
    scene = tmp_path / "s.toml"
    scene.write_text(
        f'[geometry]\nkind = "mesh"\npath = "blade.inp"\nlength_unit = "{unit}"\ntip = "TIP"\n'
        f'[contact]\ncasing = {{ kind = "concentric", clearance = "50 um" }}\n{extra}'
        "[scheme]\nh = 1e-6\nt_end = 1e-5\n"
    )
    return main(["check", str(scene), "-q"])


def test_a_deck_without_material_is_refused_unless_the_scene_gives_one(tmp_path, capsys):
    assert _check(tmp_path, material=False, contact=[5]) == 2
    err = capsys.readouterr().err
    assert "no *MATERIAL" in err and "material.young" in err
    given = '[material]\nyoung = "110 GPa"\ndensity = 4500\n'
    assert _check(tmp_path, material=False, contact=[5], extra=given) == 0


def test_a_contact_on_a_clamped_node_is_refused(tmp_path, capsys):
    assert _check(tmp_path, contact=[1]) == 2
    err = capsys.readouterr().err
    assert "contact.group" in err and "clamped" in err and "choose free nodes" in err
    assert _check(tmp_path, contact=[5]) == 0


def test_a_millimetre_mesh_declared_in_metres_is_named(tmp_path, capsys):
    assert _check(tmp_path, unit="m", contact=[5], scale=100.0) == 2
    err = capsys.readouterr().err
    assert "geometry.length_unit = 'm'" in err and "millimetre mesh declared in m" in err


def test_distorted_midside_nodes_are_refused(tmp_path, capsys):
    assert _check(tmp_path, contact=[5], midside_push=4.0) == 2
    err = capsys.readouterr().err
    assert "geometry.path" in err and "distorted mid-side node" in err and "repair" in err


def test_an_include_of_a_device_or_a_huge_file_is_refused(tmp_path, capsys, monkeypatch):
    from femrub.geometry import abaqus_parser

    deck = tmp_path / "blade.inp"
    deck.write_text("*HEADING\n*INCLUDE, INPUT=/dev/zero\n")
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[geometry]\nkind = "mesh"\npath = "blade.inp"\nlength_unit = "mm"\n'
        "[scheme]\nh = 1e-6\nt_end = 1e-5\n"
    )
    assert main(["check", str(scene), "-q"]) == 2
    assert "/dev/zero" in capsys.readouterr().err
    (tmp_path / "part.inp").write_text("*NODE\n" + "1, 0, 0, 0\n" * 100)
    deck.write_text("*HEADING\n*INCLUDE, INPUT=part.inp\n")
    monkeypatch.setattr(abaqus_parser, "MAX_DECK_BYTES", 1000)
    assert main(["check", str(scene), "-q"]) == 2
    assert "more than the" in capsys.readouterr().err


def test_femrub_mesh_estimates_elements_before_meshing(capsys, monkeypatch):
    import femrub.geometry

    for name in ("box_blade", "naca_blade"):
        monkeypatch.setattr(femrub.geometry, name, lambda *a, **k: pytest.fail("meshed"))
    assert main(["mesh", "box", "--h", "2e-5"]) == 2
    assert "tetrahedra" in capsys.readouterr().err
    assert main(["mesh", "naca", "--h", "1e-5"]) == 2
    assert "raise --h" in capsys.readouterr().err


def test_a_lofted_blade_estimates_elements_before_meshing(tmp_path, capsys, monkeypatch):
    import numpy as np

    from femrub.geometry import section_blade

    angle = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    for i, z in enumerate((0.0, 5.0, 10.0)):  # cm: ellipses 3 cm x 0.3 cm, 5 cm apart
        pts = np.column_stack([1.5 * np.cos(angle), 0.15 * np.sin(angle), np.full(40, z)])
        np.savetxt(tmp_path / f"s{i}.csv", pts, delimiter=",")
    monkeypatch.setattr(section_blade, "loft_blade", lambda *a, **k: pytest.fail("meshed"))
    assert main(["mesh", "sections", str(tmp_path), "--axis", "z", "--h", "1e-5"]) == 2
    err = capsys.readouterr().err
    assert "tetrahedra between these sections" in err and "raise h" in err
    volume = np.pi * 0.015 * 0.0015 * 0.1  # m³
    n = section_blade.estimate_section_tets(
        [np.loadtxt(tmp_path / f"s{i}.csv", delimiter=",").T * 0.01 for i in range(3)], 1e-3
    )
    assert n == pytest.approx(8.5 * volume / 1e-9, rel=0.05)


@pytest.mark.parametrize(
    "text, words",
    [
        ("*NODE\n99999999999999999999999, 0, 0, 0\n", "Malformed *NODE line"),
        ("*NODE\n1, 1e999, 0, 0\n", "non-finite coordinate"),
        ("*NSET, NSET=A, GENERATE\n1, 1e30, 1\n", "gives 1e+30 members"),
        ("*NSET, NSET=A, GENERATE\n1, 999999999999, 1\n", "at most 1e+08"),
        ("*NSET, NSET=A, GENERATE\n1, 9, 0\n", "step >= 1"),
        ("*NODE\n1,0,0,0\n*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 99999999999999999999999\n", "*ELEMENT"),
    ],
)
def test_deck_numbers_out_of_range_are_named(tmp_path, text, words):
    """Numbers too large for an index or non-finite: a GeometryError naming the line, never
    an OverflowError or a MemoryError."""
    from femrub.geometry import GeometryError
    from femrub.geometry.abaqus_reader import read_abaqus

    (tmp_path / "deck.inp").write_text(text)
    with pytest.raises(GeometryError, match=re.escape(words)):
        read_abaqus(tmp_path / "deck.inp", "mm")
