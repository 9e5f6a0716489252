"""The whole bladed disk and its casing ring in VTK frames (:mod:`femrub.output.wheel_vtk`).

The small 6-blade wheel and ring: the frames are readable by VTK and hold the whole wheel;
blade ``s``'s field is the sector field of sector ``s`` turned by ``R(sα)``; a static load at
one blade is drawn at that blade, and the same load at another blade is the same picture
turned; the casing's rotating-frame coordinates are drawn in its fixed frame (Eq. 2 of the
module), against the field of a wave set by hand.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.spatial import cKDTree
from small_wheel import STEEL, TITANIUM, N, disk_sector

from femrub.app.cli import main
from femrub.geometry.casing_ring import casing_ring_sector
from femrub.geometry.cyclic_sector import axis_rotation
from femrub.model.casing_waves import casing_waves
from femrub.model.cyclic import cyclic_structure, spinning
from femrub.model.wheel import WheelConfig, contact_rows_of_sector, tip_contacts, wheel_model
from femrub.output.wheel_vtk import WheelFields
from femrub.reduction.cyclic_ritz import cyclic_basis

SPEED = 1000.0  # rad/s
CLEARANCE = 2e-5  # m
REVOLUTION = 2 * math.pi / SPEED
ALPHA = 2 * math.pi / N


def _wheel(sector):
    """The tuned wheel at 1000 rad/s against the 3-lobed flexible ring, and its fields."""
    disk = spinning(cyclic_structure(sector, TITANIUM, prestress="linear"), TITANIUM, SPEED)
    contacts = tip_contacts(disk, 2)
    normal, tangent = contact_rows_of_sector(disk, contacts)
    basis = cyclic_basis(disk, 3, sp.vstack([normal, tangent]))
    tip_radius = sector.info["tip_radius"]
    ring = cyclic_structure(
        casing_ring_sector(N, tip_radius + CLEARANCE, 0.004, 0.03, h=0.01), STEEL
    )
    waves = casing_waves(ring, 2, contacts.points[0], tip_radius + CLEARANCE)
    config = WheelConfig(
        rotation_speed=SPEED,
        clearance=CLEARANCE,
        lobes=3,
        distortion=2e-4,
        friction=0.02,
        disk_damping=0.02,
        casing_damping=0.01,
        ramp=REVOLUTION,
    )
    model, wheel = wheel_model(
        config, disk, basis, contacts, waves, tip_radius=tip_radius, blade_size=0.03
    )
    return model, WheelFields(wheel, disk, ring, SPEED, 1.0)


@pytest.fixture(scope="module")
def sector():
    return disk_sector()


@pytest.fixture(scope="module")
def wheel(sector):
    return _wheel(sector)


def _frames(fields, model, part="rub", X=None, t=0.0):
    """Frame source ``part`` in double precision, and the compact fields of ``X`` at ``t``."""
    kind = fields.parts()[part]
    source = kind(fields, model, 1e-6, np.float64)
    if X is None:
        return source
    B = np.atleast_2d(X).shape[0]
    return source, source.compact(X, np.zeros((B, model.n_contacts)), times=np.full(B, t))


def _turned_sector_field(basis, structure, x, s, copies):
    """``R(sα) sector_field(x, s)`` at the sector's vertices (:meth:`CyclicBasis.sector_field`)."""
    full = np.zeros(structure.basis.N)
    full[structure.free] = basis.sector_field(x, s)
    local = full[structure.basis.nodal_dofs.T].reshape(-1, 3)
    return local @ axis_rotation(s * ALPHA).T


