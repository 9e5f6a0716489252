"""Exponential Moreau stepper: exact flight, energy, several contacts, bad input."""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from test_energy import _free_vibration
from test_multicontact import _two_contact_bar

import femrub as fr
from femrub.model.first_order import Layout, LoadTerm
from femrub.steppers.exponential import MAX_COORDINATES


def _free_model():
    """The paper bar without contact, a quadratic load signal and a non-zero start."""
    m = fr.bar_model(alpha=3.0)
    f = m.loads[0].vector
    load = LoadTerm(f, lambda t: 1.0 + 30.0 * t - 400.0 * t**2, np.zeros(m.n_dofs))
    x0 = np.zeros(m.n_dofs)
    x0[m.layout.u] = 1e-6 * np.linspace(0, 1, m.layout.n_u)
    x0[m.layout.t] = 5.0
    return m.with_(contact=None, loads=[load], x0=x0)


def _exact(m, T):
    """``X(T)`` from one augmented exponential over [0, T] (independent of the stepper)."""
    A, B = m.A.toarray(), m.B.toarray()
    L, G = np.linalg.solve(A, B), np.linalg.solve(A, m.loads[0].vector)[:, None]
    n = m.n_dofs
    M = np.zeros((n + 3, n + 3))
    M[:n, :n], M[:n, n : n + 1] = T * L, T * G
    M[n, n + 1] = M[n + 1, n + 2] = 1.0
    w = np.array([1.0, 30.0 * T, -2.0 * 400.0 * T**2])  # s(Tσ) = Σ w_i σ^i / i!
    return sla.expm(M)[:n] @ np.r_[m.x0, w]


@pytest.mark.parametrize("h", [1e-5, 1e-3, 0.02])
def test_contact_free_model_is_exact_at_any_step(h):
    m, T = _free_model(), 0.04
    st = fr.ExponentialMoreau(m, h, load_degree=2)
    for _ in range(st.steps_to(T)):
        st.step()
    ref = _exact(m, T)
    assert np.max(np.abs(st.X - ref)) <= 1e-10 * np.max(np.abs(ref))


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_energy_never_increases(e):
    res = fr.ExponentialMoreau(_free_vibration(e), 2e-5).run(0.05)
    E = res.energy["kinetic"] + res.energy["elastic"]
    assert len(res.contact_phases()) >= 5
    assert np.all(np.diff(E) <= 1e-12 * E[0])
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)
    assert res.energy_error() < 1e-9
    if e in (0.0, 1.0):  # impulses at located contact times: no penetration (e in (0, 1):
        assert res.gap.min() > -1e-12  # bounces accumulate, later ones get step-end impulses)


def test_elastic_impacts_conserve_energy_at_coarse_steps():
    # exact flight: the step size does not matter (the θ-method needs 2e-5 s here)
    res = fr.ExponentialMoreau(_free_vibration(1.0), 5e-4).run(0.05)
    E = res.energy["kinetic"] + res.energy["elastic"]
    assert len(res.contact_phases()) >= 5
    assert np.max(np.abs(E / E[0] - 1)) < 1e-9


def test_inelastic_impacts_dissipate():
    res = fr.ExponentialMoreau(_free_vibration(0.0), 2e-5).run(0.05)
    E = res.energy["kinetic"] + res.energy["elastic"]
    assert E[-1] < 0.99 * E[0]
    assert res.energy["impact_dissipation"][-1] == pytest.approx(E[0] - E[-1], rel=1e-8)


def test_several_contacts_lcp_and_heat():
    model = _two_contact_bar()
    res = fr.ExponentialMoreau(model, 1e-4).run(0.1)
    assert res.status == "ok"
    assert np.all(res.impulse >= 0.0)
    both = np.sum(np.all(res.impulse > 0, axis=1))
    assert both > 10  # both contacts loaded in the same step
    assert res.gap.min() > -1e-12
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)
    e = res.energy  # frictional heat is α times the impulses (α = 2 m/s)
    assert e["friction_heat"][-1] == pytest.approx(2.0 * res.impulse.sum(), rel=1e-12)
    assert np.max(np.abs(e["heat_error"])) < 1e-3 * e["friction_heat"][-1]
    # converged in h: the coarse step agrees with a ten times finer one
    fine = fr.ExponentialMoreau(model, 1e-5).run(0.1, energy=False)
    assert res.impulse.sum(axis=0) == pytest.approx(fine.impulse.sum(axis=0), rel=1e-6)


