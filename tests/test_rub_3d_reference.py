"""A 3D blade rubbing a casing, against references computed without femrub's model builder.

A box blade is pushed by a radial force F at its contact point (ramped, then held) against
a concentric casing, Rayleigh damped so the contact settles, with frictional heat. The
references are computed from the blade's mesh, its stiffness matrix and the material only:

* the settled contact force is the static one of the tip face's mean radial displacement held
  at the casing (the one contact acts on the whole tip face, femrub.contact.patches):
  ``λ = F − g0 / c`` with ``c = pᵀ K⁻¹ p``, ``p`` the radial dofs of the tip vertices
  weighted by ``w_j`` below (found here from the mesh);
* every joule of frictional heat ``α P`` (``α = η μ Ω r``) stays in the blade: at these
  short times (``κ t / h_e² ~ 1e-5``) conduction has not moved it from the tip nodes, so
  each tip node ``j`` is at the adiabatic temperature ``w_j Σ α P / (ρ c V_j)``, with
  ``w_j = ∫_tip N_j ds / |tip|`` (the uniform flux over the tip face) and
  ``V_j = ∫ N_j dV``;
* the reduced model (Craig–Bampton) follows the full one;
* a single-contact impact of a free slender box is the bar's d'Alembert solution.
"""

import numpy as np
import pytest
import scipy.sparse.linalg as spla
import skfem as fem

import femrub as fr
from femrub.cases.analytic import bar_impact
from femrub.contact.casing import Concentric
from femrub.contact.heat import heat_coefficients
from femrub.contact.points import locate_contacts
from femrub.fem.discretisation import assemble, discretise
from femrub.geometry import box_blade
from femrub.model import Load
from femrub.model.rub import rub_model
from femrub.reduction.craig_bampton import ThermoelasticCraigBampton

SPAN, CHORD, THICK, HUB = 0.1, 0.02, 0.01, 0.3
MAT = fr.Material(young=110e9, rho=4500.0, rho_c=4500.0 * 585.0, conductivity=7.0)
FORCE, CLEARANCE, RAMP = 400.0, 1e-6, 2e-4  # N, m, s
FRICTION, OMEGA = 0.2, 1000.0  # -, rad/s
H, T_END = 1e-6, 6e-4


def _ramp(t):
    return np.minimum(np.asarray(t) / RAMP, 1.0)


@pytest.fixture(scope="module")
def rub():
    blade = box_blade(span=SPAN, chord=CHORD, thickness=THICK, h=0.01, hub_radius=HUB, n_contact=1)
    disc = discretise(blade)
    mats = assemble(disc, MAT, coupling="none", damping_ratio=0.1)
    points = locate_contacts(disc)
    alpha = heat_coefficients(
        points.radii, "friction", friction=FRICTION, rotation_speed=OMEGA, heat_partition=1.0
    )
    # the force acts at the contact point: a Craig-Bampton basis holds its static response
    model, fields = rub_model(
        disc,
        mats,
        points,
        MAT,
        casing=Concentric(CLEARANCE),
        rotation_speed=OMEGA,
        alpha=alpha,
        loads=[Load(FORCE * points.normal_rows(mats).toarray()[0], _ramp, "u")],
    )
    res = fr.ThetaMethod(model, H).run(T_END, store_every=int(T_END / H))
    return blade, model, fields, res, disc


def _tip_share(blade, disc):
    """``w_j = ∫_tip N_j ds / |tip|`` on the vertices (linear shape functions)."""
    bt = disc.basis_t
    assert bt.N == blade.mesh.p.shape[1]  # linear temperature: its dofs are the vertices

    @fem.LinearForm
    def nodal(v, w):
        return v

    share = nodal.assemble(fem.FacetBasis(bt.mesh, bt.elem, facets=disc.facets_of("tip")))
    return share / share.sum()


def _static_force(blade, disc, mats):
    """Contact force of the tip face's mean radial displacement held at the casing."""
    tip = blade.require("tip")
    p = np.zeros(mats.n_u)
    p[mats.u_index(disc.basis_u.nodal_dofs[2, tip])] = _tip_share(blade, disc)[tip]  # radial: z
    compliance = p @ spla.splu(mats.K.tocsc()).solve(p)
    assert FORCE * compliance > 2 * CLEARANCE  # the force does close the gap
    return FORCE - CLEARANCE / compliance