def test_disk_field_of_every_blade_is_the_sector_field_turned(wheel):
    model, fields = wheel
    disk = fields.wheel.disk
    rng = np.random.default_rng(4)
    X = np.zeros(model.layout.n)
    X[: disk.size] = rng.standard_normal(disk.size) * 1e-6
    v = model.layout.n_u
    X[v : v + disk.size] = rng.standard_normal(disk.size) * 1e-3
    source, c = _frames(fields, model, X=X[None])
    copies = source.map.copies
    assert source.map.n_points < copies.size  # the sectors' shared nodes merged
    scale = np.abs(c["displacement"]).max()
    for s in range(N):  # every vertex of copy s, its cyclic faces included
        expected = _turned_sector_field(disk, fields.disk, X[: disk.size], s, copies)
        got = c["displacement"][0, copies[s]]
        assert np.abs(got - expected).max() <= 1e-10 * scale
        rate = _turned_sector_field(disk, fields.disk, X[v : v + disk.size], s, copies)
        assert np.abs(c["velocity"][0, copies[s]] - rate).max() <= 1e-10 * np.abs(rate).max()
    # the whole mesh's vertices are the sector's turned
    p = fields.disk.sector.mesh.mesh.p
    for s in (1, 4):
        np.testing.assert_allclose(
            source.map.points[copies[s]].T, axis_rotation(s * ALPHA) @ p, atol=1e-12
        )


def test_static_load_at_one_blade_is_drawn_at_that_blade_and_turns_with_it(wheel):
    model, fields = wheel
    disk, contacts = fields.wheel.disk, fields.wheel.contacts
    normal, _ = contact_rows_of_sector(fields.disk, contacts)
    rows = disk.sector_rows(normal)  # (N, n_c, size)
    loads = np.stack([rows[s, 0] / disk.omega**2 for s in range(N)])  # unit load at blade s
    X = np.zeros((N, model.layout.n))
    X[:, : disk.size] = loads
    source, c = _frames(fields, model, X=X)
    u, copies = c["displacement"], source.map.copies
    per_blade = np.linalg.norm(u[0][copies], axis=-1).max(axis=1)  # (N,) largest in each copy
    assert per_blade.argmax() == 0
    assert per_blade[1:].max() < 0.05 * per_blade[0]
    # the load at blade j draws blade 0's picture turned by R(jα): N-fold symmetry
    for j in (1, 3):
        R = axis_rotation(j * ALPHA)
        turned = u[0][copies] @ R.T  # copy s of load 0 -> copy s + j of load j
        moved = u[j][np.roll(copies, -j, axis=0)]
        assert np.abs(moved - turned).max() <= 1e-9 * np.abs(u[0]).max()


def _one_wave(fields, k, c=1.0, d=0.0):
    """Rotating-frame casing coordinates with ``ζ = c + i d`` on the first vector of ``k``."""
    basis = fields.wheel.casing.basis
    zeta = np.zeros(basis.size)
    h, start, m, pair = next(b for b in basis.blocks() if b[0].k == k)
    zeta[start] = c
    if pair:
        zeta[start + m] = d
    return zeta


def test_casing_field_in_the_fixed_frame_is_the_wave_set_by_hand(wheel):
    model, fields = wheel
    waves = fields.wheel.casing
    n_disk = fields.wheel.n_disk
    k, t = 2, 0.37 * REVOLUTION
    theta = k * SPEED * t  # β t, σ = +1
    X = np.zeros(model.layout.n)
    X[n_disk : n_disk + waves.size] = _one_wave(fields, k, 0.3, -0.8)
    source, c = _frames(fields, model, "casing", X[None], t)
    # ξ = ζ e^{−iβt} by hand
    xi = (0.3 - 0.8j) * np.exp(-1j * theta)
    by_hand = _one_wave(fields, k, xi.real, xi.imag)
    scale = np.abs(c["displacement"]).max()
    assert scale > 0.0
    for s in range(N):
        expected = _turned_sector_field(waves.basis, fields.ring, by_hand, s, source.map.copies)
        got = c["displacement"][0, source.map.copies[s]]
        assert np.abs(got - expected).max() <= 1e-10 * scale


