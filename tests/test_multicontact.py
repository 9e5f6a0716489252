"""Several contact nodes: the per-step LCP is solved exactly by both steppers."""

import numpy as np
import pytest

import femrub as fr
from femrub.model.build import ContactSpec, Load, first_order_model


def _two_contact_bar(e=0.0, alpha=2.0):
    mats, tip = fr.bar_matrices(fr.PAPER)
    mid = tip // 2
    normals = np.zeros((2, mats.n_u))
    normals[0, tip] = 1.0
    normals[1, mid] = 1.0
    f = np.zeros(mats.n_u)
    f[tip] = 7.0
    f[mid] = 7.0
    contact = ContactSpec(
        normals=normals,
        gap=[15e-6, 6e-6],
        heat_dofs=[tip, mid],
        restitution=e,
        heat_coefficient=alpha,
    )
    return first_order_model(
        mats,
        contact=contact,
        loads=[Load(f, lambda t: np.sin(209.44 * t))],
        observe={"u_contacts": ("u", [tip, mid]), "v_contacts": ("v", [tip, mid])},
    )


@pytest.mark.parametrize("activation", ["paper", "predicted"])
def test_theta_lcp_complementarity(activation):
    model = _two_contact_bar()
    st = fr.ThetaMethod(model, 1e-4, activation=activation)
    both, prev = 0, None
    for s in st.iterate(0.1):
        P = s.impulse
        assert np.all(P >= 0.0)
        if np.all(P > 0):
            both += 1
        if prev is not None:
            # impact law variable U = (ġ_{k+1} + e ġ_k)/(1 + e), e = 1 if separating at t_k
            e = np.where(prev > 0, 1.0, 0.0)
            U = (s.gap_velocity + e * prev) / (1 + e)
            scale = 1e-12 * (1 + np.abs(s.gap_velocity).max())
            assert np.all(U[P > 0] >= -scale)
            assert np.all(np.abs(P * U) <= scale * (1 + P.max()))
        prev = s.gap_velocity.copy()
    assert both > 10  # both contacts closed at once in many steps: the LCP path is used
    res = fr.ThetaMethod(model, 1e-4, activation=activation).run(0.1)
    assert res.status == "ok" and res.energy_error() < 1e-9
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)


def test_carpenter_several_contacts_zero_gap():
    model = _two_contact_bar()
    res = fr.Carpenter(model, 1e-5).run(0.05)
    assert res.status == "ok"
    closed = res.impulse > 0
    assert closed[:, 0].any() and closed[:, 1].any()
    assert np.all(np.abs(res.gap[closed]) < 1e-15)  # projection: gap exactly zero
    assert res.gap.min() > -1e-15


def test_theta_and_carpenter_agree_with_two_contacts():
    model = _two_contact_bar()
    th = fr.ThetaMethod(model, 1e-5).run(0.05)
    ca = fr.Carpenter(model, 1e-5).run(0.05)
    for j in range(2):
        a, b = th.signal("u_contacts", j), ca.signal("u_contacts", j)
        assert np.sqrt(np.mean((a - b) ** 2)) < 0.05 * np.sqrt(np.mean(a**2))
    assert th.energy["friction_heat"][-1] == pytest.approx(ca.energy["friction_heat"][-1], rel=0.05)
