"""The direction of rotation: the lobe phase and the casing's sliding follow it together;
the reversed sliding flips the friction; the default comes from the blade's tip section."""

from __future__ import annotations

import numpy as np
import pytest
from test_friction import block_model

from femrub.analysis import ThetaMethod
from femrub.app import translate as tr
from femrub.app.blade import load_blade
from femrub.contact.casing import sliding_velocity
from femrub.geometry.rotation_direction import derive_rotation_direction
from femrub.model.builder import build_rub
from femrub.scene import SceneError, loads_scene

BLADE = """
name = "turning"
[geometry]
kind = "naca"
code = "{code}"
span = 0.1
root_chord = 0.05
tip_chord = 0.035
twist = 20.0
n_sections = 3
h = 0.012
hub_radius = 0.2
n_contact = 6
[contact]
casing = {{ kind = "lobed", clearance = "20 um", depth = "50 um", lobes = 3, phase = 10.0 }}
gap_reference = "outermost"
reach = "all"
friction = 0.15
[loads]
rotation_speed = 1500.0
centrifugal = "off"
[physics]
order = 1
thermal = "off"
[scheme]
h = 1e-5
t_end = 1e-3
"""

TIMES = np.linspace(0.0, 4e-3, 9)


def _scene(code="0012", **changes):
    return loads_scene(BLADE.format(code=code)).with_changes(changes)


@pytest.fixture(scope="module")
def blade():
    return load_blade(_scene())


def _model(blade, **changes):
    return build_rub(blade, tr.rub_config(_scene(**changes)))


def test_sliding_block_friction_flips_with_the_reversed_slip():
    """A block pressed on the casing (spring to a wall along the sliding direction): the
    casing drags it along its sliding velocity, so the friction force on it and its mean
    displacement take the sign of the sliding, which ``reversed`` turns and the direction
    of rotation turns too."""
    means = {}
    for sigma in (1.0, -1.0):
        for slip in (1.0, -1.0):
            v = sliding_velocity([0.3], 2.0, sigma, slip)[0]
            assert v[0] == 0.0 and v[1] == pytest.approx(-slip * sigma * 0.6)
            model = block_model(m=1.0, k=400.0, N=10.0, mu=0.3, v_belt=v[1])
            res = ThetaMethod(model, 1e-4).run(0.5)
            assert res.status == "ok"
            friction = res.friction_force[1:, 0, 0]
            sliding = res.slip_velocity[1:, 0, 0] != 0.0
            assert sliding.sum() > 100
            # Coulomb on the block: |λ_t| = μ N along the casing's relative sliding
            np.testing.assert_allclose(np.abs(friction[sliding]), 3.0, rtol=1e-9)
            assert np.all(np.sign(friction[sliding]) == np.sign(v[1]))
            # force balance: the spring holds the mean friction force
            x = res.signal("x")
            means[sigma, slip] = float(np.mean(400.0 * x)), float(np.mean(friction))
    for sigma in (1.0, -1.0):
        (kx, f), (kx_r, f_r) = means[sigma, 1.0], means[sigma, -1.0]
        assert np.sign(f) == -sigma and np.sign(f_r) == sigma
        assert kx == pytest.approx(-kx_r, rel=1e-9) and f == pytest.approx(-f_r, rel=1e-9)
        assert kx == pytest.approx(f, rel=0.1)
    assert means[1.0, -1.0] == pytest.approx(means[-1.0, 1.0], rel=1e-12)


def test_reversed_slip_turns_the_sliding_and_keeps_the_phase(blade):
    rotation = _model(blade, **{"loads.rotation_direction": "counterclockwise"}).model
    reversed_ = _model(
        blade,
        **{"loads.rotation_direction": "counterclockwise", "contact.slip_direction": "reversed"},
    ).model
    np.testing.assert_array_equal(
        reversed_.contact.casing_velocity, -rotation.contact.casing_velocity
    )
    assert np.all(rotation.contact.casing_velocity[:, 1] < 0)  # −Ω r along e_φ
    for t in TIMES:
        np.testing.assert_array_equal(reversed_.contact.gap_at(t), rotation.contact.gap_at(t))
    assert reversed_.sweep.slip == -1.0 and rotation.sweep.slip == 1.0


