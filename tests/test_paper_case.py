"""The θ-method and Carpenter's scheme on the paper case (model notes, paper Sec. 4)."""

import numpy as np
import pytest

import femrub as fr

T_END = 0.4
ALPHA = 3.0


@pytest.fixture(scope="module")
def runs():
    model = fr.bar_model(alpha=ALPHA)
    out = {("theta", h): fr.ThetaMethod(model, h).run(T_END) for h in (1e-5, 1e-4, 5e-4)}
    out[("carpenter", 1e-5)] = fr.Carpenter(model, 1e-5).run(T_END)
    return out


def _rel_l2(res, ref, name="tip_displacement"):
    y = np.interp(ref.t, res.t, res.signal(name))
    r = ref.signal(name)
    return np.sqrt(np.mean((y - r) ** 2)) / np.sqrt(np.mean(r**2))


def test_first_contact_after_4ms(runs):
    # paper Sec. 4.3: "the first time step after 4 ms"; the static deflection (19.1 µm)
    # exceeds the gap (15 µm), so the first contact happens in the first load quarter
    ref = runs[("theta", 1e-5)].first_contact_time()
    assert 4.0e-3 < ref < 5.0e-3
    for res in runs.values():
        assert abs(res.first_contact_time() - ref) <= 1.5 * res.h


def test_theta_and_carpenter_agree_at_1e_5(runs):
    th, ca = runs[("theta", 1e-5)], runs[("carpenter", 1e-5)]
    assert th.status == ca.status == "ok"
    assert abs(th.first_contact_time() - ca.first_contact_time()) <= 2e-5
    assert _rel_l2(ca, th) < 0.05
    assert _rel_l2(ca, th, "tip_temperature") < 0.03
    assert ca.signal("tip_temperature")[-1] == pytest.approx(
        th.signal("tip_temperature")[-1], rel=0.03
    )


@pytest.mark.parametrize("h,tol_u,tol_T", [(1e-4, 0.08, 0.10), (5e-4, 0.10, 0.10)])
def test_theta_coarse_steps_stay_close(runs, h, tol_u, tol_T):
    ref, res = runs[("theta", 1e-5)], runs[("theta", h)]
    assert res.status == "ok"
    assert _rel_l2(res, ref) < tol_u
    T, Tref = res.signal("tip_temperature")[-1], ref.signal("tip_temperature")[-1]
    assert T == pytest.approx(Tref, rel=tol_T)
    assert res.force.max() == pytest.approx(ref.force.max(), rel=0.5)


def test_coupling_raises_temperature_and_force(runs):
    unc = fr.ThetaMethod(fr.bar_model(alpha=ALPHA, coupling="none"), 1e-4).run(T_END)
    cou = runs[("theta", 1e-4)]
    assert cou.signal("tip_temperature")[-1] > 5 * unc.signal("tip_temperature")[-1]
    assert cou.force.max() > 5 * unc.force.max()
    # uncoupled: the contact force is periodic (paper Sec. 4.1)
    period = int(round(2 * np.pi / fr.PAPER.force_frequency / 1e-4))
    f = unc.force[:, 0]
    assert np.max(f[-period:]) == pytest.approx(np.max(f[-2 * period : -period]), rel=0.3)


def test_penetration_bounded_by_h_times_velocity(runs):
    for h in (1e-5, 1e-4, 5e-4):
        res = runs[("theta", h)]
        vmax = np.abs(res.signal("tip_velocity")).max()
        assert -res.gap.min() <= h * vmax


def test_carpenter_stability_limit_matches_paper():
    lim = fr.Carpenter(fr.bar_model(), 1e-5).stability_limit()
    assert 1.5e-5 < lim < 3e-5  # paper: "approximately h < 2e-5 s"
    mats, _ = fr.bar_matrices()
    import scipy.linalg as sla

    w_max = np.sqrt(sla.eigh(mats.K.toarray(), mats.M.toarray(), eigvals_only=True)[-1])
    assert lim == pytest.approx(2.0 / w_max, rel=1e-8)


@pytest.mark.parametrize("h", [3e-5, 2.7e-5])
def test_carpenter_above_limit_reports_instability(h):
    res = fr.Carpenter(fr.bar_model(alpha=ALPHA), h).run(0.1)
    assert res.status == "unstable"
    assert "stability limit" in res.message or "blow-up" in res.message or "nothing" in res.message
    assert np.all(np.isfinite(res.signal("tip_displacement")))
    assert res.steps < int(0.1 / h)  # stopped before the end, results kept up to the blow-up


def test_runaway_alpha7_is_physical():
    res = fr.ThetaMethod(fr.bar_model(alpha=7.0), 1e-4).run(
        T_END, limits={"tip_temperature": 1500.0}
    )
    assert res.status == "diverged-physically"
    assert 0.15 < res.t[-1] < T_END
    assert res.energy_error() < 1e-8  # fed by thermal work, not by numerics
    assert np.all(np.isfinite(res.signal("tip_temperature")))
