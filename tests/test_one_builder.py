"""One builder: a blade built in Python and the same blade in a scene give the same model.

The scene goes through its typed configuration (``femrub.app.translate.rub_config``), the
Python presets (``solid_model``, ``bar_model``) through theirs; both end in
``femrub.model.builder.build_rub``. Matrices, contacts (after the reach filter), friction,
the rotation speed and the loads must agree bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import femrub as fr
from femrub.app import translate as tr
from femrub.app.blade import load_blade
from femrub.contact.casing import Concentric
from femrub.geometry import naca_blade
from femrub.model.builder import build_rub
from femrub.model.config import ForceLaw
from femrub.model.rub import solid_model
from femrub.scene import load_scene, loads_scene
from femrub.scene.units import rpm

BLADE = """
name = "naca"
[geometry]
kind = "naca"
code = "0012"
span = 0.1
root_chord = 0.05
tip_chord = 0.035
twist = 20.0
n_sections = 5
h = 0.012
hub_radius = 0.2
n_contact = 8
[contact]
casing = { kind = "concentric", clearance = "5 um" }
gap_reference = "outermost"
friction = 0.1
[loads]
rotation_speed = "1000 rpm"
centrifugal = "off"
tip_force = { law = "sin", amplitude = 50.0, frequency = "rotation", direction = [0.0, 1.0, 0.0] }
[physics]
order = 1
[scheme]
h = 1e-5
t_end = 1e-3
"""

TIMES = np.linspace(0.0, 0.01, 7)


def _same_sparse(a, b) -> None:
    a, b = sp.csr_matrix(a), sp.csr_matrix(b)
    assert a.shape == b.shape
    assert (a != b).nnz == 0


def _same_values(a, b) -> None:
    if a is None or b is None:
        assert a is None and b is None
    elif callable(a):
        for t in TIMES:
            np.testing.assert_array_equal(np.asarray(a(t)), np.asarray(b(t)))
    else:
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def _same_blocks(a, b) -> None:
    """The Eq. (2) blocks of two full models."""
    for name in ("M", "K", "C", "Kut", "Ctu", "Ctt", "Ktt"):
        x, y = getattr(a, name, None), getattr(b, name, None)
        if x is None or y is None:
            assert x is None and y is None, name
        else:
            _same_sparse(x, y)


def _same_contacts(a, b) -> None:
    assert a.names == b.names
    for name in ("G", "Gv", "Hm", "Ht", "Gvt", "Hmt", "frames", "casing_velocity"):
        _same_values(getattr(a, name), getattr(b, name))
    for name in ("friction", "heat_partition", "heat_coefficient", "gap0", "gap_rate"):
        _same_values(getattr(a, name), getattr(b, name))
    assert (a.heat_law, a.restitution) == (b.heat_law, b.restitution)


def _assert_same_model(a, b) -> None:
    assert a.layout == b.layout
    _same_sparse(a.A, b.A)
    _same_sparse(a.B, b.B)
    _same_blocks(a.blocks, b.blocks)
    assert a.boundary.keys() == b.boundary.keys()
    for key in a.boundary:
        _same_values(
            a.boundary[key].toarray() if sp.issparse(a.boundary[key]) else a.boundary[key],
            b.boundary[key].toarray() if sp.issparse(b.boundary[key]) else b.boundary[key],
        )
    assert (a.contact is None) == (b.contact is None)
    if a.contact is not None:
        _same_contacts(a.contact, b.contact)
    assert a.info["rotation_speed"] == b.info["rotation_speed"]
    assert a.length_scale == b.length_scale
    assert sorted(a.observations) == sorted(b.observations)
    for name in a.observations:
        _same_sparse(a.observations[name], b.observations[name])
    assert len(a.loads) == len(b.loads)
    for la, lb in zip(a.loads, b.loads, strict=True):
        _same_values(la.vector, lb.vector)
        _same_values(la.signal, lb.signal)
    _same_values(a.x0, b.x0)


@pytest.fixture(scope="module")
def blade_scene():
    scene = loads_scene(BLADE)
    return scene, build_rub(load_blade(scene), tr.rub_config(scene))


def test_python_blade_is_the_scene_blade(blade_scene, monkeypatch):
    scene, built = blade_scene
    builds = []  # what solid_model's build decided (the reach filter's deflection, ...)

    def spy(*args, **kw):
        builds.append(build_rub(*args, **kw))
        return builds[-1]

    monkeypatch.setattr("femrub.model.builder.build_rub", spy)
    kept = built.model.n_contacts
    assert 0 < kept < built.candidates.n  # the reach filter dropped some candidates
    g = scene["geometry"]
    blade = naca_blade(
        "0012",
        g["span"],
        g["root_chord"],
        g["tip_chord"],
        g["twist"],
        g["n_sections"],
        hub_radius=g["hub_radius"],
        h=g["h"],
        n_contact=g["n_contact"],
    )
    omega = rpm(1000)
    mat = fr.Material(
        young=110e9,
        rho=4500.0,
        poisson=0.3,
        rho_c=4500.0 * 585.0,
        conductivity=3.35,
        expansion=8.6e-6,
    )
    model, _ = solid_model(
        blade,
        mat,
        casing=Concentric(5e-6),
        rotation_speed=omega,
        friction=0.1,
        order=1,
        gap_reference="outermost",
        tip_force=(np.array([0.0, 50.0, 0.0]), ForceLaw("sin", omega)),
    )
    monkeypatch.undo()
    np.testing.assert_array_equal(blade.mesh.p, load_blade(scene).mesh.p)
    _assert_same_model(model, built.model)
    python_reach = builds[0].reach  # harmonic deflection at the force's frequency too
    assert (python_reach.deflection, python_reach.reach) == (
        built.reach.deflection,
        built.reach.reach,
    )
    np.testing.assert_array_equal(python_reach.keep, built.reach.keep)
    assert model.info["rotation_speed"] == scene["loads"]["rotation_speed"] == omega
    np.testing.assert_array_equal(model.contact.friction, np.full(kept, 0.1))
    assert model.contact.Gvt is not None and model.contact.heat_law == "power"
    # every candidate on request
    everything, _ = solid_model(blade, mat, casing=Concentric(5e-6), order=1, reach="all")
    assert everything.n_contacts == built.candidates.n


def test_python_friction_reaches_the_contacts():
    blade = naca_blade("0012", h=0.012, n_contact=3, hub_radius=0.2)
    mat = fr.Material(young=110e9, rho=4500.0, rho_c=4500.0 * 585.0, conductivity=7.0)
    model, fields = solid_model(
        blade,
        mat,
        casing=Concentric(1e-6),
        rotation_speed=100.0,
        friction=0.02,
        order=1,
        reach="all",
    )
    assert model.n_contacts == 3 and model.contact.Gvt is not None
    np.testing.assert_array_equal(model.contact.friction, [0.02] * 3)
    # the casing slides past at Ω r_i along the circumferential tangent
    np.testing.assert_allclose(model.contact.casing_velocity[:, 1], -100.0 * fields.contacts.radii)
    assert model.layout.n_t > 0  # and heats the blade (η × friction power)


def test_bar_model_is_the_paper_scene():
    scene = load_scene("paper")
    built = build_rub(load_blade(scene), tr.rub_config(scene))
    model = fr.bar_model(alpha=3.0)
    _assert_same_model(model, built.model)
    assert model.info["rotation_speed"] == scene["loads"]["rotation_speed"] == rpm(2000.0)
    assert fr.bar_model().length_scale == 0.3


def test_rpm_is_the_scene_unit():
    from femrub.scene.units import to_si

    for value in (7, 1000, 2000, 3000, 12345.5):
        assert rpm(value) == to_si(f"{value} rpm", "angular_speed")
    assert to_si("15 um", "length") == 15e-6  # decimal factors: the decimal result