def test_casing_velocity_in_the_fixed_frame_is_the_rate_of_its_displacement(wheel):
    """``ξ̇ = (ζ̇ − iβζ) e^{−iβt}`` (Eq. 2): the velocity drawn is the central difference of
    the displacements drawn at ``t ± δ`` for ``ζ(t) = ζ_0 + (t − t_0) ζ̇``."""
    model, fields = wheel
    n_disk, n_casing, v = fields.wheel.n_disk, fields.wheel.n_casing, model.layout.n_u
    rng = np.random.default_rng(7)
    zeta, rate = rng.standard_normal(n_casing), 300.0 * rng.standard_normal(n_casing)
    t0, delta = 0.29 * REVOLUTION, 1e-7
    X = np.zeros((3, model.layout.n))
    for i, dt in enumerate((0.0, -delta, delta)):
        X[i, n_disk : n_disk + n_casing] = zeta + dt * rate
        X[i, v + n_disk : v + n_disk + n_casing] = rate
    source = _frames(fields, model, "casing")
    c = source.compact(X, None, times=t0 + np.array([0.0, -delta, delta]))
    u = c["displacement"]
    difference = (u[2] - u[1]) / (2 * delta)
    scale = np.abs(c["velocity"][0]).max()
    assert np.abs(c["velocity"][0] - difference).max() <= 1e-6 * scale
    still = source.fixed(zeta[None], [t0], np.zeros((1, n_casing)))  # ζ̇ = 0: ξ̇ = −iβξ
    assert np.abs(still).max() > 0.0


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_a_wave_still_in_the_rotor_turns_with_it_in_the_casing_frame(wheel, direction):
    """Constant rotating-frame coordinates are a pattern carried by the rotor: after one
    sector's turn ``α / Ω`` the casing's fixed-frame field is the first one turned by
    ``R(σα)``; its velocity is ``−σΩ`` times its derivative along the circumference."""
    model, fields = wheel
    fields = replace(fields, direction=direction)  # the drawing's σ: the model's is not read
    n_disk = fields.wheel.n_disk
    X = np.zeros(model.layout.n)
    X[n_disk : n_disk + fields.wheel.n_casing] = (
        _one_wave(fields, 1, 1.0, 0.5) + _one_wave(fields, 2, -0.2, 0.7) + _one_wave(fields, 0, 0.4)
    )
    source = _frames(fields, model, "casing")
    times = np.array([0.0, ALPHA / SPEED])
    c = source.compact(np.stack([X, X]), None, times=times)
    u0, u1, copies = c["displacement"][0], c["displacement"][1], source.map.copies
    step = int(direction)
    R = axis_rotation(direction * ALPHA)
    assert (
        np.abs(u1[np.roll(copies, -step, axis=0)] - u0[copies] @ R.T).max()
        <= 1e-10 * np.abs(u0).max()
    )


def _symmetry_error(frame, turn: float) -> float:
    """Largest ``|u(R p) − R u(p)|`` over the vertices ``p`` of ``frame`` (``R = R(turn)``),
    relative to the largest displacement: 0 for a field with that symmetry."""
    R = axis_rotation(turn)
    dist, image = cKDTree(frame.points).query(frame.points @ R.T)
    assert dist.max() < 1e-9
    u = frame.point_data["displacement"].astype(float)
    return np.abs(u[image] - u @ R.T).max() / np.abs(u).max()


def _read(path):
    """A frame read by VTK (pyvista). meshio 5.3 misreads raw appended data whose base64
    length up to one array equals the raw offset of a later one (it looks arrays up by
    offset while rewriting the offsets): the rotor's frames of this wheel hit it."""
    import pyvista

    return pyvista.read(path)


