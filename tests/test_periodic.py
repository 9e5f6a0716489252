"""Periodic orbits by shooting on the θ-method, checked against closed forms.

The impact oscillator: ``ẍ + x = F cos(ω t)`` (m = 1 kg, k = 1 N/m, ω0 = 1 rad/s) against a
rigid wall at ``x = d`` with Newton's restitution ``e``. Between impacts
``x = y + X_p cos(ω t)``, ``X_p = F / (1 − ω²)``, with ``y`` a free oscillation. A period-1
orbit leaves the wall at the phase ``φ = ω τ`` with ``v⁺ = −e v⁻`` and comes back after
``T = 2π/ω`` with ``v⁻``. With ``y0 = d − X_p cos φ``, ``a = X_p ω sin φ`` and the free flight
``y(s) = y0 cos s + ẏ0 sin s`` (``c = cos T``, ``s = sin T``), periodicity of the position
gives ``ẏ0 = q y0``, ``q = tan(T/2)``, and then ``ẏ(T) = −q y0``. The velocity conditions
``ẏ0 = a − e v⁻`` and ``ẏ(T) = v⁻ + a`` give (Shaw & Holmes, J. Sound Vib. 90, 1983)::

    v⁻ = −2 a / (1 − e),     (1 + e) X_p ω sin φ + q (1 − e) X_p cos φ = q (1 − e) d

a harmonic equation in φ: two orbits, of which the physical one has ``v⁻ > 0`` and stays
below the wall between impacts. As ``d → |X_p|`` the impact velocity goes to zero: the
grazing orbit, beyond which (``d > |X_p|``) the orbit is the linear one, ``max x = |X_p|``.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from femrub.model.config import ForceLaw
from femrub.model.first_order import Contact, FirstOrderModel, Layout, LoadTerm
from femrub.periodic import PeriodMap, Shooting, continue_branch, forcing_frequency
from femrub.periodic.output import write_branch


def oscillator(omega, F=0.36, d=0.5, e=0.5, c=0.0, wall=True):
    """``ẍ + c ẋ + x = F cos(ω t)``, a wall at ``x = d`` (restitution ``e``)."""
    A = sp.identity(2)
    B = sp.csr_matrix(np.array([[0.0, 1.0], [-1.0, -c]]))
    load = LoadTerm(np.array([0.0, F]), ForceLaw("sin", omega, phase=np.pi / 2), np.array([0, 1.0]))
    contact = None
    if wall:
        contact = Contact(
            G=np.array([-1.0, 0.0]),
            Gv=np.array([0.0, -1.0]),
            Hm=np.array([0.0, -1.0]),
            Ht=np.zeros(2),
            gap0=d,
            restitution=e,
        )
    obs = {"tip_displacement": sp.csr_matrix([[1.0, 0.0]])}
    return FirstOrderModel(A, B, Layout(1, 1, 0), loads=[load], contact=contact, observations=obs)


def impact_orbit(omega, F=0.36, d=0.5, e=0.5):
    """The physical period-1 orbit of the module docstring: ``(φ, v⁻, X(0))``."""
    T = 2 * np.pi / omega
    Xp, q = F / (1 - omega**2), np.tan(T / 2)
    R = Xp * np.hypot((1 + e) * omega, q * (1 - e))
    psi = np.arctan2(q * (1 - e) * Xp, (1 + e) * Xp * omega)
    best = None
    for phi in (np.arcsin(q * (1 - e) * d / R) - psi, np.pi - np.arcsin(q * (1 - e) * d / R) - psi):
        vm = -2 * Xp * omega * np.sin(phi) / (1 - e)
        y0 = d - Xp * np.cos(phi)
        s = np.linspace(0, T, 2001)[1:-1]
        x = y0 * np.cos(s) + q * y0 * np.sin(s) + Xp * np.cos(phi + omega * s)
        if vm > 0 and x.max() < d:
            s0 = (-phi / omega) % T  # from the impact to t = 0
            x0 = y0 * np.cos(s0) + q * y0 * np.sin(s0) + Xp * np.cos(phi + omega * s0)
            v0 = -y0 * np.sin(s0) + q * y0 * np.cos(s0) - Xp * omega * np.sin(phi + omega * s0)
            best = (phi % (2 * np.pi), vm, np.array([x0, v0]))
    return best


def test_linear_forced_response_equals_frf():
    """No contact: the orbit's amplitude and phase are the FRF's, ``F / (k − m ω² + i c ω)``."""
    omega, F, c = 0.9, 0.2, 0.05
    model = oscillator(omega, F=F, c=c, wall=False)
    pm = PeriodMap(model, 2 * np.pi / omega / 2000)
    res = Shooting(pm).solve(np.zeros(2), scale=np.ones(2))
    H = F / (1 - omega**2 + 1j * c * omega)  # x = Re(H e^{iωt}) for F cos(ω t)
    orbit = pm.orbit(res.X0)
    exact = np.real(H * np.exp(1j * omega * orbit.t))
    assert res.converged and res.iterations <= 2
    assert np.abs(orbit.X[:, 0] - exact).max() < 1e-5 * abs(H)
    assert pm.steps == 2000 and pm.period == pytest.approx(2 * np.pi / omega)


def test_floquet_multipliers_of_a_linear_damped_system():
    """The monodromy's eigenvalues are ``e^{λ T}``, ``λ`` the eigenvalues of ``A⁻¹ B``."""
    omega, c = 1.7, 0.1
    model = oscillator(omega, c=c, wall=False)
    pm = PeriodMap(model, 2 * np.pi / omega / 4000)
    res = Shooting(pm).solve(np.zeros(2), scale=np.ones(2))
    lam = np.linalg.eigvals(np.array([[0.0, 1.0], [-1.0, -c]]))
    exact = np.sort_complex(np.exp(lam * pm.period))
    got = np.sort_complex(np.linalg.eigvals(res.monodromy))
    assert np.abs(got - exact).max() < 1e-6
    assert forcing_frequency(model) == pytest.approx(omega)


