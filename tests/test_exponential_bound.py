"""The least-cost study of the exponential stepper (benchmarks/exponential_bound.py)."""

import pytest


@pytest.fixture(scope="module")
def eb(load_benchmark):
    return load_benchmark("exponential_bound")


@pytest.mark.parametrize(
    "rho, count",
    [
        (0.0, 2),  # degree 3, no squaring
        (0.01, 2),  # below θ_3
        (0.2, 3),  # degree 5
        (5.0, 6),  # degree 13, no squaring
        (5.4, 7),  # one squaring of degree 13 (6 + 1), or degree 9 + 2 squarings = 7
        (153.0, 11),  # the paper case at h = 2e-3 s: 6 + ⌈log₂(153 / 5.37)⌉
    ],
)
def test_least_products_of_scaling_and_squaring(eb, rho, count):
    assert eb.products(rho) == count


def test_bound_on_the_paper_bar(eb):
    """A short paper run: the split of θ's run and the budgets follow their definitions."""
    import femrub as fr

    model = fr.bar_model(alpha=3.0, coupling="paper")
    rows = [
        {"method": "θ paper", "h": 1e-3, "cpu": 1.0, "T_end": 0.005},
        {"method": "exponential", "h": 2e-3, "cpu": 1.0, "T_end": 0.002},
        {"method": "exponential", "h": 1e-3, "cpu": 2.0, "T_end": 0.02},  # not within 1 %
    ]
    makers = {"θ paper": lambda h: fr.ThetaMethod(model, h)}
    row = eb._case("paper", model, rows, makers, 0.01, lambda s: None, "cheapest within 1 %")
    assert row["other"] == "θ paper" and row["steps"] == 10 and row["exp_h"] == 2e-3
    assert row["budget_free"] == pytest.approx((row["constructor"] + row["stepping"]) / 3)
    assert row["budget_now"] == pytest.approx(row["run"] / 3 - row["shared"])
    assert row["held_sets"] >= 1 and row["n_z"] > model.n_dofs
    assert 0 < row["ideal"] and 0 < row["expm"] and row["exp_run"] > 0
    assert row["verdict"] in ("infeasible", "infeasible as the code stands", "not excluded")
    # no exponential run within 1 %: no row
    none = eb._case("paper", model, rows[::2], makers, 0.01, lambda s: None, "cheapest within 1 %")
    assert none is None


def test_steady_reading_skips_a_lucky_coarse_step(load_benchmark):
    """θ within 1 % at 1e-3 s, above it at 2e-4 s, within it below: the steady run is 1e-4."""
    report = load_benchmark("exponential_levels")
    rows = [
        {"method": "θ paper", "h": h, "cpu": 1 / h, "T_end": e}
        for h, e in ((1e-3, 0.009), (2e-4, 0.012), (1e-4, 0.006), (5e-5, 0.001))
    ]
    assert report.cheapest(rows, "T_end", 0.01)["θ paper"]["h"] == 1e-3
    assert report.steadily(rows, "T_end", 0.01)["θ paper"]["h"] == 1e-4
    assert report.steadily(rows[:2], "T_end", 0.01) == {}