def test_clockwise_mirrors_the_lobe_phase(blade):
    """``g(−Ω t + φ)``: the clockwise gap at t is the counterclockwise one at −t, its rate
    the opposite, and the casing slides the other way."""
    ccw = _model(blade, **{"loads.rotation_direction": "counterclockwise"}).model.contact
    cw = _model(blade, **{"loads.rotation_direction": "clockwise"}).model.contact
    for t in TIMES[1:]:
        np.testing.assert_allclose(cw.gap_at(t), ccw.gap_at(-t), rtol=0, atol=1e-15)
        assert not np.allclose(cw.gap_at(t), ccw.gap_at(t), rtol=0, atol=1e-9)
        np.testing.assert_allclose(cw.gap_rate(t), -ccw.gap_rate(-t), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(cw.casing_velocity, -ccw.casing_velocity)


def test_the_speed_parameter_keeps_the_direction(blade):
    """``with_parameters(rotation_speed=...)`` keeps the direction and the sliding."""
    for changes in (
        {"loads.rotation_direction": "clockwise"},
        {"loads.rotation_direction": "clockwise", "contact.slip_direction": "reversed"},
    ):
        slow = _model(blade, **changes).model
        fast = _model(blade, **changes, **{"loads.rotation_speed": 2500.0}).model
        moved = slow.with_parameters(rotation_speed=2500.0)
        assert moved.sweep == slow.sweep
        np.testing.assert_array_equal(moved.contact.casing_velocity, fast.contact.casing_velocity)
        for t in TIMES:
            np.testing.assert_array_equal(moved.contact.gap_at(t), fast.contact.gap_at(t))
            np.testing.assert_array_equal(moved.contact.gap_rate(t), fast.contact.gap_rate(t))


def test_default_is_derived_from_a_cambered_tip_and_mirrors_with_the_blade():
    scene = _scene("4412")
    cambered = load_blade(scene)
    derived = derive_rotation_direction(cambered)
    assert derived.source == "geometry" and "pressure side" in derived.reason
    built = build_rub(cambered, tr.rub_config(scene))
    assert built.rotation == derived
    assert built.model.sweep.direction == derived.sign
    assert np.sign(built.model.contact.casing_velocity[:, 1]).tolist() == [-derived.sign] * 6
    # the blade mirrored in a plane through the machine axis turns the other way
    cambered.mesh.p[1] *= -1.0
    mirrored = derive_rotation_direction(cambered)
    assert mirrored.source == "geometry" and mirrored.sign == -derived.sign


def test_no_default_from_a_symmetric_section_or_the_bar(blade):
    from femrub.geometry.bar import bar_mesh

    for mesh, why in ((blade, "no camber"), (bar_mesh(0.3, 10), "1D bar")):
        d = derive_rotation_direction(mesh)
        assert (d.direction, d.source) == ("counterclockwise", "default") and why in d.reason


def test_bad_values_get_the_one_line_error():
    for key, value in (
        ("loads.rotation_direction", "anticlockwise"),
        ("contact.slip_direction", "backwards"),
    ):
        with pytest.raises(SceneError) as err:
            _scene(**{key: value})
        text = str(err.value)
        assert key in text and value in text and "\n" not in text.strip()


def test_a_clockwise_coated_casing_is_cut_behind_the_contacts(tmp_path):
    """Frictional blade cutting an abradable coating, clockwise: the run is ok at the yield
    force, and every worn cell lies on the arc the contacts swept, ψ = φ_i − Ω t."""
    import json

    from test_abradable import COATED_BLADE

    from femrub.app.run import run_scene
    from femrub.scene import load_scene

    t_end, omega = COATED_BLADE["scheme.t_end"], 1500.0  # twisted-naca's speed
    changes = {**COATED_BLADE, "loads.rotation_direction": "clockwise"}
    _, built = run_scene(load_scene("twisted-naca", changes), tmp_path / "out")
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["status"] == "ok", s.get("message")
    assert s["max_contact_force"] == pytest.approx(5.0, rel=1e-9)
    assert built.report["rotation"]["direction"] == "clockwise"
    table = np.loadtxt(tmp_path / "out" / "wear_map.csv", delimiter=",", skiprows=1)
    worn = np.radians(table[table[:, 1:].max(axis=1) > 0, 0])
    assert worn.size > 10
    cell = 2 * np.pi / table.shape[0]
    behind = np.mod(built.full.sweep.angles[:, None] - worn[None, :], 2 * np.pi)
    assert np.all(behind.min(axis=0) <= omega * t_end + 2 * cell)