def test_impact_oscillator_orbit_equals_closed_form():
    """The period-1 impacting orbit: impact phase, impact velocity and the wall's position."""
    omega, d, e = 0.8, 0.5, 0.5
    phi, vm, X0 = impact_orbit(omega, d=d, e=e)
    pm = PeriodMap(model := oscillator(omega, d=d, e=e), 2 * np.pi / omega / 8000)
    res = Shooting(pm, tolerance=1e-9).solve(X0 * 1.01)
    orbit = pm.orbit(res.X0)
    k = int(np.argmax(orbit.P[:, 0]))
    assert res.converged
    assert np.count_nonzero(orbit.P[:, 0] > 1e-9) == 1  # one impact per period
    assert orbit.X[k - 1, 1] == pytest.approx(vm, rel=5e-3)  # velocity before the impact
    assert (orbit.t[k] * omega) % (2 * np.pi) == pytest.approx(phi, abs=5e-3)
    assert orbit.X[:, 0].max() == pytest.approx(d, rel=2e-3)
    assert model.contact is not None


@pytest.mark.parametrize("ratio", [0.97, 1.03])
def test_impact_oscillator_grazing(ratio):
    """Below the grazing gap the impact velocity follows the closed form (small); above it
    the orbit is the linear one and never touches the wall."""
    omega, F, e = 0.8, 0.36, 0.5
    Xp = F / (1 - omega**2)
    d = ratio * Xp
    pm = PeriodMap(oscillator(omega, F=F, d=d, e=e), 2 * np.pi / omega / 8000)
    if ratio < 1:
        phi, vm, X0 = impact_orbit(omega, F=F, d=d, e=e)
        res = Shooting(pm, tolerance=1e-9).solve(X0)
        orbit = pm.orbit(res.X0)
        k = int(np.argmax(orbit.P[:, 0]))
        assert res.converged and vm < 0.2 * Xp * omega
        assert orbit.X[k - 1, 1] == pytest.approx(vm, rel=3e-2)
    else:
        res = Shooting(pm, tolerance=1e-9).solve(np.array([Xp, 0.0]))
        orbit = pm.orbit(res.X0)
        assert res.converged and not orbit.P.any()
        assert orbit.X[:, 0].max() == pytest.approx(Xp, rel=1e-5)


