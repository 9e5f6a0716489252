"""Elastic bar impacting a rigid obstacle vs the exact solution (Doyen, Ern, Piperno 2011)."""

import bar_impact as ex
import pytest


@pytest.mark.parametrize("row", ex.rows, ids=lambda r: f"{r['scheme']}-{r['n_elements']}")
def test_impact_matches_exact_solution(row):
    exact = ex.exact
    tol = 0.03 if row["n_elements"] == 50 else 0.012
    assert row["contact_start"] == pytest.approx(exact.contact_start, abs=2 * row["h"])
    assert row["contact_duration"] == pytest.approx(exact.contact_duration, rel=tol)
    assert row["impulse"] == pytest.approx(exact.impulse, rel=tol)
    assert row["mean_force"] == pytest.approx(exact.contact_force, rel=tol)
    assert row["rebound_velocity"] == pytest.approx(exact.rebound_velocity, rel=tol)


def test_impact_converges_with_mesh():
    err = {}
    for r in ex.rows:
        if r["scheme"] == "theta":
            err[r["n_elements"]] = abs(r["rebound_velocity"] / ex.exact.rebound_velocity - 1)
    assert err[200] < 0.5 * err[50]


def test_exponential_stepper_has_no_dispersion():
    """At Courant 0.5 and 8 the exponential stepper gives the same impulse and rebound (the
    mesh's error only), within 1.5 % of the exact ones; the θ-method's error grows."""
    exact, runs = ex.exact, {(r["scheme"], r["courant"]): r for r in ex.courant_rows}
    fine, coarse = runs["exponential", 0.5], runs["exponential", 8.0]
    for key in ("impulse", "rebound_velocity"):  # θ's differ by percents
        assert coarse[key] == pytest.approx(fine[key], rel=2e-6)
    assert coarse["impulse"] == pytest.approx(exact.impulse, rel=0.015)
    assert coarse["rebound_velocity"] == pytest.approx(exact.rebound_velocity, rel=0.015)
    assert coarse["energy_error"] < 1e-9

    def err(r):
        return abs(r["rebound_velocity"] / exact.rebound_velocity - 1)

    assert err(runs["theta", 8.0]) > 3 * max(err(runs["theta", 0.5]), err(coarse))