def test_run_of_a_wheel_scene_writes_the_whole_wheel_and_its_casing(tmp_path):
    """Half a revolution of the tuned 6-blade wheel against its 3-lobed ring (the lobes
    ramped in over an eighth of a revolution), a frame every 150 steps: both series are
    readable, every frame holds the whole structure, and the response, the same on blades
    a lobe apart, is drawn 3-fold symmetric on the rotor and on the casing; the contact
    and friction forces drawn are those of the frame's step."""
    from test_wheel_scene import WHEEL

    stride, h = 150, REVOLUTION / 1500
    scene = WHEEL.replace(f"t_end = {3 * REVOLUTION!r}", f"t_end = {REVOLUTION / 2!r}")
    scene = scene.replace("[outputs]", f"[outputs]\nvtk_stride = {stride}")
    scene = scene.replace("families = 2\n", f"families = 2\nramp = {REVOLUTION / 8!r}\n")
    path = tmp_path / "wheel6.toml"
    path.write_text(scene)
    out = tmp_path / "run"
    assert main(["run", str(path), "-o", str(out), "-q"]) in (0, 1)
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] in ("ok", "inaccurate"), s["message"]
    assert s["steps"] == 750 and s["vtk"] == "vtk/rub.pvd" and s["vtk_frames"] == 6
    with np.load(out / "history.npz") as history:
        impulses = history["impulse"][::stride]  # at the frames' steps
        friction = history["friction_force"][::stride]  # (frames, contacts, 3), global axes
    touched = int(impulses.sum(axis=1).argmax())
    assert impulses[touched].sum() > 0.0
    for name in ("rub", "casing"):
        pvd = (out / "vtk" / f"{name}.pvd").read_text()
        assert "femrub units: displacement [m], velocity [m/s]" in pvd
        files = re.findall(r'file="([^"]+)"', pvd)
        times = [float(x) for x in re.findall(r'timestep="([^"]+)"', pvd)]
        assert files == [f"{name}_{i:06d}.vtu" for i in range(6)]
        assert times == pytest.approx(np.arange(6) * stride * h)
        first, frame = (_read(out / "vtk" / f) for f in (files[0], files[touched]))
        assert np.abs(first.point_data["displacement"]).max() == 0.0  # the initial state
        assert first.points.shape == frame.points.shape == frame.point_data["velocity"].shape
        assert _symmetry_error(frame, 2 * ALPHA) < 1e-5  # blades a lobe apart alike
        if name == "rub":  # but not neighbours (the ring's waves of 1 and 2 diameters have
            # no 3-fold part: its response to 3-fold forces is the round k = 0 one)
            assert _symmetry_error(frame, ALPHA) > 1e-2
    rotor = _read(out / "vtk" / f"rub_{touched:06d}.vtu")
    radius = np.hypot(rotor.points[:, 1], rotor.points[:, 2])
    angles = np.arctan2(-rotor.points[:, 1], rotor.points[:, 2])
    assert radius.min() == pytest.approx(0.02, rel=1e-6)  # the bore of the whole disk
    assert np.ptp(angles) > 2 * math.pi * 0.99  # all the way round
    assert np.abs(rotor.point_data["static_displacement"]).max() > 0.0
    # friction heats the blades (physics.thermal "auto"): their temperature is drawn, hottest
    # at the tips, 3-fold symmetric as the rest
    hot = rotor.point_data["temperature"].ravel()
    assert hot.max() > 0.0 and radius[hot.argmax()] > 0.045
    assert "temperature [K]" in (out / "vtk" / "rub.pvd").read_text()
    normal = np.linalg.norm(rotor.point_data["contact_force"], axis=1)
    assert normal.sum() == pytest.approx(impulses[touched].sum() / h, rel=1e-5)
    tangent = rotor.point_data["friction_force"]
    scale = np.linalg.norm(friction[touched], axis=1).sum()
    assert np.linalg.norm(tangent, axis=1).sum() == pytest.approx(scale, rel=1e-5)
    np.testing.assert_allclose(
        tangent.sum(axis=0), friction[touched].sum(axis=0), rtol=0, atol=1e-6 * scale
    )
    slipping = np.linalg.norm(tangent, axis=1)[normal > 0] / normal[normal > 0]
    assert slipping.max() == pytest.approx(0.02, rel=1e-5)  # μ, on the same vertices