def test_branch_of_linear_orbits_and_its_folder(tmp_path):
    """Continuation in the forcing frequency of the damped linear oscillator follows the FRF
    through the resonance (no fold: the linear branch is a graph over ω), every point
    stable (``max |μ| = e^{−c T / 2}``), and the folder holds its files."""
    F, c = 0.1, 0.1

    def family(w):
        return oscillator(w, F=F, c=c, wall=False)

    branch = continue_branch(family, 0.8, 1.2, h=2.5e-2, key="omega", warmup=0, max_points=200)
    w = branch.parameter
    frf = F / np.abs(1 - w**2 + 1j * c * w)
    assert branch.status == "ok" and len(w) > 10
    assert np.allclose(branch.column("max_tip_displacement"), frf, rtol=2e-3)
    assert all(p.stable and not p.special for p in branch.points)
    mods = np.array([p.max_floquet_modulus for p in branch.points])
    assert np.allclose(mods, np.exp(-c * 2 * np.pi / w / 2), rtol=1e-3)
    doc = write_branch(branch, tmp_path, model_of=family)
    head = (tmp_path / "branch.csv").read_text().splitlines()[0].split(",")
    assert head[0] == "omega" and "max_tip_displacement" in head and "special" in head
    assert doc["status"] == "ok" and (tmp_path / "branch.png").stat().st_size > 0
    with np.load(tmp_path / doc["orbits"][0]["folder"] / "history.npz") as h:
        assert {"t", "signal_tip_displacement", "impulse"} <= set(h.files)


def test_fold_of_the_impacting_resonance_is_passed():
    """The damped impact oscillator's impacting resonance peak bends to higher frequencies
    and folds: continuation in ω from its stable upper branch passes the fold, where a real
    multiplier crosses +1, and goes on along the unstable branch (ω decreasing, converged
    points). A time integration just above the fold leaves the impacting orbit for the
    linear one; just below it keeps impacting."""
    F, d, e, c, n = 0.2, 0.5, 0.5, 0.1, 2000

    def family(w):
        return oscillator(w, F=F, d=d, e=e, c=c)

    branch = continue_branch(
        family,
        1.3,
        2.0,
        h=2 * np.pi / n,
        key="omega",
        x0=np.array([d, 0.0]),
        warmup=200,
        activation="paper",
        max_points=26,
    )
    w, pts = branch.parameter, branch.points
    folds = [i for i, p in enumerate(pts) if p.special == "fold"]
    assert folds, [p.special for p in pts]
    i = folds[0]
    assert w[i - 1] == w.max() or w[i] == w.max()  # the branch turns back there
    after = pts[i:]
    assert len(after) >= 4 and all(p.converged for p in after)
    assert np.all(np.diff(w[i:]) < 0) and w[-1] < w.max() - 0.02
    assert all(p.stable for p in pts[:i]) and not any(p.stable for p in after)
    real = [
        np.max(m.real[np.abs(m.imag) < 1e-9]) for m in (pts[i - 1].multipliers, pts[i].multipliers)
    ]
    assert real[0] < 1.0 < real[1]
    top = pts[int(np.argmax(w))]
    for ratio, impacts in ((1.005, False), (0.99, True)):
        pm = PeriodMap(family(top.parameter * ratio), 2 * np.pi / n, activation="paper")
        X = top.X0
        for _ in range(300):
            X = pm(X)
        assert bool(pm.orbit(X).P.any()) == impacts


def test_a_turn_without_a_multiplier_crossing_one_is_not_a_fold():
    """``fold`` needs both the turn (``dp/ds`` changes sign) and a real multiplier across +1."""
    from femrub.periodic.floquet import special_point

    def info(dp, mu):
        return {"dp": dp, "mu": np.array(mu, dtype=complex), "det_sign": 1.0}

    assert special_point(info(1.0, [0.95, 0.3]), info(-1.0, [1.05, 0.3])) == "fold"
    assert special_point(info(1.0, [0.7, 0.3]), info(-1.0, [0.8, 0.3])) == ""
    assert special_point(info(1.0, [0.7, 0.3]), info(1.0, [-1.2, 0.3])) == "period-doubling"
    assert special_point(info(1.0, [0.7, 0.3]), info(1.0, [1.3, 0.3])) == "stability-change"


