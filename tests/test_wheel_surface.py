"""The casing's surface on a bladed disk: the abradable coating every blade cuts, the wall's heat.

The wheel is the small 6-blade wheel of ``test_wheel_scene.py``. Its casing has three lobes,
the first crest (widest bore) at ``phase = 10°``, so the bore is narrowest, and the blades cut
deepest, at ``10° + 60° + 120° j``; a grid swept the wrong way round would put the cuts at
the mirror angles ``−70° + 120° j`` (50° modulo 120°).
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from test_wheel_scene import REVOLUTION, WHEEL

from femrub.app.cli import main
from femrub.app.scheme import bare_stepper
from femrub.app.wheel import _bases, _model, wheel_parts
from femrub.scene import load_scene

THICKNESS = 100e-6  # m
YIELD = 5.0  # N per contact
LOBES, PHASE = 3, 10.0  # the casing's lobes and first crest (deg)
TROUGH = PHASE + 180.0 / LOBES  # deg: the narrowest bore, modulo 360 / LOBES
MIRROR = -TROUGH % (360.0 / LOBES)  # deg: where a grid swept the wrong way would put it


def _scene_text(*, direction="counterclockwise", friction=0.0, rigid=False, extra=""):
    text = WHEEL.replace(
        "[contact]\nfriction = 0.02",
        f"[contact]\nfriction = {friction}\n{extra}[contact.abradable]\n"
        f'thickness = "{THICKNESS * 1e6:g} um"\nyield = {YIELD}\nn_angle = 180',
    )
    text = text.replace("lobes = 3", f"lobes = {LOBES}\nphase = {PHASE}")
    text = text.replace(
        'centrifugal = "linear"', f'centrifugal = "linear"\nrotation_direction = "{direction}"'
    )
    if rigid:
        text = text.replace("thickness = 0.004\naxial_length", "axial_length")
    return text


def _coated_run(tmp_path, **kw):
    path = tmp_path / "coated.toml"
    path.write_text(_scene_text(**kw))
    scene = load_scene(str(path))
    parts = wheel_parts(scene)
    (bases,) = _bases(parts, [(scene["rotor"]["families"], scene["casing"]["ring"]["families"])])
    model, _ = _model(parts, *bases)
    stepper = bare_stepper(scene, model)
    return scene, model, stepper, stepper.run(REVOLUTION)


def _harmonic_angle(angles, profile) -> float:
    """The angle (deg, modulo 360 / LOBES) of the ``LOBES``-th harmonic of ``profile`` over
    the casing ``angles`` (rad)."""
    c = np.sum(profile * np.exp(1j * LOBES * angles))
    return math.degrees(np.angle(c)) / LOBES % (360.0 / LOBES)


@pytest.mark.parametrize("direction", ["counterclockwise", "clockwise"])
def test_every_blade_cuts_the_coating_under_the_narrow_bore(tmp_path, direction):
    scene, model, stepper, res = _coated_run(tmp_path, direction=direction, rigid=True)
    wear = stepper.model.contact.wear
    assert model.contact.wear is not wear  # the run's own coating; the model's stays unworn
    assert not model.contact.wear.depth.any()
    assert 5e-6 < wear.max_depth < THICKNESS and wear.depth.min() >= 0.0
    # every blade's tips went into the coating, none deeper than it, the surface no deeper
    # than what they reached
    incursion = wear.incursion.reshape(6, -1).max(axis=1)
    assert np.all(incursion > 0.0) and incursion.max() <= THICKNESS
    assert wear.max_depth <= incursion.max() * (1 + 1e-9)
    assert (
        abs(_harmonic_angle(wear.angle_centres(), wear.surface.mean(axis=1)) - TROUGH) < 5
    )  # the mirror angle is 20° off
    # every blade cuts: each one's contacts take an impulse at the cap h F_y
    cap = scene["scheme"]["h"] * YIELD
    impulse = res.impulse.reshape(res.impulse.shape[0], 6, -1)
    assert impulse.max() <= cap * (1 + 1e-9)
    assert np.all(impulse.max(axis=(0, 2)) >= cap * (1 - 1e-6))
    assert res.energy_error() < 1e-8


@pytest.mark.parametrize("thermal", ["off", "auto"])
def test_a_coated_ring_heated_by_friction_through_femrub_run(tmp_path, thermal):
    path = tmp_path / "heated.toml"
    heat = f"[contact.casing_heat]\nthickness = 0.004\n[physics]\nthermal = '{thermal}'\n"
    text = _scene_text(friction=0.1).replace("[loads]", heat + "[loads]")
    text = text.replace("step_check = true", "step_check = false")
    path.write_text(text.replace(f"t_end = {3 * REVOLUTION!r}", f"t_end = {REVOLUTION!r}"))
    out = tmp_path / "run"
    assert main(["run", str(path), "-o", str(out), "-q"]) in (0, 1)
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] in ("ok", "inaccurate"), s["message"]
    build = s["inputs"]["build"]
    eta = build["casing_heat"]["partition"]
    assert 0.0 < eta < 1.0 and build["abradable"]["thickness"] == pytest.approx(THICKNESS)
    assert 0.0 < s["max_wear_depth"] <= THICKNESS and s["worn_volume"] > 0.0
    surface = np.loadtxt(out / "wear_map.csv", delimiter=",", skiprows=1)
    assert surface.shape == (180, 1 + build["abradable"]["n_axial"])
    assert surface[:, 1:].max() <= s["max_wear_depth"] * (1 + 1e-7)  # 8 digits in the csv
    # the casing takes its share 1 − η of the friction work (the energy meter's mid-step
    # slip) and the wall's model received as much (its own end-of-step slip); the blades
    # take the rest into their temperature, or, without temperature dofs, nothing
    work, blade, casing = s["friction_work"], s["heat_to_blade"], s["heat_to_casing"]
    assert work > 0.0
    assert s["casing_heat_in"] == pytest.approx(casing, rel=1e-2)
    explain = (out / "explain.txt").read_text()
    if thermal == "off":
        assert blade == 0.0 and casing == pytest.approx((1 - eta) * work, rel=1e-9)
        assert "blade heat" in explain
    else:
        assert blade + casing == pytest.approx(work, rel=1e-9)
        assert blade == pytest.approx(eta * work, rel=1e-2) and s["heat_error"] < 1e-10
        assert "coordinates of the blades' temperature" in explain
        assert s["max_contact_temperature"] > 0.0
    wall = np.loadtxt(out / "casing_temperature.csv", delimiter=",", skiprows=1)
    assert 0.0 < wall[:, 1:].max() <= s["max_casing_temperature"] * (1 + 1e-7)
    hot = _harmonic_angle(np.radians(wall[:, 0]), wall[:, 1:].mean(axis=1))
    assert abs(hot - TROUGH) < abs(hot - MIRROR)  # heated where it rubs (ahead of the trough)
    assert "yields at 5 N per contact" in explain
    # the coating is read at points: the warning names one blade's contact spacing (a few
    # mm on a 12 mm tip), not the blades' pitch (78 mm at the tips)
    (footprint,) = [w for w in build["warnings"] if w.startswith("contact.abradable.footprint")]
    assert "each of the 12 contacts" in footprint
    assert 0.5 < float(re.search(r"about ([0-9.]+) mm", footprint).group(1)) < 12.0
    blades = np.genfromtxt(out / "blades.csv", delimiter=",", names=True)
    deepest = blades["max_incursion_m"]
    assert np.all(deepest > 0.0) and deepest.max() == pytest.approx(s["max_incursion"])
    assert s["max_wear_depth"] <= s["max_incursion"] * (1 + 1e-9) <= THICKNESS * (1 + 1e-9)
    assert s["blades"]["deepest_incursion"]["max_incursion_m"] == pytest.approx(deepest.max())
    # scheme.step_check = false: no time-step check, and its cost is not in the timings
    assert "time step  not checked (scheme.step_check = false)" in explain
    assert s.get("time_step_error") is None and "step_check" not in s["timings"]
    assert s["timings"]["reduction"] > 0.0 and s["reduction_error"]["estimate"] >= 0.0


@pytest.mark.parametrize(
    ("change", "key"),
    [
        ("friction = 0.0", "contact.friction"),
        ("friction = 0.1\nheat_partition = 1.0", "contact.heat_partition"),
        ("friction = 0.1\nheat_law = 'alpha'", "contact.heat_coefficient"),
    ],
)
def test_casing_heat_without_heat_for_the_casing_is_refused_before_building(
    tmp_path, capsys, change, key
):
    text = _scene_text(friction=0.0).replace("friction = 0.0", change)
    text = text.replace("[loads]", "[contact.casing_heat]\nthickness = 0.004\n[loads]")
    path = tmp_path / "refused.toml"
    path.write_text(text)
    assert main(["run", str(path), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].count(key) >= 1, err
    assert not (tmp_path / "out").exists()
