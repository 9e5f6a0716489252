"""No scheme creates energy: impacts with e <= 1 and no load (θ-method, γ = 1/2)."""

import numpy as np
import pytest

import femrub as fr


def _free_vibration(e, n_elements=20):
    # a clamped bar released with a uniform velocity towards the casing: many impacts
    return fr.bar_model(
        force_amplitude=0.0,
        coupling="none",
        alpha=0.0,
        restitution=e,
        initial_velocity=0.05,
        gap=5e-6,
        n_elements=n_elements,
    )


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("activation", ["position", "capped", "paper", "predicted"])
def test_energy_never_increases(e, activation):
    model = _free_vibration(e)
    res = fr.ThetaMethod(model, 2e-5, activation=activation).run(0.05)
    E = res.energy["kinetic"] + res.energy["elastic"]
    assert len(res.contact_phases()) >= 5
    assert np.all(np.diff(E) <= 1e-12 * E[0])
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)
    assert res.energy_error() < 1e-9


def test_elastic_impacts_conserve_energy():
    res = fr.ThetaMethod(_free_vibration(1.0), 2e-5).run(0.05)
    E = res.energy["kinetic"] + res.energy["elastic"]
    assert len(res.contact_phases()) >= 5
    assert np.max(np.abs(E / E[0] - 1)) < 1e-9


def test_inelastic_impacts_dissipate():
    res = fr.ThetaMethod(_free_vibration(0.0), 2e-5).run(0.05)
    E = res.energy["kinetic"] + res.energy["elastic"]
    assert E[-1] < 0.99 * E[0]
    assert res.energy["impact_dissipation"][-1] == pytest.approx(E[0] - E[-1], rel=1e-8)


def test_heat_balance_closes_on_paper_case():
    res = fr.ThetaMethod(fr.bar_model(alpha=3.0), 1e-4).run(0.2)
    e = res.energy
    assert e["friction_heat"][-1] > 0
    assert np.max(np.abs(e["heat_error"])) < 1e-9 * e["friction_heat"][-1]
    # the frictional heat is α times the total impulse
    assert e["friction_heat"][-1] == pytest.approx(3.0 * res.impulse.sum(), rel=1e-12)
