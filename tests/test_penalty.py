"""Penalty baseline (Radau/BDF with restarts at contact switches) converges to the MDI."""

import numpy as np
import pytest

import femrub as fr

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
