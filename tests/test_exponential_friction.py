"""Coulomb friction in the exponential stepper: hand-derived cases, energy, θ agreement."""

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import brentq
from test_friction import block_model

import femrub as fr
from femrub.contact.friction import SLIP, coulomb_check
from femrub.model.first_order import Contact, EnergyForms, FirstOrderModel, Layout, LoadTerm


def belt_model(  # noqa: PLR0913 (the belt's parameters, all with defaults)
    n=1,
    m=2.0,
    N=20.0,
    mu=0.3,
    v_belt=10.0,
    eta=0.6,
    gap=1e-3,
    k=0.0,
    kz=0.0,
    couple=0.0,
    e=0.0,
    C=5.0,
    law="power",
    alpha=0.0,
    ky=0.0,
    vy=0.0,
):
    """``n`` point masses (x, y, z each) with a lumped temperature each, pressed by ``N``
    onto a belt (gap ``gap``) moving at ``v_belt`` along x: friction μ, heat law ``law``
    (η of the friction power, or α λ), springs ``k`` along x to a wall, ``ky`` along y and
    ``kz`` along z, neighbours coupled along x by ``couple``; initial velocity ``vy`` along y
    (across the belt)."""
    nu, nt = 3 * n, n
    K = np.zeros((nu, nu))
    for i in range(n):
        K[3 * i, 3 * i] += k
        K[3 * i + 1, 3 * i + 1] += ky
        K[3 * i + 2, 3 * i + 2] += kz
        if i + 1 < n and couple:
            a, b = 3 * i, 3 * i + 3
            K[np.ix_([a, b], [a, b])] += couple * np.array([[1.0, -1.0], [-1.0, 1.0]])
    M = m * np.eye(nu)
    A = sp.block_diag([np.eye(nu), M, C * np.eye(nt)]).tocsc()
    B = np.zeros((2 * nu + nt, 2 * nu + nt))
    B[:nu, nu : 2 * nu] = np.eye(nu)
    B[nu : 2 * nu, :nu] = -K
    I = np.eye(2 * nu + nt)
    vz = [nu + 3 * i + 2 for i in range(n)]
    press = -N * I[vz].sum(axis=0)
    loads = [LoadTerm(press, 1.0, power=press.copy(), name="press")]
    tang = np.column_stack([I[:, nu + 3 * i + j] for i in range(n) for j in (0, 1)])
    frame = [[0, 0, -1.0], [1.0, 0, 0], [0, 1.0, 0]]
    contact = Contact(
        G=I[:, [3 * i + 2 for i in range(n)]],
        Gv=I[:, vz],
        Hm=I[:, vz],
        Ht=I[:, 2 * nu : 2 * nu + nt],
        gap0=gap,
        restitution=e,
        Gvt=tang,
        friction=mu,
        casing_velocity=[[v_belt, 0.0]] * n,
        frames=np.array([frame] * n),
        heat_law=law,
        heat_partition=eta,
        heat_coefficient=alpha,
    )
    heat = np.r_[np.zeros(2 * nu), C * np.ones(nt)]
    energy = EnergyForms(
        Qk=sp.csr_matrix(sp.block_diag([np.zeros((nu, nu)), M, np.zeros((nt, nt))])),
        Qe=sp.csr_matrix(sp.block_diag([K, np.zeros((nu + nt, nu + nt))])),
        Pth=sp.csr_matrix((2 * nu + nt,) * 2),
        Pd=sp.csr_matrix((2 * nu + nt,) * 2),
        heat_content=heat,
        heat_outflow=np.zeros(2 * nu + nt),
    )
    obs = {"x": sp.csr_matrix(I[[0]]), "vx": sp.csr_matrix(I[[nu]]), "y": sp.csr_matrix(I[[1]])}
    x0 = np.zeros(2 * nu + nt)
    x0[[nu + 3 * i + 1 for i in range(n)]] = vy
    return FirstOrderModel(
        A=A,
        B=B.copy(),
        layout=Layout(nu, nu, nt),
        loads=loads,
        contact=contact,
        energy=energy,
        observations=obs,
        x0=x0,
    )


