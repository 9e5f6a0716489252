"""Immutable models and the rotation speed as a model parameter (``with_parameters``)."""

from __future__ import annotations

import dataclasses
import pickle

import pytest
from test_one_builder import BLADE, _assert_same_model, _same_values

import femrub as fr
from femrub.app import translate as tr
from femrub.app.blade import load_blade
from femrub.model.builder import build_rub
from femrub.reduction.craig_bampton import ThermoelasticCraigBampton
from femrub.scene import loads_scene
from femrub.scene.units import rpm


def test_models_are_frozen():
    model = fr.bar_model()
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.A = None
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.loads[0].signal = None
    with pytest.raises(AttributeError):
        model.parameters.rotation_speed = 1.0
    assert model.parameters == {"rotation_speed": rpm(2000.0)}
    assert pickle.loads(pickle.dumps(model.parameters)) == model.parameters


def test_bar_at_another_speed_is_the_bar_built_there():
    model = fr.bar_model(alpha=3.0)
    faster = model.with_parameters(rotation_speed=rpm(3000.0))
    _assert_same_model(faster, fr.bar_model(alpha=3.0, force_frequency=rpm(3000.0)))
    assert faster.A is model.A and faster.B is model.B  # no matrix rebuilt
    assert model.parameters["rotation_speed"] == rpm(2000.0)  # the model itself unchanged
    assert model.with_parameters() is model
    with pytest.raises(ValueError, match="unknown model parameter"):
        model.with_parameters(speed=1.0)


@pytest.fixture(scope="module")
def blades():
    """The scene's blade at 1000 rpm and built again at 2500 rpm."""
    scene = loads_scene(BLADE).with_changes({"contact.reach": "all"})
    blade = load_blade(scene)
    slow = build_rub(blade, tr.rub_config(scene)).model
    fast_scene = scene.with_changes({"loads.rotation_speed": "2500 rpm"})
    fast = build_rub(blade, tr.rub_config(fast_scene)).model
    return slow, fast


def test_blade_at_another_speed_is_the_blade_built_there(blades):
    slow, fast = blades
    moved = slow.with_parameters(rotation_speed=rpm(2500.0))
    _assert_same_model(moved, fast)
    _same_values(moved.contact.casing_velocity, fast.contact.casing_velocity)
    assert moved.parameters["rotation_speed"] == fast.parameters["rotation_speed"]


def test_reduced_model_follows_the_speed(blades):
    slow, fast = blades
    reduced = ThermoelasticCraigBampton(slow, 6, 4).reduce()
    assert reduced.length_scale == slow.length_scale
    assert reduced.parameters == slow.parameters
    moved = reduced.with_parameters(rotation_speed=rpm(2500.0))
    assert moved.A is reduced.A
    for t in (0.0, 1e-3, 7e-3):
        _same_values(moved.contact.gap_at(t), fast.contact.gap_at(t))
        _same_values(moved.load(t)[:0], fast.load(t)[:0])
        assert moved.loads[0].signal(t) == fast.loads[0].signal(t)
    _same_values(moved.contact.casing_velocity, fast.contact.casing_velocity)


def test_prestressed_model_refuses_another_speed():
    scene = loads_scene(BLADE).with_changes(
        {"loads.centrifugal": "linear", "contact.reach": "all", "geometry.h": 0.02}
    )
    model = build_rub(load_blade(scene), tr.rub_config(scene)).model
    assert model.sweep.prestress_speed == scene["loads"]["rotation_speed"]
    with pytest.raises(ValueError, match="centrifugal prestress"):
        model.with_parameters(rotation_speed=rpm(2000.0))
