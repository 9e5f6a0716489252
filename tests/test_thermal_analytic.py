"""The thermal side against closed-form solutions, through the assembly and steppers users run.

Each case is run on a mesh/time step and on the mesh and step both halved. The scheme is of
order 2 in space (P1, lumped capacity) and in time (trapezoidal rule), so the error of the
fine run is about a third of the difference between the two runs (Richardson); a run
passes when its error is within that difference (a safety factor of 3 on the estimate).
A wrong physical term does not converge to the reference and fails whatever the mesh.
"""

from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sla
import skfem as fem

import femrub as fr
from femrub.cases.analytic_thermal import (
    adiabatic_temperature_rise,
    bar_heat_flux_temperature,
    heated_bar_tip_displacement,
    zener_damping_ratio,
    zener_mode_history,
)
from femrub.fem.discretisation import assemble, discretise
from femrub.geometry import box_blade
from femrub.geometry.bar import bar_mesh
from femrub.model import Load, first_order_model

# a 5 cm bar/box with κ = k / (ρ c) such that L² / κ = 330 s
L, AREA, K_TH, RHO, C = 0.05, 1e-6, 20.0, 4500.0, 585.0
TAU = L**2 * RHO * C / K_TH
MAT = fr.Material(young=110e9, rho=RHO, rho_c=RHO * C, conductivity=K_TH, expansion=8.6e-6)
Q = 0.01  # W


def _ends(basis, coord=0):
    x = basis.doflocs[coord]
    return (
        basis.get_dofs(lambda p: np.isclose(p[coord], x.min())).all(),
        basis.get_dofs(lambda p: np.isclose(p[coord], x.max())).all(),
    )


def _bar(n, *, fix_u=(), fix_t=(), material=MAT, **kw):
    """1D bar discretisation with the ends named in ``fix_u``/``fix_t`` held (root, tip)."""
    disc = discretise(bar_mesh(L, n), 1, clamped=False)
    ends_u, ends_t = _ends(disc.basis_u), _ends(disc.basis_t)
    pick = {"root": 0, "tip": 1}
    fu = np.concatenate([ends_u[pick[e]] for e in fix_u] or [np.zeros(0, int)])
    ft = np.concatenate([ends_t[pick[e]] for e in fix_t] or [np.zeros(0, int)])
    disc = replace(disc, fixed_u=fu.astype(int), fixed_t=ft.astype(int))
    return disc, assemble(disc, material, area=AREA, lumping="row-sum", **kw)


def _theta_full(model, res):
    """Temperature on every node (Dirichlet dofs included) at every stored state."""
    P = model.to_full[-model.blocks.n_t_all :, model.layout.t]
    return (P @ res.states[:, model.layout.t].T).T


def _within_richardson(coarse, fine, exact, floor):
    err = np.abs(fine - exact).max()
    est = np.abs(fine - coarse).max()
    assert err <= est + floor, f"error {err:.3e} > Richardson difference {est:.3e}"
    return err, est


def _ramp(tr):
    return lambda t: 1.0 - np.exp(-np.asarray(t) / tr)


# -- transient conduction: Fourier series ----------------------------------------------------


