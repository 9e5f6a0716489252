"""The stability limit (an eigen-solve for Carpenter) is computed once per stepper."""

import math

import femrub as fr
from femrub.steppers import carpenter


def test_carpenter_stability_limit_computed_once(monkeypatch):
    calls = []
    solve = carpenter.largest_modulus

    def counted(A, B):
        calls.append(1)
        return solve(A, B)

    monkeypatch.setattr(carpenter, "largest_modulus", counted)
    stepper = fr.Carpenter(fr.bar_model(alpha=3.0), 1e-6)
    first = stepper.stability_limit()
    n_solves = len(calls)  # mechanical and thermal parts
    assert n_solves == 2
    res = stepper.run(1e-4)
    assert stepper.stability_limit() == first == res.info["stability_limit"]
    assert len(calls) == n_solves


def test_unconditionally_stable_schemes_have_no_limit():
    model = fr.bar_model()
    assert math.isinf(fr.ThetaMethod(model, 1e-5).stability_limit())
    assert math.isinf(fr.Penalty(model, 1e-5, stiffness=1e7).stability_limit())