def test_impact_then_slide_on_a_fast_belt_matches_the_hand_solution():
    """A mass dropped on a belt (e = 0): the impact P_n = m v_i takes P_t = μ P_n along the
    belt (sliding), then the held contact slides with λ_t = μ N; heat = η × friction work,
    η μ P_n (v_b − μ v_i / 2) at the impact and η μ N (v_b − v_x) while held. Exact at a
    step of 0.01 s (the impact inside a step)."""
    m, N, mu, vb, eta, d, T, h = 2.0, 20.0, 0.3, 10.0, 0.6, 1e-3, 0.2, 0.01
    model = belt_model(m=m, N=N, mu=mu, v_belt=vb, eta=eta, gap=d)
    st = fr.ExponentialMoreau(model, h)
    res = st.run(T)
    assert res.status == "ok" and st._S == (0,)
    ti = np.sqrt(2 * d * m / N)
    vi = N / m * ti
    Pn = m * vi
    s = T - ti
    vx = mu * vi + mu * N / m * s
    x = mu * vi * s + 0.5 * mu * N / m * s**2
    work = mu * Pn * (vb - mu * vi / 2) + mu * N * (vb * s - mu * vi * s - 0.5 * mu * N / m * s**2)
    assert res.signal("x")[-1] == pytest.approx(x, rel=1e-9)
    assert res.signal("vx")[-1] == pytest.approx(vx, rel=1e-9)
    assert res.impulse.sum() == pytest.approx(Pn + N * s, rel=1e-9)
    Pt = res.friction_force[:, 0] * h  # per step, global axes: along the belt (+x)
    np.testing.assert_allclose(Pt[:, 0], mu * res.impulse[:, 0], rtol=1e-12, atol=1e-15)
    assert np.all(np.abs(Pt[:, 1:]) == 0.0)
    assert np.all(res.contact_state[res.impulse[:, 0] > 0, 0] == SLIP)
    e = res.energy
    assert e["friction_work"][-1] == pytest.approx(work, rel=1e-9)
    assert e["friction_heat"][-1] == pytest.approx(eta * work, rel=1e-9)
    assert 5.0 * st.X[-1] == pytest.approx(eta * work, rel=1e-9)  # C θ: the heat entered
    assert res.energy_error() < 1e-10 and res.heat_error() < 1e-12


@pytest.mark.parametrize("law", ["power", "alpha"])
@pytest.mark.parametrize("e", [0.0, 1.0])
def test_energy_balance_with_friction_closes_and_creates_nothing(e, law):
    """A mass on a vertical spring bouncing on (e = 1) or sticking to (e = 0) a belt, and
    sliding along x on a spring: every impact and held flight dissipates (impact and
    friction work >= 0), the balance closes to round-off, heat = η × friction work
    ("power") or α P_n ("alpha")."""
    model = belt_model(
        m=1.0, N=5.0, mu=0.2, v_belt=3.0, gap=2e-3, k=50.0, kz=400.0, e=e, law=law, alpha=0.7
    )
    res = fr.ExponentialMoreau(model, 2e-3).run(0.5)
    assert res.status == "ok"
    en = res.energy
    assert np.count_nonzero(res.impulse[:, 0]) >= 5
    assert res.energy_error() < 1e-11 and res.heat_error() < 1e-11
    assert np.all(np.diff(en["impact_dissipation"]) >= -1e-14)
    assert np.all(np.diff(en["friction_work"]) >= -1e-14) and en["friction_work"][-1] > 0
    if e == 1.0:  # an elastic impact: no normal work (decoupled tangent)
        assert abs(en["impact_dissipation"][-1]) < 1e-12 * en["friction_work"][-1]
    if law == "power":
        assert en["friction_heat"][-1] == pytest.approx(0.6 * en["friction_work"][-1], rel=1e-10)
    else:
        assert en["friction_heat"][-1] == pytest.approx(0.7 * res.impulse.sum(), rel=1e-10)
    # the mechanical energy change is the belt's work less what contact dissipated
    E = en["kinetic"] + en["elastic"]
    lost = en["impact_dissipation"] + en["friction_work"]
    np.testing.assert_allclose(
        E[-1] - E[0], en["external_work"][-1] + en["casing_work"][-1] - lost[-1], rtol=1e-9
    )


def test_a_held_slide_that_sticks_is_refused_at_the_exact_time():
    """Mass on a slow belt with a spring (test_friction's stick-slip), landing from 1 µm: the
    impact slides (P_t = μ P_n), the held slide is the exact harmonic
    ``x = x_s (1 − cos ωs) + (μ v_i / ω) sin ωs`` until the mass reaches the belt's speed at
    t1; there the slip along the belt stops (located as an event) and the run is refused
    (no held stick), its results kept up to t1."""
    m, k, N, mu, vb, h, d = 1.0, 100.0, 10.0, 0.3, 0.1, 1e-3, 1e-6
    model = block_model(m, k, N, mu, vb)
    model.contact.gap0 = np.array([d])
    w, xs = np.sqrt(k / m), mu * N / k
    ti = np.sqrt(2 * d * m / N)
    vi = N / m * ti

    def x_slide(t):
        s = t - ti
        return xs * (1 - np.cos(w * s)) + mu * vi / w * np.sin(w * s)

    t1 = brentq(
        lambda t: xs * w * np.sin(w * (t - ti)) + mu * vi * np.cos(w * (t - ti)) - vb,
        ti,
        ti + 0.5 * np.pi / w,
    )
    res = fr.ExponentialMoreau(model, h).run(0.6)
    assert res.status == "failed" and "stops sliding" in res.message
    t_msg = float(res.message.split("t = ")[1].split(" s")[0])
    assert t_msg == pytest.approx(t1, rel=1e-8)
    assert t1 - h <= res.t[-1] < t1
    assert np.all(res.contact_state[res.t > ti, 0] == SLIP)
    x = res.signal("x")[res.t > ti]
    np.testing.assert_allclose(x, x_slide(res.t[res.t > ti]), rtol=1e-9)
    assert res.energy_error() < 1e-10
    # without event location the stop is found at the step end after t1
    model.contact.gap0 = np.array([d])
    res = fr.ExponentialMoreau(model, h, events=False).run(0.6)
    assert res.status == "failed" and "stops sliding" in res.message
    t_msg = float(res.message.split("t = ")[1].split(" s")[0])
    assert t1 <= t_msg < t1 + h


