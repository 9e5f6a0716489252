"""Hard cases that must stay stable (the fast ones; the slow ones live in benchmarks/)."""

import numpy as np
import pytest

import femrub as fr
from femrub.model.build import ContactSpec, Load, first_order_model


@pytest.mark.parametrize("h", [5e-4, 1e-3, 5e-3])
def test_theta_coarse_steps_bounded(h):
    res = fr.ThetaMethod(fr.bar_model(alpha=3.0), h).run(0.4, limits={"tip_temperature": 1500})
    u, T = res.signal("tip_displacement"), res.signal("tip_temperature")
    assert res.status in ("ok", "diverged-physically")
    assert np.isfinite(u).all() and np.isfinite(T).all()
    assert np.abs(u).max() < 25e-6  # never beyond the free static amplitude (19.1 µm) by much
    assert 4e-3 - h <= res.first_contact_time() <= 5e-3 + h
    assert T.min() >= -1e-9 * T.max()  # maximum principle: friction only heats
    assert res.energy_error() < 1e-8
    assert abs(res.energy["heat_error"][-1]) < 1e-9 * res.energy["friction_heat"][-1]


@pytest.mark.parametrize("h,tol", [(5e-4, 0.15), (1e-3, 0.35)])
def test_theta_coarse_steps_temperature(h, tol):
    ref = fr.ThetaMethod(fr.bar_model(alpha=3.0), 1e-5).run(0.4, energy=False)
    res = fr.ThetaMethod(fr.bar_model(alpha=3.0), h).run(0.4, energy=False)
    T, Tr = res.signal("tip_temperature")[-1], ref.signal("tip_temperature")[-1]
    assert T == pytest.approx(Tr, rel=tol)


def test_grazing_contact():
    # gap equal to the peak static deflection 7 L / (E A) = 19.09 µm
    gap = 7.0 * 0.3 / (110e9 * 1e-6)
    res = fr.ThetaMethod(fr.bar_model(alpha=1.0, gap=gap), 1e-5).run(0.1)
    assert res.status == "ok"
    vmax = np.abs(res.signal("tip_velocity")).max()
    assert -res.gap.min() <= 1e-5 * vmax and -res.gap.min() < 1e-7  # grazing: tiny penetration
    assert res.force.max() < 2.0
    assert res.energy_error() < 1e-8


def test_chattering_and_long_closed_contact():
    # a large static preload holds the tip on the casing for most of the cycle
    res = fr.ThetaMethod(fr.bar_model(alpha=1.0, force_amplitude=50.0), 1e-5).run(0.06)
    closed = res.impulse[:, 0] > 0
    assert res.status == "ok" and closed.mean() > 0.4
    assert len(res.contact_phases()) > 5  # chattering at closure
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)
    # while a contact stays closed the gap is held (velocity-level constraint): after the
    # closing step of each run of closed steps the gap does not move
    edges = np.flatnonzero(np.diff(np.r_[0, closed.astype(int), 0]))
    runs = [(a, b) for a, b in zip(edges[::2], edges[1::2]) if b - a > 3]
    assert runs
    for a, b in runs:
        assert np.ptp(res.gap[a + 1 : b, 0]) < 1e-12


@pytest.mark.parametrize("gamma_thermal", [0.5, 1.0])
def test_stiff_heat_equation(gamma_thermal):
    # micrometre-long tip elements (grading 3) and a 1000x conductivity: stiff heat modes
    case = dict(alpha=3.0, conductivity=3.35e3, grading=3.0, n_elements=60, coupling="physical")
    model = fr.bar_model(**case)
    runs = [
        fr.ThetaMethod(model, h, gamma_thermal=gamma_thermal).run(
            0.1, limits={"tip_temperature": 1500}
        )
        for h in (1e-4, 2.5e-5, 1e-5)
    ]
    for res in runs:
        T = res.signal("tip_temperature")
        assert res.status == "ok" and np.isfinite(T).all() and T.max() < 50.0
        assert abs(res.energy["heat_error"][-1]) < 1e-9 * res.energy["friction_heat"][-1]
    T_end = [r.signal("tip_temperature")[-1] for r in runs]
    # converging in h: each coarse run within 6 % of the h = 1e-5 s one
    assert T_end[0] == pytest.approx(T_end[2], rel=0.06)
    assert T_end[1] == pytest.approx(T_end[2], rel=0.06)
    carp = fr.Carpenter(model, 1e-5)
    assert carp.stability_limit() < 1e-6  # explicit heat equation: tiny stable step
    out = carp.run(0.01)
    assert out.status == "unstable" and np.isfinite(out.signal("tip_temperature")).all()


def test_paper_coupling_refuses_graded_mesh():
    with pytest.raises(ValueError, match="uniform mesh"):
        fr.bar_model(grading=3.0)


def test_many_contacts_closing_at_once():
    mats, tip = fr.bar_matrices(fr.PAPER)
    n = mats.n_u
    f = np.zeros(n)
    f[tip] = 7.0
    static = np.linalg.solve(mats.K.toarray(), f)
    contact = ContactSpec(
        normals=np.eye(n), gap=0.8 * static, heat_dofs=np.arange(n), heat_coefficient=1.0
    )
    model = first_order_model(
        mats, contact=contact, loads=[Load(f, lambda t: np.sin(209.44 * t))], observe={}
    )
    res = fr.ThetaMethod(model, 1e-4).run(0.03)
    assert res.status == "ok"
    assert (res.impulse > 0).sum(axis=1).max() >= n // 2  # many contacts active in one step
    assert res.gap.min() > -1e-6 and res.energy_error() < 1e-8
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)