@pytest.mark.parametrize("h", [1e-3, 1e-4])
def test_energy_balance_closes_with_heat_entering_inside_steps(h):
    # the stepper integrates the works and heats on its exact flights
    # (steppers/exponential/work.py):
    # the balance closes to round-off at any step, however many events fall inside one
    res = fr.ExponentialMoreau(_two_contact_bar(), h).run(0.1)
    assert res.status == "ok"
    assert res.energy_error() < 1e-9 and res.heat_error() < 1e-9
    assert res.energy["thermal_work"][-1] != 0.0 and res.energy["external_work"][-1] != 0.0
    # without the balance the works are not integrated; the flight is the same to round-off
    quiet = fr.ExponentialMoreau(_two_contact_bar(), h).run(0.1, energy=False)
    assert quiet.impulse.sum(axis=0) == pytest.approx(res.impulse.sum(axis=0), rel=1e-9)
    assert quiet.energy == {} and np.abs(quiet.gap - res.gap).max() < 1e-9 * np.abs(res.gap).max()


def test_paper_case_coarse_step_and_first_contact():
    model = fr.bar_model(alpha=3.0)
    coarse = fr.ExponentialMoreau(model, 1e-3).run(0.1)
    fine = fr.ExponentialMoreau(model, 1e-4).run(0.1, energy=False)
    T = coarse.signals["tip_temperature"][-1, 0]
    assert coarse.status == "ok" and coarse.energy_error() < 1e-9
    assert T == pytest.approx(fine.signals["tip_temperature"][-1, 0], rel=1e-4)
    theta = fr.ThetaMethod(model, 1e-5).run(0.01, energy=False)
    # the impulse of the step holding the first contact: exact to one step
    assert abs(coarse.first_contact_time() - theta.first_contact_time()) <= 1e-3


def test_make_stepper_and_scene_key():
    st = fr.make_stepper("exponential", fr.bar_model(), 1e-4, events=False)
    assert isinstance(st, fr.ExponentialMoreau) and st.events is False


def test_bad_input():
    m = fr.bar_model()
    n = MAX_COORDINATES + 1
    big = fr.FirstOrderModel(sp.identity(n), sp.identity(n), Layout(n, 0, 0))
    with pytest.raises(ValueError, match="reduce it first"):
        fr.ExponentialMoreau(big, 1e-4)
    with pytest.raises(ValueError, match="time step"):
        fr.ExponentialMoreau(m, -1.0)
    with pytest.raises(ValueError, match="events"):
        fr.ExponentialMoreau(m, 1e-4, events="yes")
    with pytest.raises(ValueError, match="probes"):
        fr.ExponentialMoreau(m, 1e-4, probes=0)
    with pytest.raises(ValueError, match="load_degree"):
        fr.ExponentialMoreau(m, 1e-4, load_degree=0)
    with pytest.raises(TypeError):
        fr.ExponentialMoreau("model", 1e-4)


def test_load_polynomials_of_a_block_are_those_of_each_step():
    # the paper bar's sine load takes arrays: BLOCK steps' polynomials come from one call
    from femrub.steppers.exponential.loads import BLOCK

    st = fr.ExponentialMoreau(fr.bar_model(alpha=3.0), 1e-4)
    loads = st._loads
    assert all(loads._vector) and loads.n_s == 1
    for k in (0, 1, BLOCK - 1, BLOCK, BLOCK + 5):
        t = st.t0 + k * st.h
        loads.sk = loads.values(t)
        s0 = loads.sk.copy()
        b = loads.poly(t).copy()
        assert len(loads._blocks) == BLOCK and np.array_equal(loads._blocks[t][1], b)  # a block's
        end = loads.sk.copy()
        loads.sk = s0
        assert b == pytest.approx(loads._step_poly(t), rel=1e-14, abs=1e-14)
        assert end == pytest.approx(loads.sk, rel=1e-15, abs=0.0)
        loads.sk = s0  # the same step again (a slide's second pass): the same polynomial
        assert np.array_equal(loads.poly(t), b)