def test_a_held_slide_follows_its_slip_across_the_belt():
    """A mass pressed on a belt (2 m/s along x) oscillating across it (a spring along y, 0.5
    m/s at the start): the slip turns by up to a quarter radian, and the friction of the held
    contact follows it (the direction of each step fixed on its end slip). Coulomb's direction
    check holds within the verdict's bound (status ok), the transverse motion, damped by
    friction, agrees with a fine θ step, and the balances close to round-off."""
    model = belt_model(m=1.0, N=10.0, mu=0.3, v_belt=2.0, gap=0.0, ky=400.0, vy=0.5)
    T = 0.1
    ex = fr.ExponentialMoreau(model, 5e-4).run(T)
    th = fr.ThetaMethod(model, 1e-5).run(T)
    assert ex.status == "ok" and th.status == "ok"
    check = coulomb_check(
        ex.force, ex.friction_force, ex.slip_velocity, ex.contact_state, ex.friction_limit
    )
    assert check["slip_steps"] == 200
    assert check["direction"] < 1e-9 and check["slip_equality"] < 1e-9
    w = ex.slip_velocity[:, 0]
    assert np.max(np.abs(np.arctan2(w[:, 1], w[:, 0]))) > 0.2  # the slip turns
    y_th = np.interp(ex.t, th.t, th.signal("y"))
    scale = np.max(np.abs(y_th))
    assert np.max(np.abs(ex.signal("y") - y_th)) < 2e-3 * scale
    assert ex.energy_error() < 1e-11 and ex.heat_error() < 1e-11
    en = ex.energy
    assert en["friction_heat"][-1] == pytest.approx(0.6 * en["friction_work"][-1], rel=1e-10)


@pytest.mark.parametrize("n", [2, 3])
def test_several_contacts_agree_with_the_theta_method(n):
    """Masses coupled by springs along x, each dropped on the belt from its own height
    (impacts at different times inside the coarse steps), several held sliding contacts:
    the exponential stepper at h = 5e-3 s agrees with the θ-method at 1e-5 s."""
    model = belt_model(
        n=n,
        m=1.0,
        N=10.0,
        mu=0.25,
        v_belt=5.0,
        k=80.0,
        couple=150.0,
        gap=np.linspace(1e-3, 3e-3, n),
        kz=300.0,
    )
    T = 0.1
    ex = fr.ExponentialMoreau(model, 5e-3).run(T)
    th = fr.ThetaMethod(model, 1e-5).run(T)
    assert ex.status == "ok" and th.status == "ok"
    assert ex.energy_error() < 1e-10 and ex.heat_error() < 1e-10
    x_th = np.interp(ex.t, th.t, th.signal("x"))
    scale = np.max(np.abs(th.signal("x")))
    assert np.max(np.abs(ex.signal("x") - x_th)) < 1e-4 * scale
    assert ex.impulse.sum() == pytest.approx(th.impulse.sum(), rel=1e-4)
    for key in ("friction_work", "friction_heat"):
        assert ex.energy[key][-1] == pytest.approx(th.energy[key][-1], rel=1e-4)


def test_bad_input():
    """Friction on a casing at rest has no slip direction for held contacts: refused."""
    with pytest.raises(ValueError, match="casing at rest"):
        fr.ExponentialMoreau(block_model(v_belt=0.0), 1e-3)
    # a landing that sticks at once (μ P_n beyond the belt's speed) cannot start a hold
    model = belt_model(m=1.0, N=10.0, mu=0.9, v_belt=0.01, gap=1e-3)
    res = fr.ExponentialMoreau(model, 1e-3).run(0.05)
    assert res.status == "failed" and "stops sliding" in res.message
    t_msg = float(res.message.split("t = ")[1].split(" s")[0])
    assert t_msg == pytest.approx(np.sqrt(2e-3 / 10.0), rel=1e-8)  # the landing time
    # frictionless contacts on a resting casing are still held
    st = fr.ExponentialMoreau(block_model(mu=0.0, v_belt=0.0), 1e-3)
    assert st.run(0.01).status == "ok" and st._S == (0,)
