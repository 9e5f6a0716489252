"""Coulomb friction: the per-step solver, analytic stick-slip cases, energy, outputs."""

import json

import numpy as np
import pytest
import scipy.sparse as sp

from femrub.analysis import Carpenter, Penalty, ThetaMethod
from femrub.contact.friction import SLIP, STICK, coulomb_check, solve_frictional_contact
from femrub.model.first_order import Contact, EnergyForms, FirstOrderModel, Layout, LoadTerm


def block_model(m=1.0, k=100.0, N=10.0, mu=0.3, v_belt=0.0, pull=None):
    """A mass on a rigid floor (gap z), pressed by ``N``, spring ``k`` along x to a wall;
    the floor (a belt) moves at ``v_belt`` along x; ``pull(t)`` is a force along x."""
    K = np.diag([k, 0.0, 0.0])
    M = m * np.eye(3)
    A = sp.block_diag([np.eye(3), M]).tocsc()
    B = sp.csc_matrix(np.block([[np.zeros((3, 3)), np.eye(3)], [-K, np.zeros((3, 3))]]))
    e = np.eye(6)
    press = -N * e[5]
    loads = [LoadTerm(press, 1.0, power=press.copy(), name="press")]
    if pull is not None:
        loads.append(LoadTerm(e[3], pull, power=e[3].copy(), name="pull"))
    contact = Contact(
        G=e[2][:, None],
        Gv=e[5][:, None],
        Hm=e[5][:, None],
        Ht=np.zeros((6, 1)),
        gap0=0.0,
        Gvt=e[:, [3, 4]],
        friction=mu,
        casing_velocity=[[v_belt, 0.0]],
        frames=np.array([[[0, 0, -1.0], [1.0, 0, 0], [0, 1.0, 0]]]),
    )
    Z = sp.csr_matrix((6, 6))
    energy = EnergyForms(
        Qk=sp.block_diag([np.zeros((3, 3)), M]).tocsr(),
        Qe=sp.block_diag([K, np.zeros((3, 3))]).tocsr(),
        Pth=Z,
        Pd=Z,
        heat_content=np.zeros(6),
        heat_outflow=np.zeros(6),
    )
    obs = {"x": sp.csr_matrix(e[[0]]), "vx": sp.csr_matrix(e[[3]])}
    return FirstOrderModel(
        A=A,
        B=B,
        layout=Layout(3, 3, 0),
        loads=loads,
        contact=contact,
        energy=energy,
        observations=obs,
    )


def _switches(res):
    st = res.contact_state[:, 0]
    ch = np.flatnonzero(np.diff(st)) + 1
    return res.t[ch], st[ch]


def test_solver_random_problems_satisfy_signorini_coulomb():
    rng = np.random.default_rng(1)
    for _ in range(300):
        n = int(rng.integers(1, 7))
        a = rng.normal(size=(3 * n, 3 * n))
        W = a @ a.T + 0.05 * np.eye(3 * n)
        q, mu = rng.normal(size=(n, 3)), rng.uniform(0.0, 1.0, n)
        r = solve_frictional_contact(W, q, mu, np.ones(n, dtype=bool))
        P, u = r.P, r.u
        assert np.all(P[:, 0] >= 0.0) and np.all(u[:, 0] >= -1e-10)
        assert np.all(np.abs(P[:, 0] * u[:, 0]) <= 1e-10)
        nt = np.linalg.norm(P[:, 1:], axis=1)
        assert np.all(nt <= mu * P[:, 0] * (1 + 1e-12))
        slip, stick = r.state == SLIP, r.state == STICK
        np.testing.assert_allclose(nt[slip], mu[slip] * P[slip, 0], rtol=1e-12)
        assert np.all(np.linalg.norm(u[stick, 1:], axis=1) <= 1e-10)
        ut = u[slip, 1:]
        cos = np.einsum("ij,ij->i", P[slip, 1:], ut) / (nt[slip] * np.linalg.norm(ut, axis=1))
        assert np.all(cos[nt[slip] > 0] <= -1 + 1e-8)


def test_solver_inactive_and_frictionless():
    W = np.diag([2.0, 1.0, 1.0, 3.0, 1.0, 1.0])
    q = np.array([[-1.0, 0.5, 0.0], [-3.0, 1.0, 0.0]])
    r = solve_frictional_contact(W, q, 0.0, np.array([True, False]))
    np.testing.assert_allclose(r.P, [[0.5, 0, 0], [0, 0, 0]])
    assert list(r.state) == [SLIP, 0]
    with pytest.raises(ValueError, match="Delassus"):
        solve_frictional_contact(np.eye(3), q, 0.1, [True, True])