def _flux_bar_run(n, steps):
    disc, mats = _bar(n, fix_u=("root",), fix_t=("root",), coupling="none")
    tip = mats.t_index(_ends(disc.basis_t)[1])
    vec = np.zeros(mats.n_t)
    vec[tip] = Q
    model = first_order_model(mats, loads=[Load(vec, _ramp(0.02 * TAU), "theta")], thermal=True)
    h = TAU / steps
    res = fr.ThetaMethod(model, h).run(TAU, store_every=steps // 20, energy=False)
    return disc.basis_t.doflocs[0], res.state_times, _theta_full(model, res)


def _flux_3d_run(h_mesh, steps, conduction="galerkin"):
    blade = box_blade(span=L, chord=0.005, thickness=0.005, h=h_mesh, n_contact=1)
    disc = discretise(blade, 1)  # P1 displacement: only the temperature matters here
    mats = assemble(disc, MAT, coupling="none", conduction=conduction)
    fb = fem.FacetBasis(disc.mesh, disc.basis_t.elem, facets=disc.facets_of("tip"))
    flux = Q / 0.005**2

    @fem.LinearForm
    def q(v, w):
        return flux * v

    vec = q.assemble(fb)[mats.free_t]
    model = first_order_model(mats, loads=[Load(vec, _ramp(0.02 * TAU), "theta")], thermal=True)
    res = fr.ThetaMethod(model, TAU / steps).run(TAU, store_every=steps // 20, energy=False)
    return disc.basis_t.doflocs[2], res.state_times, _theta_full(model, res)


def _probe(x, T, where):
    """Temperatures at the nodes nearest to the stations ``where`` (exactly on them here)."""
    idx = [int(np.argmin(np.abs(x - w))) for w in where]
    assert np.allclose(x[idx], where, atol=1e-9)
    return T[:, idx]


STATIONS = np.array([0.25, 0.5, 1.0]) * L


def _exact(t, area=AREA):
    return bar_heat_flux_temperature(
        STATIONS,
        t,
        flux=Q,
        length=L,
        conductivity=K_TH,
        rho_c=RHO * C,
        area=area,
        ramp_time=0.02 * TAU,
    )


def test_bar_conduction_matches_fourier_series():
    x1, t1, T1 = _flux_bar_run(8, 200)
    x2, t2, T2 = _flux_bar_run(16, 400)
    assert np.allclose(t1, t2)
    exact = _exact(t2)
    assert exact[-1, -1] == pytest.approx(0.92 * Q * L / (K_TH * AREA), rel=0.05)  # near steady
    err, est = _within_richardson(_probe(x1, T1, STATIONS), _probe(x2, T2, STATIONS), exact, 0.0)
    assert err < 5e-3 * exact.max()


def test_slender_box_conduction_matches_fourier_series():
    z1, t1, T1 = _flux_3d_run(0.005, 100)
    z2, t2, T2 = _flux_3d_run(0.0025, 200)
    exact = _exact(t2, 0.005**2)
    # every node at a station: the cross-section is at one temperature (1D solution)
    for z, T in ((z1, T1), (z2, T2)):
        for s in STATIONS:
            on = np.isclose(z, s)
            assert on.sum() >= 4 and np.ptp(T[:, on], axis=1).max() < 1e-2 * np.abs(T).max()
    c = np.stack([T1[:, np.isclose(z1, s)].mean(axis=1) for s in STATIONS], axis=1)
    f = np.stack([T2[:, np.isclose(z2, s)].mean(axis=1) for s in STATIONS], axis=1)
    err, est = _within_richardson(c, f, exact, 0.0)
    assert err < 1e-2 * exact.max()


# -- adiabatic heating: ΔT = Q t / (m c) -----------------------------------------------------


def _mean_temperature(basis_t, model, res):
    """Volume mean of θ, integrated on the mesh (independent of the heat-capacity matrix)."""
    ones = fem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).assemble(basis_t)

    @fem.LinearForm
    def vol(v, w):
        return v

    wts = vol.assemble(basis_t)
    return _theta_full(model, res) @ wts / ones, ones


@pytest.mark.parametrize("dim", [1, 3])
def test_insulated_body_heats_adiabatically(dim):
    if dim == 1:
        disc, mats = _bar(10, coupling="none")
        tip = mats.t_index(_ends(disc.basis_t)[1])
        vec, area = np.zeros(mats.n_t), AREA
        vec[tip] = Q
    else:
        blade = box_blade(span=L, chord=0.01, thickness=0.005, h=0.005, n_contact=1)
        disc = discretise(blade, 1, clamped=False)
        mats = assemble(disc, MAT, coupling="none")
        vec = np.zeros(mats.n_t)
        vec[mats.t_index(disc.blade.require("tip"))] = Q / disc.blade.require("tip").size
        area = 1.0
    model = first_order_model(mats, loads=[Load(vec, _ramp(0.05 * TAU), "theta")], thermal=True)
    h = 0.01 * TAU
    res = fr.ThetaMethod(model, h).run(0.3 * TAU, store_every=1, energy=False)
    mean, volume = _mean_temperature(disc.basis_t, model, res)
    t = res.t
    heat = Q * (t - 0.05 * TAU * (1.0 - np.exp(-t / (0.05 * TAU))))  # ∫ Q s dt, exactly
    # trapezoidal quadrature of ∫ Q s dt: error ≤ h² t max|s''| / 12
    quad = h**2 * t * Q / (0.05 * TAU) ** 2 / 12
    expected = adiabatic_temperature_rise(heat, RHO * volume * area, C)
    assert np.all(np.abs(mean - expected) <= quad / (RHO * C * volume * area) + 1e-12)
    assert expected[-1] > 0.1


# -- thermal expansion under a temperature history ---------------------------------------------


def _heated_bar_run(n, h, t_end, rate):
    disc, mats = _bar(n, fix_u=("root",), coupling="physical")

    @fem.LinearForm
    def q(v, w):
        return RHO * C * rate * AREA * v  # uniform volumetric heating ρ c r

    vec = q.assemble(disc.basis_t)[mats.free_t]
    tip = mats.u_index(_ends(disc.basis_u)[1])
    model = first_order_model(
        mats, loads=[Load(vec, 1.0, "theta")], observe={"tip": ("u", tip)}, thermal=True
    )
    res = fr.ThetaMethod(model, h).run(t_end, store_every=1, energy=False)
    theta = res.states[:, model.layout.t]
    return res.t, res.signal("tip"), theta


def test_thermal_expansion_follows_temperature_history():
    rate, t_end = 2000.0, 4e-4  # K/s; a few axial periods (2π/ω_1 = 4e-5 s)
    t1, u1, th1 = _heated_bar_run(10, 2e-7, t_end, rate)
    t2, u2, th2 = _heated_bar_run(20, 1e-7, t_end, rate)
    # uniform heating keeps the temperature uniform: θ = r t on every node
    assert np.allclose(th2, rate * t2[:, None], rtol=1e-9, atol=1e-12)
    exact = heated_bar_tip_displacement(
        t2, rate=rate, length=L, young=MAT.young, rho=RHO, expansion=MAT.expansion
    )
    err, est = _within_richardson(u1[::1], u2[::2], exact[::2], 0.0)
    assert err < 0.02 * np.abs(exact).max()
    # and the quasi-static part: mean over the last periods ≈ α L θ
    assert u2[-1] == pytest.approx(MAT.expansion * L * rate * t_end, rel=0.1)


# -- thermoelastic (Zener) damping -----------------------------------------------------------------


# a fictitious material whose first mode of a 0.1 m bar sits at ω τ = 1 (largest Zener
# damping): k_th = ρ c ω / k², α large enough for a measurable decay
ZL, ZT0 = 0.1, 293.15
ZW = np.pi / ZL * np.sqrt(110e9 / RHO)
ZK = np.pi / ZL
ZMAT = fr.Material(
    young=110e9,
    rho=RHO,
    rho_c=RHO * C,
    conductivity=RHO * C * ZW / ZK**2,
    expansion=5e-5,
    reference_temperature=ZT0,
)
ZPAR = dict(
    young=ZMAT.young,
    rho=RHO,
    rho_c=ZMAT.rho_c,
    conductivity=ZMAT.conductivity,
    expansion=ZMAT.expansion,
    t0=ZT0,
    wavenumber=ZK,
)


def _zener_run(n, steps_per_period, periods):
    disc = discretise(bar_mesh(ZL, n), 1, clamped=False)
    ends = _ends(disc.basis_u)
    disc = replace(disc, fixed_u=np.concatenate(ends), fixed_t=np.zeros(0, int))
    mats = assemble(
        disc, ZMAT, area=AREA, lumping="row-sum", coupling="physical", strain_heating=True
    )
    x = disc.basis_u.doflocs[0][mats.free_u]
    x0 = np.zeros(2 * mats.n_u + mats.n_t)
    x0[: mats.n_u] = 1e-6 * np.sin(ZK * x)
    model = first_order_model(mats, thermal=True, x0=x0)
    h = 2 * np.pi / ZW / steps_per_period
    res = fr.ThetaMethod(model, h).run(periods * 2 * np.pi / ZW, store_every=1, energy=False)
    mid = int(np.argmin(np.abs(x - ZL / 2)))
    xt = disc.basis_t.doflocs[0][mats.free_t]
    root = int(np.argmin(xt))  # θ = Θ cos(k x) is largest at the (insulated) ends
    return res.t, res.states[:, mid], res.states[:, model.layout.t.start + root]


def test_zener_damping_of_a_vibrating_bar():
    zeta, w = zener_damping_ratio(**ZPAR)
    delta = ZMAT.young * ZMAT.expansion**2 * ZT0 / ZMAT.rho_c
    assert zeta == pytest.approx(delta / 4, rel=2 * delta)  # Zener at ω τ = 1
    t1, u1, T1 = _zener_run(16, 80, 6)
    t2, u2, T2 = _zener_run(32, 160, 6)
    ref = zener_mode_history(t2, u0=1e-6, **ZPAR)
    _within_richardson(u1, u2[::2], ref[::2, 0], 0.0)
    _within_richardson(T1, T2[::2], ref[::2, 2], 0.0)
    # the decay is Zener's: amplitude after 6 periods e^{−ζ ω t}, far from undamped
    env = np.abs(ref[-1, 0]) / 1e-6
    assert env < 0.85 and np.exp(-zeta * w * t2[-1]) == pytest.approx(env, rel=0.05)
    peak = np.abs(u2[-len(u2) // 6 :]).max() / 1e-6
    assert peak == pytest.approx(np.exp(-zeta * w * t2[-1]), rel=0.05)


@pytest.mark.parametrize("coupling", ["paper", "physical"])
def test_strain_heating_is_the_adjoint_of_the_thermal_stress(coupling):
    # C^θu = −T0 (K^uθ)ᵀ makes the free energy ½uᵀKu + ½vᵀMv + θᵀC^θθθ/(2 T0) a Lyapunov
    # function: its rate is −vᵀCv − θᵀK^θθθ / T0 ≤ 0, so no eigenvalue grows
    model = fr.bar_model(gap=1.0, alpha=0.0, strain_heating=True, coupling=coupling)
    mats = model.blocks
    T0 = fr.PAPER.material.reference_temperature
    assert abs(mats.Ctu).max() > 0
    ctu, ref = mats.Ctu.toarray(), -T0 * mats.Kut.T.toarray()
    assert np.abs(ctu - ref).max() <= 1e-12 * np.abs(ref).max()
    ev = sla.eigvals(model.B.toarray(), model.A.toarray())
    assert ev.real.max() <= 1e-9 * np.abs(ev).max()


def test_slender_box_monotone_conduction_is_first_order():
    """The monotone conduction (femrub.fem.monotone) on the same slender box: no undershoot,
    but the discrete upwinding adds conductance where the Galerkin couplings are positive,
    an O(h) error where conduction carries the heat (docs/reduction_3d.md): the error to
    the Fourier series (26 % and 11 % here, Galerkin 0.4 % and 0.1 %) halves with h."""
    errs = []
    for h_mesh, steps in ((0.005, 100), (0.0025, 200)):
        z, t, T = _flux_3d_run(h_mesh, steps, conduction="monotone")
        assert T.min() >= -1e-12 * T.max()
        mean = np.stack([T[:, np.isclose(z, s)].mean(axis=1) for s in STATIONS], axis=1)
        exact = _exact(t, 0.005**2)
        errs.append(np.abs(mean - exact).max() / exact.max())
    assert errs[1] < 0.6 * errs[0] and errs[1] < 0.15, errs