def test_restart_equals_a_fresh_stepper_from_that_state():
    """``Stepper.restart(X, t)`` then steps = a new θ-method on ``model.with_(x0=X)`` at ``t``,
    bit for bit, with the wall hit in between; a state that is not finite is refused."""
    from femrub.steppers.theta import ThetaMethod

    model = oscillator(0.8)
    st = ThetaMethod(model, 1e-3)
    for _ in range(500):
        st.step()
    X, t = np.array([0.3, 0.9]), 0.37
    st.restart(X, t)
    fresh = ThetaMethod(model.with_(x0=X), 1e-3, t0=t)
    for _ in range(800):
        a, b = st.step(), fresh.step()
    assert a.t == b.t and np.array_equal(a.X, b.X)
    with pytest.raises(ValueError, match="finite vector"):
        st.restart(np.array([np.nan, 0.0]))


@pytest.mark.parametrize("rule", ["position", "capped", "paper"])
def test_step_monodromy_equals_finite_differences(rule):
    """On an impacting orbit the product of the step Jacobians is the finite-difference
    monodromy (no impact moves a step under the perturbations)."""
    omega = 0.8
    pm = PeriodMap(oscillator(omega), 2 * np.pi / omega / 1000, activation=rule)
    X0 = impact_orbit(omega)[2]
    assert pm.orbit(X0).P.any()
    exact = Shooting(pm).monodromy(X0, np.ones(2))
    fd = Shooting(pm, derivatives="fd", eps=1e-8).monodromy(X0, np.ones(2))
    assert np.allclose(exact, fd, rtol=1e-5, atol=1e-5 * np.abs(exact).max())


def test_finite_difference_newton_takes_one_monodromy_and_broyden_updates(monkeypatch):
    """With finite differences Newton takes the monodromy once and then Broyden's update
    (one period per iteration): it ends on the orbit of Newton with the step Jacobians."""
    import femrub.periodic.shooting as shooting

    omega = 0.8
    X0 = impact_orbit(omega)[2]
    pm = PeriodMap(oscillator(omega), 2 * np.pi / omega / 8000)
    taken = []
    plain = shooting.differences
    monkeypatch.setattr(shooting, "differences", lambda *a, **k: taken.append(1) or plain(*a, **k))
    fd = Shooting(pm, tolerance=1e-9, derivatives="fd").solve(1.3 * X0, monodromy=False)
    exact = Shooting(pm, tolerance=1e-9).solve(1.3 * X0, monodromy=False)
    assert fd.converged and fd.iterations >= 2 and len(taken) == 1
    assert np.allclose(fd.X0, exact.X0, rtol=0, atol=1e-9)


@pytest.mark.parametrize("rule", ["position", "paper"])
def test_checked_differences_refuse_columns_that_cross_an_impact(rule):
    """A finite-difference step that moves the impact by a step gives a column of size
    ``jump / δ``: the plain differences are then far from the step Jacobians' product, the
    checked ones take those columns again at smaller steps and equal it; with a step whose
    every refinement still crosses, the column is counted unsettled."""
    from femrub.periodic.shooting import checked_differences, differences

    omega = 0.8
    pm = PeriodMap(oscillator(omega), 2 * np.pi / omega / 1000, activation=rule)
    X0 = impact_orbit(omega)[2]
    image = pm(X0)
    exact = Shooting(pm).monodromy(X0, np.ones(2))
    delta = 1e-2 * (1.0 + np.abs(X0))
    plain = differences(pm, X0, image, delta)
    checked, unsettled = checked_differences(pm, X0, image, delta, np.ones(2))
    assert np.abs(plain - exact).max() > 0.5 * np.abs(exact).max()
    assert unsettled == 0
    assert np.allclose(checked, exact, rtol=1e-6, atol=1e-6 * np.abs(exact).max())
    assert checked_differences(pm, X0, image, 10 * delta, np.ones(2))[1] > 0


