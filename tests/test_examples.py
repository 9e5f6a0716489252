"""The examples run and give the reference values."""

import pytest


def test_paper_bar_example():
    import paper_bar as ex

    assert ex.theta.status == ex.carpenter.status == "ok"
    assert 4e-3 < ex.first_contact_time < 5e-3
    # Carpenter (1e-5 s) and the θ-method (1e-4 s) give the same heating within 10 %
    Tc = ex.carpenter.signal("tip_temperature")[-1]
    assert ex.tip_temperature_end == pytest.approx(Tc, rel=0.1)
    assert ex.tip_temperature_end > 5 * ex.theta_uncoupled.signal("tip_temperature")[-1]
    assert 2e-5 < ex.carpenter_limit < 3e-5
