"""Free decay of damped modes against the analytic decay, stepped by the θ-method.

A mode released at rest decays as ``e^(−ζ ω t) (cos ω_d t + ζ/√(1−ζ²) sin ω_d t)``. The
trapezoidal rule (γ = 1/2) integrates ``q̇ = s q`` with a relative error of about
``|s h|² |s| t / 12`` (its local error is ``(s h)³ / 12``), which sets the tolerance.
"""

import numpy as np
import pytest

import femrub as fr
from femrub.cases.analytic_thermal import damped_mode, rayleigh_ratio
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import lowest_modes
from femrub.geometry import box_blade
from femrub.model import first_order_model


def _trapezoid_tolerance(omega, h, t_end):
    return 2.0 * (omega * h) ** 2 * omega * t_end / 12.0


def test_rayleigh_damped_bar_modes_decay_at_the_analytic_rate():
    # both terms matter: at mode 1 the mass and stiffness parts give half of ζ_0 each
    mats0, _ = fr.bar_matrices(fr.PAPER.with_(coupling="none"))
    w2, V = lowest_modes(mats0.K, mats0.M, 2)
    w = np.sqrt(w2)
    zeta0 = 0.02
    a, b = zeta0 * w[0], zeta0 / w[0]
    zeta = rayleigh_ratio(a, b, w)
    assert zeta[0] == pytest.approx(zeta0) and zeta[1] > 1.5 * zeta0
    model = fr.bar_model(coupling="none", alpha=0.0, force_amplitude=0.0, gap=1.0, rayleigh=(a, b))
    x0 = np.zeros(model.n_dofs)
    x0[model.layout.u] = 1e-6 * (V[:, 0] + V[:, 1])  # well inside the 1 m gap
    h, t_end = 2 * np.pi / w[1] / 200, 5 * 2 * np.pi / w[0]
    res = fr.ThetaMethod(model.with_(x0=x0), h).run(t_end, store_every=1, energy=False)
    u = res.states[:, model.layout.u]
    q = np.linalg.lstsq(1e-6 * V, u.T, rcond=None)[0]  # modal coordinates (V spans the motion)
    for k in range(2):
        exact = damped_mode(res.state_times, w[k], zeta[k])
        assert np.abs(q[k] - exact).max() <= _trapezoid_tolerance(w[k], h, t_end)
    # the decay is the one of ζ, not of the mass term alone
    assert abs(q[0, -1]) < 0.8 * np.exp(-a / 2 * t_end)


def test_modally_damped_blade_mode_decays_at_its_damping_ratio():
    # chord = 2 × thickness: the edgewise mode sits at about twice the flapwise one, so the
    # stiffness-proportional term carries about a third of ζ at mode 1
    blade = box_blade(span=0.1, chord=0.02, thickness=0.01, h=0.01, n_contact=1)
    mat = fr.Material(young=110e9, rho=4500.0)
    zeta = 0.03
    disc = discretise(blade)
    mats = assemble(disc, mat, coupling="none", damping_ratio=zeta, damping_modes=(1, 2))
    w2, V = lowest_modes(mats.K, mats.M, 2)
    w = np.sqrt(w2)
    a, b = mats.info["rayleigh"]
    assert rayleigh_ratio(a, b, w) == pytest.approx([zeta, zeta], rel=1e-6)
    model = first_order_model(mats, thermal=False, x0=np.r_[V[:, 0], np.zeros(mats.n_u)])
    assert b * w[0] / 2 > 0.25 * zeta  # the stiffness term matters at mode 1
    h, t_end = 2 * np.pi / w[0] / 60, 3 * 2 * np.pi / w[0]
    res = fr.ThetaMethod(model, h).run(t_end, store_every=1, energy=False)
    top = int(np.argmax(np.abs(V[:, 0])))
    u = res.states[:, top] / V[top, 0]
    exact = damped_mode(res.state_times, w[0], zeta)
    assert np.abs(u - exact).max() <= _trapezoid_tolerance(w[0], h, t_end)
    assert abs(exact[-1]) < 0.6  # e^{-ζ ω t} after three periods: a real decay
