"""Penalty baseline (Radau/BDF with restarts at contact switches) converges to the MDI."""

import numpy as np
import pytest

import femrub as fr
from femrub.cases.bar import PAPER, bar_matrices, rpm
from femrub.cases.paper import contact_phases
from femrub.contact.casing import Lobed
from femrub.model.build import ContactSpec, Load, first_order_model

T_END = 0.012  # the first contact phase


@pytest.fixture(scope="module")
def reference():
    return fr.ThetaMethod(fr.bar_model(alpha=3.0), 1e-6).run(T_END, energy=False)


def _err(res, ref):
    u = np.interp(ref.t, res.t, res.signal("tip_displacement"))
    r = ref.signal("tip_displacement")
    return np.sqrt(np.mean((u - r) ** 2)) / np.sqrt(np.mean(r**2))


def test_penalty_converges_with_stiffness(reference):
    errs, pens = [], []
    for k in (1e6, 1e8):
        res = fr.Penalty(fr.bar_model(alpha=3.0), 1e-5, stiffness=k).run(T_END)
        assert res.status == "ok"
        errs.append(_err(res, reference))
        pens.append(-res.gap.min())
        # the impulse integrated with the state gives the same frictional heat balance
        assert res.energy["heat_error"][-1] == pytest.approx(
            0.0, abs=1e-6 * res.energy["friction_heat"][-1]
        )
    assert errs[1] < 0.3 * errs[0] and errs[1] < 0.02
    assert pens[1] < 0.05 * pens[0]  # penetration ~ force / k_p


@pytest.mark.parametrize("method", ["Radau", "BDF"])
def test_penalty_methods_and_input(method, reference):
    res = fr.Penalty(fr.bar_model(alpha=3.0), 1e-5, stiffness=1e7, method=method).run(T_END)
    assert res.status == "ok" and _err(res, reference) < 0.05
    with pytest.raises(ValueError, match="penalty stiffness"):
        fr.Penalty(fr.bar_model(), 1e-5, stiffness=-1.0)
    with pytest.raises(ValueError, match="unknown method"):
        fr.Penalty(fr.bar_model(), 1e-5, stiffness=1e7, method="RK45")


# -- a rotating lobed casing: the dashpot acts on the relative gap velocity ġ0(t) + Gvᵀ X --
CASING = Lobed(clearance=20e-6, depth=60e-6, lobes=2, phase=np.pi / 2)  # open at t = 0
SPEED = rpm(3000.0)  # rotor speed (rad/s): one lobe passes the tip in t ∈ (2.8, 7.4) ms
T_LOBE = 0.008  # one passage of a lobe, entry to exit
K_LOBE = 3e7  # penalty stiffness (N/m): penetration λ/k <= 1 µm, i.e. 2.5 % of the intrusion
TIP_MASS = 0.1 / 40  # lumped tip mass (kg): total mass / (2 n_elements)


def _lobed_bar():
    """The paper bar (no heat) rubbing the rotating lobed casing, in gap form with ġ0 != 0."""
    case = PAPER.with_(alpha=0.0)
    mats, tip = bar_matrices(case)
    e_tip = np.zeros(mats.n_u)
    e_tip[tip] = 1.0
    om = case.force_frequency
    spec = ContactSpec(
        normals=e_tip[None, :],
        gap=lambda t: np.atleast_1d(CASING.gap(SPEED * t)),
        gap_rate=lambda t: np.atleast_1d(SPEED * CASING.slope(SPEED * t)),
    )
    load = Load(case.force_amplitude * e_tip, lambda t: np.sin(om * t), "u", "tip_force")
    return first_order_model(
        mats, contact=spec, loads=[load], observe={"tip_displacement": ("u", [tip])}
    )


def _phase_impulses(res):
    """Impulse (N s) of each contact phase, bursts closer than 0.1 ms merged."""
    phases = contact_phases(res, merge=1e-4)
    return phases, [res.impulse[(res.t >= a) & (res.t <= b)].sum() for a, b in phases]


def test_penalty_damping_follows_moving_casing():
    """Penalty with a critically damped contact converges to the MDI on a moving casing.

    With the casing's own gap rate ġ0 dropped, the dashpot acts on the tip's absolute
    velocity: while the lobe recedes it pushes the tip along its velocity (negative damping)
    and the run blows up (status "unstable") before the lobe has passed. Tolerances: the
    penalty solution differs from the rigid-contact limit by O(λ/k), falling as 1/k; at
    this k the penetration λ/k is 2.5 % of the intrusion, and the bounds allow about one
    (impulse), three (displacement, exit time shifted) such errors.
    """
    model = _lobed_bar()
    ref = fr.ThetaMethod(model, 1e-6).run(T_LOBE, energy=False)
    damping = 2.0 * np.sqrt(K_LOBE * TIP_MASS)  # critical damping of the tip on the spring
    res = fr.Penalty(model, 1e-5, stiffness=K_LOBE, damping=damping).run(T_LOBE, energy=False)
    assert res.status == "ok", res.message
    (ph_ref, p_ref), (ph, p) = _phase_impulses(ref), _phase_impulses(res)
    assert len(ph) == len(ph_ref) == 1  # one lobe, one contact phase
    assert p == pytest.approx(p_ref, rel=0.03)
    assert ph[0] == pytest.approx(ph_ref[0], abs=1e-4)  # entry and exit within 0.1 ms
    u = np.interp(ref.t, res.t, res.signal("tip_displacement"))
    r = ref.signal("tip_displacement")
    assert np.max(np.abs(u - r)) < 0.08 * np.max(np.abs(r))