def test_settled_contact_force_is_the_static_one(rub):
    blade, model, fields, res, disc = rub
    assert model.n_contacts == 1 and res.status == "ok"
    vertex = int(fields.contacts.vertices[0])
    assert np.allclose(blade.mesh.p[:, vertex], [CHORD / 2, 0.0, HUB + SPAN])
    ref = _static_force(blade, disc, model.blocks)
    period = int(round(2 * np.pi / 1e5 / H))  # longer than the axial period (~80 µs)
    settled = res.force[-period:, 0].mean()
    assert settled == pytest.approx(ref, rel=0.01)
    # held at the casing: the velocity-level impact law leaves a gap below h |ġ| (Sec. 4.3)
    assert abs(res.gap[-1, 0]) <= H * np.abs(res.signal("tip_velocity")).max()


def test_frictional_heat_enters_the_tip_adiabatically(rub):
    blade, model, fields, res, disc = rub
    alpha = FRICTION * OMEGA * (HUB + SPAN)  # η μ Ω r, η = 1
    assert model.contact.alpha_at(0.0)[0] == pytest.approx(alpha)
    heat = alpha * res.impulse[:, 0].sum()
    assert heat > 0
    bt = disc.basis_t
    theta = (model.to_full @ res.states[-1])[-bt.N :]

    @fem.LinearForm
    def nodal(v, w):
        return v

    volume = nodal.assemble(bt)  # V_j = ∫ N_j dV
    tip = blade.require("tip")
    share = _tip_share(blade, disc)
    # all the heat is in the blade, and it is where it entered
    assert MAT.rho_c * volume @ theta == pytest.approx(heat, rel=1e-6)
    adiabatic = share[tip] * heat / (MAT.rho_c * volume[tip])
    kappa_t = MAT.conductivity / MAT.rho_c * T_END / 0.005**2
    assert kappa_t < 1e-4
    assert np.abs(theta[tip] - adiabatic).max() <= 100 * kappa_t * adiabatic.max()


def test_reduced_model_follows_the_full_one(rub):
    _, model, _, res, _ = rub
    rom = ThermoelasticCraigBampton(model, 12, 6).reduce()
    red = fr.ThetaMethod(rom, H).run(T_END)
    # the reduced model's energy balance may open beyond the 5 % tolerance (verdict.py):
    # reported as inaccurate, never unstable or stopped
    assert red.status in ("ok", "inaccurate")
    # settled: the static response to the tip-face force is in the basis (Eq. 11)
    assert red.force[-200:, 0].mean() == pytest.approx(res.force[-200:, 0].mean(), rel=5e-3)
    # transient: the local response to the tip load is what the truncated modes miss
    u, ur = res.signal("tip_displacement"), red.signal("tip_displacement")
    assert np.abs(ur - u).max() < 0.1 * np.abs(u).max()
    T, Tr = res.signal("tip_temperature"), red.signal("tip_temperature")
    assert Tr[-1] == pytest.approx(T[-1], rel=0.02)


def test_single_contact_impact_of_a_free_slender_box_is_d_alembert():
    # a free slender box (ν = 0) moving radially at v0 hits the casing at the one contact
    # point of its tip: the exact bar solution holds (force ρ c A v0 during 2L/c, impulse
    # 2 m v0, rebound at −v0). Its discretisation error is the bar's wave dispersion: 1D P1
    # bars are within 3 % at 50 elements (test_impact_exact); this 30-element P2 box was
    # within 0.5 % when written (0.17 % at half the mesh size), asserted at 2 %.
    length, side, v0, gap = 0.3, 1e-3, 0.1, 1e-7
    mat = fr.Material(young=110e9, rho=4500.0, poisson=0.0)
    blade = box_blade(span=length, chord=side, thickness=side, h=0.01, n_contact=1)
    disc = discretise(blade, clamped=False)
    mats = assemble(disc, mat, coupling="none")
    model, _ = rub_model(disc, mats, locate_contacts(disc), mat, casing=Concentric(gap))
    x0 = np.zeros(model.n_dofs)
    x0[model.layout.v] = v0 * (np.arange(disc.basis_u.N)[mats.free_u] % 3 == 2)
    exact = bar_impact(length, mat.young, mat.rho, side**2, v0, gap)
    h = 0.25 * 0.01 / np.sqrt(mat.young / mat.rho)  # Courant 1/2 on the P2 node spacing
    t_end = 1.5 * (exact.contact_start + exact.contact_duration)
    res = fr.ThetaMethod(model.with_(x0=x0), h).run(t_end, store_every=1)
    phases = res.contact_phases()
    assert len(phases) == 1 and phases[0][0] == pytest.approx(exact.contact_start, abs=2 * h)
    assert phases[0][1] - phases[0][0] == pytest.approx(exact.contact_duration, rel=0.02)
    assert res.impulse.sum() == pytest.approx(exact.impulse, rel=0.02)
    momentum = res.states[-1] @ (model.energy.Qk @ x0) / v0  # Σ m v_z
    mass = mat.rho * side**2 * length
    assert momentum / mass == pytest.approx(exact.rebound_velocity, rel=0.02)
