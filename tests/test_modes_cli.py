"""``femrub modes``: the files of a small bladed disk with its casing ring, the refusals."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from femrub.app.cli import main

SCENE = """
name = "small-wheel"
[geometry]
kind = "naca"
span = 0.03
root_chord = 0.015
tip_chord = 0.012
n_sections = 3
h = 0.015
[rotor]
sectors = 6
hub_radius = 0.02
rim_radius = 0.045
thickness = 0.015
families = 2
[casing.ring]
thickness = 0.004
axial_length = 0.04
clearance = "1 mm"
lobes = 3
distortion = "20 um"
h = 0.012
families = 2
[loads]
rotation_speed = 2000.0
centrifugal = "linear"
[scheme]
h = 1e-6
t_end = 1e-5
"""


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def modes_folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("modes")
    scene = root / "wheel.toml"
    scene.write_text(SCENE)
    out = root / "out"
    assert main(["modes", str(scene), "-o", str(out), "-q"]) == 0
    return scene, out


def test_modes_csv_has_both_structures_by_nodal_diameter_and_family(modes_folder):
    _, out = modes_folder
    rows = _rows(out / "modes.csv")
    assert list(rows[0]) == [
        "structure",
        "nodal_diameter",
        "family",
        "frequency_hz",
        "rotation_speed",
    ]
    for structure, speed in (("disk", 2000.0), ("casing", 0.0)):
        mine = [r for r in rows if r["structure"] == structure]
        assert sorted({int(r["nodal_diameter"]) for r in mine}) == [0, 1, 2, 3]
        assert sorted({int(r["family"]) for r in mine}) == [1, 2]
        assert all(float(r["rotation_speed"]) == speed for r in mine)
        for k in range(4):
            f = [float(r["frequency_hz"]) for r in mine if int(r["nodal_diameter"]) == k]
            assert f == sorted(f) and f[0] > 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["structures"] == ["disk", "casing"]
    assert summary["disk"]["prestress"] == "linear" and summary["casing"]["lobes"] == 3
    ring = summary["casing"]["inner_radius"]
    assert ring == pytest.approx(summary["disk"]["tip_radius"] + 1e-3)
    assert (out / "modes.png").stat().st_size > 10_000


def test_coincidence_speeds_follow_from_the_modes(modes_folder):
    _, out = modes_folder
    modes = {
        (r["structure"], int(r["nodal_diameter"]), int(r["family"])): float(r["frequency_hz"])
        for r in _rows(out / "modes.csv")
    }
    rows = _rows(out / "coincidences.csv")
    assert len(rows) == 3 * 2 * 2  # k = 1, 2, 3; two families each
    for r in rows:
        k = int(r["nodal_diameter"])
        fd = modes["disk", k, int(r["disk_family"])]
        fc = modes["casing", k, int(r["casing_family"])]
        assert float(r["rotation_speed"]) == pytest.approx(2 * math.pi * (fd + fc) / k, rel=1e-9)
    speeds = [float(r["rotation_speed"]) for r in rows]
    assert speeds == sorted(speeds)
    assert {r["method"] for r in rows} == {"scene-speed"}
    assert not (out / "campbell.png").exists()


def test_modes_keeps_a_finished_folder_and_run_refuses_what_a_wheel_lacks(modes_folder, capsys):
    scene, out = modes_folder
    capsys.readouterr()
    assert main(["modes", str(scene), "-o", str(out), "-q"]) == 2
    assert "--overwrite" in capsys.readouterr().err
    run = ["run", str(scene), "-o", str(out.parent / "run"), "-q", "--set=scheme.name=carpenter"]
    assert main(run) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "scheme.name = 'carpenter'" in err and "a bladed disk runs the θ-method" in err
    assert not (out.parent / "run").exists()


@pytest.mark.parametrize(
    ("option", "words"),
    [
        ("--set=rotor.rim_radius=0.01", "rotor.rim_radius = 0.01: must exceed rotor.hub_radius"),
        ("--set=rotor.sectors=2", "rotor.sectors = 2: must be >= 3"),
        ("--set=geometry.kind=box", "geometry.kind = 'box': the blades of a bladed disk"),
        ("--set=casing.ring.lobes=0", "casing.ring.distortion = 2e-05: an out-of-roundness needs"),
        ("--speeds=15000:10000:1000", "--speeds '15000:10000:1000': use START:STOP:STEP"),
        ("--speeds=fast", "--speeds 'fast': use START:STOP:STEP"),
        ("--speeds=5000", "--speeds '5000': give two or more increasing speeds"),
        ("--speeds=-100,2000", "--speeds '-100,2000': give two or more increasing speeds >= 0"),
        ("--speeds=3000,1000", "--speeds '3000,1000': give two or more increasing speeds"),
    ],
)
def test_bad_values_are_refused_in_one_line_before_any_mesh(tmp_path, capsys, option, words):
    scene = tmp_path / "wheel.toml"
    scene.write_text(SCENE)
    out = tmp_path / "out"
    assert main(["modes", str(scene), option, "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err
    assert not out.exists()


def test_a_single_blade_scene_gets_its_blade_modes(tmp_path):
    out = tmp_path / "out"
    args = ["modes", "twisted-naca", "-o", str(out), "-q", "--set", "rotor.families=2"]
    assert main(args + ["--set", "geometry.h=0.02"]) == 0
    rows = _rows(out / "modes.csv")
    assert [r["structure"] for r in rows] == ["blade", "blade"]
    assert [r["nodal_diameter"] for r in rows] == ["", ""]
    f = np.array([float(r["frequency_hz"]) for r in rows])
    assert np.all(f > 0) and f[1] > f[0]
    assert {float(r["rotation_speed"]) for r in rows} == {1500.0}
    assert not (out / "coincidences.csv").exists()


def test_a_failed_computation_keeps_the_disk_modes_marked_failed(tmp_path, monkeypatch, capsys):
    import femrub.app.modes as modes

    def no_ring(scene, tip_radius):
        raise modes.SceneError("casing.ring: gmsh could not mesh the ring")

    monkeypatch.setattr(modes, "casing_sector", no_ring)
    scene = tmp_path / "wheel.toml"
    scene.write_text(SCENE.replace("families = 2", "families = 1"))
    out = tmp_path / "out"
    assert main(["modes", str(scene), "-o", str(out), "-q"]) == 2
    assert "casing.ring: gmsh could not mesh the ring" in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "gmsh could not mesh" in summary["message"]
    rows = _rows(out / "modes.csv")
    assert {r["structure"] for r in rows} == {"disk"} and len(rows) == 4
    assert not (out / "coincidences.csv").exists()


@pytest.fixture(scope="module")
def speeds_folder(tmp_path_factory):
    """The small wheel at 10 000 and 15 000 rad/s with a soft ring (5 GPa): the 3-diameter
    coincidences lie between the two speeds."""
    root = tmp_path_factory.mktemp("modes-speeds")
    scene = root / "wheel.toml"
    scene.write_text(SCENE)
    out = root / "out"
    args = ["modes", str(scene), "-o", str(out), "-q", "--speeds", "10000:15000:5000"]
    assert main(args + ["--set", "casing.ring.young=5e9"]) == 0
    return out


def test_modes_over_speeds_write_a_block_per_speed_and_the_campbell_diagram(speeds_folder):
    out = speeds_folder
    rows = _rows(out / "modes.csv")
    disk = [r for r in rows if r["structure"] == "disk"]
    assert [float(r["rotation_speed"]) for r in disk] == [10000.0] * 8 + [15000.0] * 8
    assert [(r["nodal_diameter"], r["family"]) for r in disk[:8]] == [
        (r["nodal_diameter"], r["family"]) for r in disk[8:]
    ]
    assert all(
        float(b["frequency_hz"]) > float(a["frequency_hz"]) for a, b in zip(disk[:8], disk[8:])
    )
    casing = [r for r in rows if r["structure"] == "casing"]
    assert len(casing) == 8 and {float(r["rotation_speed"]) for r in casing} == {0.0}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["speeds"] == [10000.0, 15000.0]
    assert "campbell.png" in summary["files"]
    assert (out / "campbell.png").stat().st_size > 10_000
    assert (out / "modes.png").stat().st_size > 10_000


def test_coincidences_between_speeds_solve_the_interpolated_equation(speeds_folder):
    """Each interpolated row solves k Ω = ω_d(Ω) + ω_c with ω_d² linear in Ω² between the
    two blocks of modes.csv; the others keep their sign and take the top speed's ω_d."""
    out = speeds_folder
    hz = {}
    for r in _rows(out / "modes.csv"):
        key = (r["structure"], int(r["nodal_diameter"]), int(r["family"]))
        hz.setdefault(key, []).append(float(r["frequency_hz"]))
    rows = _rows(out / "coincidences.csv")
    assert list(rows[0])[-1] == "method" and len(rows) == 12
    interpolated = [r for r in rows if r["method"] == "interpolated"]
    assert {int(r["nodal_diameter"]) for r in interpolated} == {3}
    for r in rows:
        k, speed = int(r["nodal_diameter"]), float(r["rotation_speed"])
        (fa, fb), (fc,) = (
            hz["disk", k, int(r["disk_family"])],
            hz["casing", k, int(r["casing_family"])],
        )
        if r["method"] == "interpolated":
            assert 10000.0 < speed < 15000.0
            t = (speed**2 - 10000.0**2) / (15000.0**2 - 10000.0**2)
            fd = math.sqrt(fa**2 + (fb**2 - fa**2) * t)
            assert float(r["disk_frequency_hz"]) == pytest.approx(fd, rel=1e-9)
        else:
            assert r["method"] == "outside-range" and speed > 15000.0
            fd = fb
        assert k * speed == pytest.approx(2 * math.pi * (fd + fc), rel=1e-9)