def test_a_landing_held_on_the_wall_keeps_the_step_multipliers():
    """A plastic impact (e = 0) that the next steps hold on the wall: where in its step it
    lands moves nothing once the mass is held, so the Floquet multipliers (the monodromy
    with the impact-time terms) are those of the step Jacobians' product and of the decay
    of a perturbation in time integration (the impact-time term of a bounce gave 1e-4)."""
    omega = 0.8
    model = oscillator(omega, d=0.3, e=0.0, c=0.1)
    pm = PeriodMap(model, 2 * np.pi / omega / 2000, activation="paper")
    X = np.zeros(2)
    for _ in range(400):
        X = pm(X)
    res = Shooting(pm, tolerance=1e-10).solve(X)
    assert res.converged and np.count_nonzero(pm.orbit(res.X0).P) > 100  # held
    mu = np.abs(np.linalg.eigvals(res.monodromy)).max()
    Y, distance = res.X0 + 1e-3 * res.scale, []
    for _ in range(40):
        Y = pm(Y)
        distance.append(np.max(np.abs(Y - res.X0) / res.scale))
    assert mu == pytest.approx((distance[-1] / distance[-11]) ** 0.1, rel=1e-3)


def test_multipliers_of_an_impacting_orbit_carry_the_impact_time():
    """Perturbations that move the impact by many steps return after a period as the
    orbit's monodromy with the saltation terms says (a linear map fitted to the period
    map's response); the product of the step Jacobians alone, blind to the impact time,
    is off by far more."""
    from femrub.periodic.sensitivity import step_monodromy

    w, n = 1.3, 16000
    pm = PeriodMap(oscillator(w, F=0.2, d=0.5, e=0.5, c=0.1), 2 * np.pi / w / n, activation="paper")
    X = np.array([0.5, 0.0])
    for _ in range(30):
        X = pm(X)
    res = Shooting(pm).solve(X)
    X, orbit = res.X0, pm.orbit(res.X0)
    assert res.converged and np.count_nonzero(orbit.P) == 1
    before, after = [], []
    for angle in np.linspace(0.0, np.pi, 6, endpoint=False):
        Y = X + 0.03 * np.array([np.cos(angle), np.sin(angle)])
        for k in range(4):
            Z = pm(Y)
            if k:  # the first period settles the perturbation onto the orbit's directions
                before.append(Y - X)
                after.append(Z - X)
            Y = Z
    fitted = np.linalg.lstsq(np.array(before), np.array(after), rcond=None)[0].T
    exact = np.sort_complex(np.linalg.eigvals(fitted))
    salted = np.sort_complex(np.linalg.eigvals(step_monodromy(pm.stepper, orbit, True)))
    plain = np.sort_complex(np.linalg.eigvals(step_monodromy(pm.stepper, orbit)))
    assert np.abs(salted - exact).max() < 0.03
    assert np.abs(plain - exact).max() > 0.2
    assert np.allclose(np.sort_complex(np.linalg.eigvals(res.monodromy)), salted)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--set", "physics.thermal=on", "--param", "rotation_speed=1:2"], "physics.thermal"),
        (["--param", "loads.rotation_speed=1"], "KEY=START:STOP"),
        (["--param", "loads.rotation_speed=2000rpm:2000rpm"], "equal"),
        (["--param", "loads.nothing=1:2"], "unknown key"),
        (["--set", "scheme.name=carpenter", "--param", "rotation_speed=1:2"], "theta"),
    ],
)
def test_cli_refuses_bad_input_in_one_line_before_any_folder(tmp_path, capsys, args, message):
    from femrub.app.cli import main

    out = tmp_path / "branch"
    assert main(["periodic", "paper", *args, "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_paper_bar_without_damping_has_no_settled_response_to_start_from(tmp_path, capsys):
    """The paper's bar without damping (γ = 1/2, plastic impacts) at 20000 rpm: the time
    integration from rest does not settle (its state changes by a large fraction of its size
    from period to period), Newton from there finds no orbit, and the branch says both and
    keeps its folder."""
    from femrub.app.cli import main

    out = tmp_path / "branch"
    args = ["periodic", "paper", "--set", "physics.thermal=off", "--set", "scheme.h=2e-6"]
    args += ["--param", "loads.rotation_speed=20000rpm:40000rpm", "-o", str(out), "--quiet"]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "no periodic orbit at loads.rotation_speed = 2094.4" in err
    drift = float(err.split("still changes by ")[1].split()[0])
    assert "has not settled" in err and drift > 0.1
    assert (out / "branch.csv").exists() and (out / "summary.json").exists()
