"""`femrub run` of a bladed-disk scene: the wheel against its flexible casing ring, checked."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from femrub.app.cli import main
from femrub.app.wheel import _bases, _state_transfer, wheel_parts
from femrub.scene import load_scene

SPEED = 1000.0  # rad/s
REVOLUTION = 2 * math.pi / SPEED
WHEEL = f"""
name = "wheel6"
[geometry]
kind = "naca"
code = "0012"
span = 0.03
root_chord = 0.015
tip_chord = 0.012
twist = 20.0
n_sections = 3
h = 0.015
h_min = 0.01
[material]
young = "110 GPa"
poisson = 0.3
density = 4500.0
[rotor]
sectors = 6
hub_radius = 0.02
rim_radius = 0.045
thickness = 0.015
families = 3
contacts = 2
damping_ratio = 0.02
[casing.ring]
thickness = 0.004
axial_length = 0.03
clearance = "20 um"
lobes = 3
distortion = "200 um"
h = 0.01
families = 2
[contact]
friction = 0.02
[loads]
rotation_speed = {SPEED}
centrifugal = "linear"
[scheme]
step_check = true
h = {REVOLUTION / 1500!r}
t_end = {3 * REVOLUTION!r}
[outputs]
plots = false
"""


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("wheel") / "wheel6.toml"
    path.write_text(WHEEL)
    return path


def test_run_writes_every_blade_and_both_checks(scene_file, tmp_path):
    out = tmp_path / "run"
    assert main(["run", str(scene_file), "-o", str(out), "-q"]) in (0, 1)
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] in ("ok", "inaccurate"), s["message"]
    assert s["steps"] == 4500
    assert s["timings"]["step_check"] > 0.0 and s["timings"]["reduction"] > 0.0
    seconds = s["inputs"]["build"]["reduction"]["seconds"]  # the bases, the estimate's runs
    assert s["timings"]["reduction"] == pytest.approx(seconds["bases"] + seconds["estimate"])
    for check in ("reduction_error", "time_step_error"):
        assert 0.0 <= s[check]["estimate"] < 1.0 and s[check]["tolerance"] > 0.0
    with np.load(out / "history.npz") as h:
        assert h["signal_blade_tip_displacement"].shape == (4501, 6)
        assert h["impulse"].shape == (4501, 12) and h["impulse"].sum() > 0.0
        assert (
            np.abs(h["energy_energy_error"]).max() < 1e-8 * np.abs(h["energy_contact_work"]).max()
        )
        assert np.abs(h["energy_heat_error"]).max() < 1e-8 * h["energy_heat_content"].max()
        impulse = h["impulse"].reshape(4501, 6, 2)
        tip = h["signal_blade_tip_displacement"]
        hot = h["signal_blade_tip_temperature"]
    assert "6 blades, 2 tip contacts each" in (out / "explain.txt").read_text()
    # blades.csv: one row per blade from the histories; a tuned wheel against a 3-lobed
    # casing treats blades a lobe apart (two blades) alike
    blades = np.genfromtxt(out / "blades.csv", delimiter=",", names=True)
    h_step = REVOLUTION / 1500
    np.testing.assert_allclose(blades["max_normal_force_n"], impulse.max(axis=(0, 2)) / h_step)
    np.testing.assert_allclose(blades["rms_tip_displacement_m"], np.sqrt((tip**2).mean(axis=0)))
    np.testing.assert_allclose(blades["max_tip_temperature_k"], hot.max(axis=0))
    for column in ("max_normal_force_n", "rms_tip_displacement_m", "max_tip_temperature_k"):
        v = blades[column]
        np.testing.assert_allclose(v[[2, 3, 4, 5]], v[[0, 1, 2, 3]], rtol=1e-6)
    assert s["blades"]["n_blades"] == 6 and s["blades"]["hottest_tip"]["blade"] in range(6)


def test_the_richer_wheel_holds_the_runs_fields_exactly(scene_file):
    parts = wheel_parts(load_scene(str(scene_file)))
    assert parts.thermal is not None  # friction heats the blades: temperature dofs
    small, rich = _bases(parts, [(3, 2, 2), (5, 3, 3)])
    T = _state_transfer(parts, small, rich)
    n_disk_small, n_disk_rich = small[0].size, rich[0].size
    x = np.random.default_rng(1).standard_normal(T.shape[1])
    carried = T @ x
    n_t_small, n_t_rich = small[2].size, rich[2].size
    for s in (0, 1, 3):
        a = small[0].sector_field(x[:n_disk_small], s)
        b = rich[0].sector_field(carried[:n_disk_rich], s)
        assert np.abs(a - b).max() <= 1e-9 * np.abs(a).max()
        a = small[2].sector_field(x[-n_t_small:], s)  # the temperature, last in the state
        b = rich[2].sector_field(carried[-n_t_rich:], s)
        assert np.abs(a - b).max() <= 1e-9 * np.abs(a).max()
    # the mass norm and the heat-capacity norm are kept: every coordinate set is normalised
    n_u_small, n_u_rich = (T.shape[1] - n_t_small) // 2, (T.shape[0] - n_t_rich) // 2
    assert np.linalg.norm(carried[:n_u_rich]) == pytest.approx(
        np.linalg.norm(x[:n_u_small]), rel=1e-9
    )
    assert np.linalg.norm(carried[-n_t_rich:]) == pytest.approx(
        np.linalg.norm(x[-n_t_small:]), rel=1e-9
    )