def test_speeds_on_a_single_blade_point_to_femrub_campbell(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["modes", "twisted-naca", "--speeds", "0:1000:500", "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "femrub campbell twisted-naca --speeds 0:1000:500" in err
    assert not out.exists()


def test_a_sweep_that_fails_keeps_the_speeds_solved_marked_failed(tmp_path, monkeypatch, capsys):
    """The prestress fails at the second speed: the first speed's block is written, the
    folder marked failed with the one-line reason, no coincidences."""
    import femrub.model.cyclic as cyclic

    solve = cyclic.spinning

    def no_convergence_above_12000(rest, material, omega, start=None):
        if omega > 12000.0:
            raise ValueError(f"Newton on the rotor's centrifugal prestress at Ω = {omega:g} rad/s")
        return solve(rest, material, omega, start)

    monkeypatch.setattr(cyclic, "spinning", no_convergence_above_12000)
    scene = tmp_path / "wheel.toml"
    scene.write_text(SCENE.replace("families = 2", "families = 1"))
    out = tmp_path / "out"
    assert main(["modes", str(scene), "--speeds", "10000,15000", "-o", str(out), "-q"]) == 2
    assert "Ω = 15000 rad/s" in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["speeds"] == [10000.0, 15000.0]
    rows = _rows(out / "modes.csv")
    assert [float(r["rotation_speed"]) for r in rows] == [10000.0] * 4
    assert (out / "campbell.png").exists() and not (out / "coincidences.csv").exists()