@pytest.mark.parametrize("stepper", [ThetaMethod, Carpenter])
def test_mass_on_moving_belt_exact_stick_slip_sequence(stepper):
    """Slip from rest until v = v_b (t1), stick until k x = μ N (t2), then slip for ever
    (harmonic orbit touching v_b once a period)."""
    m, k, N, mu, vb, h = 1.0, 100.0, 10.0, 0.3, 0.1, 1e-4
    res = stepper(block_model(m, k, N, mu, vb), h).run(0.6)
    assert res.status == "ok"
    w, xs = np.sqrt(k / m), mu * N / k
    t1 = np.arcsin(vb * k / (mu * N * w)) / w
    t2 = t1 + (xs - xs * (1 - np.cos(w * t1))) / vb
    times, states = _switches(res)
    assert list(states) == [SLIP, STICK, SLIP]
    np.testing.assert_allclose(times, [h, t1, t2], atol=3 * h)
    first = res.t <= t1
    x = xs * (1 - np.cos(w * res.t[first]))
    np.testing.assert_allclose(res.signal("x")[first], x, atol=2e-3 * xs)
    stick = (res.t > t1 + 2 * h) & (res.t < t2 - 2 * h)
    np.testing.assert_allclose(res.signal("vx")[stick], vb, rtol=1e-9)
    # friction force while sticking balances the spring (mean over the step), |λ_t| < μ N
    ft = res.friction_force[stick, 0, 0]
    np.testing.assert_allclose(ft, k * res.signal("x")[stick], atol=k * vb * h)  # within a step
    assert np.all(np.abs(ft) < mu * N)


def test_block_pressed_and_dragged():
    """Pull F = c t: stick (λ_t = −F) below μ N, then slide with λ_t = −μ N exactly."""
    m, N, mu, c, h = 2.0, 50.0, 0.4, 100.0, 1e-4
    model = block_model(m, k=0.0, N=N, mu=mu, pull=lambda t: c * t)
    res = ThetaMethod(model, h).run(0.4)
    assert res.status == "ok"
    ts = mu * N / c  # 0.2 s
    ft = res.friction_force[:, 0, 0]
    stick = (res.t > h) & (res.t < ts - 2 * h)
    slide = res.t > ts + 2 * h
    assert np.all(res.contact_state[stick, 0] == STICK)
    assert np.all(res.contact_state[slide, 0] == SLIP)
    np.testing.assert_allclose(ft[stick], -c * (res.t[stick] - h / 2), rtol=1e-9)  # step mean
    np.testing.assert_allclose(ft[slide], -mu * N, rtol=1e-12)
    np.testing.assert_allclose(res.signal("vx")[stick], 0.0, atol=1e-12)
    # sliding: m a = c t − μ N, v = (c/2)(t − ts)² / m
    v = 0.5 * c * (res.t[slide] - ts) ** 2 / m
    np.testing.assert_allclose(res.signal("vx")[slide], v, rtol=2e-3, atol=1e-6)
    np.testing.assert_allclose(res.force[1:, 0], N, rtol=1e-12)
    # energy: dissipated = friction work = ∫ μ N v dt, and the balance closes
    e = res.energy
    assert res.energy_error() < 1e-10
    np.testing.assert_allclose(
        e["friction_work"][-1], e["external_work"][-1] - e["kinetic"][-1], rtol=1e-10
    )
    exact = mu * N * c / (6 * m) * (0.4 - ts) ** 3
    np.testing.assert_allclose(e["friction_work"][-1], exact, rtol=5e-3)
    check = coulomb_check(
        res.force, res.friction_force, res.slip_velocity, res.contact_state, res.friction_limit
    )
    assert check["cone"] <= 1e-12 and check["slip_equality"] <= 1e-12
    assert check["direction"] <= 1e-12


def test_friction_work_equals_dissipation_on_the_belt():
    res = ThetaMethod(block_model(v_belt=0.1), 1e-4).run(0.5)
    e = res.energy
    # the belt's work goes into the spring, the mass and the friction dissipation
    np.testing.assert_allclose(
        e["casing_work"][-1] - e["friction_work"][-1],
        e["kinetic"][-1] + e["elastic"][-1],
        rtol=1e-9,
    )
    assert np.all(np.diff(e["friction_work"]) >= -1e-15)


def test_penalty_refuses_friction():
    with pytest.raises(ValueError, match="no Coulomb friction"):
        Penalty(block_model(), 1e-4, stiffness=1e6)


def test_frictionless_single_contact_keeps_the_fast_path():
    assert not ThetaMethod(block_model(mu=0.0), 1e-4)._friction
    assert ThetaMethod(block_model(mu=0.0), 1e-4)._fast
    assert ThetaMethod(block_model(mu=0.2), 1e-4)._friction


def test_history_keys(tmp_path, monkeypatch):
    """The friction rows of ``history.npz`` and the summary's friction entries; the Coulomb
    check of the run's rows is measured once, for the verdict and the summary together."""
    import femrub.contact.friction as friction
    from femrub.output.run_folder import run_to_folder

    measured = []
    plain = friction.coulomb_check
    monkeypatch.setattr(friction, "coulomb_check", lambda *a: measured.append(1) or plain(*a))
    res = run_to_folder(ThetaMethod(block_model(v_belt=0.1), 1e-3), 0.1, tmp_path, plots=False)
    assert len(measured) == 1 and res.coulomb["slip_steps"] > 0
    with np.load(tmp_path / "history.npz") as d:
        n = res.steps + 1
        assert d["normal_force"].shape == (n, 1)
        assert d["friction_force"].shape == (n, 1, 3)
        assert d["slip_velocity"].shape == (n, 1, 3)
        assert set(np.unique(d["contact_state"])) <= {0, 1, 2}
    s = json.loads((tmp_path / "summary.json").read_text())
    for key in ("max_friction_force", "friction_work", "heat_to_blade", "heat_to_casing"):
        assert key in s
    assert s["max_friction_force"] == pytest.approx(3.0)
    assert s["coulomb_check"]["cone"] <= 1e-8


def test_energy_and_heat_balance_close_on_a_full_blade_model(monkeypatch, model_cache):
    """Twisted NACA blade, full model (no reduction), μ = 0.15, frictional heat on."""
    from femrub.app import build
    from femrub.scene import load_scene

    scene = load_scene(
        "twisted-naca",
        {
            "reduction.method": "none",
            "contact.friction": 0.15,
            "scheme.t_end": 8e-4,
            "outputs.vtk_stride": 0,
        },
    )
    res = build(scene, cache=model_cache).stepper.run(scene["scheme"]["t_end"])
    assert res.status == "ok" and res.force.max() > 0
    e = res.energy
    assert res.energy_error() < 1e-8 and res.heat_error() < 1e-10
    assert e["friction_work"][-1] > 0
    # η = 1: the blade takes the whole friction work
    np.testing.assert_allclose(e["friction_heat"][-1], e["friction_work"][-1], rtol=1e-9)
    check = coulomb_check(
        res.force, res.friction_force, res.slip_velocity, res.contact_state, res.friction_limit
    )
    assert check["cone"] <= 1e-8 and check["slip_equality"] <= 1e-8
    assert check["direction"] <= 1e-8  # the heat fixed point keeps the state on the law
    # checked a few rows at a time: the same verdict
    import femrub.contact.friction as friction

    monkeypatch.setattr(friction, "CHECK_ROWS", 7)
    rows = coulomb_check(
        res.force, res.friction_force, res.slip_velocity, res.contact_state, res.friction_limit
    )
    assert rows == check and check["slip_steps"] > 0 and len(res.t) > 7


def test_contacts_starting_inside_the_casing_warn_by_how_much():
    from femrub.app.build_warnings import initial_penetration, warn

    model = block_model()
    model.contact.gap0 = np.array([-3e-6])
    report = {}
    with pytest.warns(UserWarning, match=r"1 of 1 contacts start inside the casing.*3 um"):
        warn(initial_penetration(model), report)
    assert "3 um" in report["warnings"][0]
    model.contact.gap0 = np.array([1e-6])
    warn(initial_penetration(model), report := {})
    assert "warnings" not in report


def test_a_broken_coulomb_check_is_not_ok():
    from femrub.output.verdict import coulomb_message

    def _coulomb_violated(check):
        return coulomb_message(check, 1e-8) or ""

    good = {"cone": -0.5, "slip_equality": 1e-15, "direction": 0.0, "force_without_normal": 0.0}
    assert _coulomb_violated(good) == "" and _coulomb_violated(None) == ""
    assert "Coulomb law violated" in _coulomb_violated({**good, "cone": 1e-6})
    assert "Coulomb law violated" in _coulomb_violated({**good, "force_without_normal": 1.0})
