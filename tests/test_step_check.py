"""The a-posteriori time-step check (``scheme.step_check``, femrub.analysis.step_check)."""

import json

import numpy as np
import pytest

from femrub.analysis import ThetaMethod
from femrub.analysis.step_check import ORDER, coarsen
from femrub.app.simulation import build
from femrub.scene import load_scene
from femrub.scene.spec import SceneError

T_END = 0.06  # s: two contact phases of the paper case


def _paper(h, **changes):
    return load_scene(
        "paper", {"scheme.step_check": True, "scheme.h": h, "scheme.t_end": T_END, **changes}
    )


def test_coarsen_keeps_impulses_and_the_coarse_times():
    sim = build(load_scene("paper", {"scheme.h": 5e-5, "scheme.t_end": T_END}))
    res = ThetaMethod(sim.model, 2.5e-5).run(T_END)
    c = coarsen(res, 2)
    assert c.h == pytest.approx(5e-5)
    np.testing.assert_allclose(c.t, res.t[::2])
    np.testing.assert_allclose(c.signals["tip_temperature"], res.signals["tip_temperature"][::2])
    np.testing.assert_allclose(c.impulse.sum(axis=0), res.impulse.sum(axis=0), rtol=1e-13)
    # each coarse row holds the two fine steps ending at its time
    k = int(np.argmax(c.impulse[:, 0]))
    assert c.impulse[k, 0] == pytest.approx(res.impulse[2 * k - 1, 0] + res.impulse[2 * k, 0])


def test_the_estimate_is_twice_the_measured_difference_to_the_half_step_run():
    h = 5e-4
    sim = build(_paper(h))
    err = sim.report["time_step"]
    # the two runs, stepped independently here
    a = ThetaMethod(sim.model, h).run(T_END)
    b = ThetaMethod(sim.model, h / 2).run(T_END)
    ta, tb = a.signals["tip_temperature"][:, 0], b.signals["tip_temperature"][::2, 0]
    n = min(ta.size, tb.size)
    direct = np.abs(ta[:n] - tb[:n]).max() / np.abs(tb[:n]).max()
    assert err["contact_temperature"] == pytest.approx(direct, rel=1e-9)
    assert err["difference"] >= err["contact_temperature"]
    assert err["estimate"] == pytest.approx(err["difference"] * 2**ORDER / (2**ORDER - 1))
    assert (err["h"], err["reference_h"]) == (h, h / 2)
    assert err["decided_by"] in (
        "contact_force",
        "contact_temperature",
        "displacement",
        "displacement_end",
        "temperature_end",
    )


@pytest.mark.parametrize("h", [1e-3, 1e-5])
def test_the_verdict_follows_the_estimate(tmp_path, h):
    from femrub.app.run import run_scene

    res, built = run_scene(_paper(h), tmp_path / "out")
    doc = json.loads((tmp_path / "out" / "summary.json").read_text())
    err = doc["time_step_error"]
    assert err["estimate"] == pytest.approx(built.report["time_step"]["estimate"])
    assert "step_check" in doc["timings"]
    if err["estimate"] > err["tolerance"]:
        assert doc["status"] == "inaccurate"
        assert "scheme.h <=" in doc["message"] and "time-step error" in doc["message"]
        # the suggested step brings an order-1 error to the tolerance
        suggested = float(doc["message"].split("scheme.h <= ")[1].split()[0])
        assert suggested == pytest.approx(
            min(0.5, err["tolerance"] / err["estimate"]) * h,
            rel=5e-3,  # 3 digits
        )
    else:
        assert doc["status"] == "ok"
    if h == 1e-3:  # 30 steps per load period: far from converged
        assert doc["status"] == "inaccurate"
        assert "sensitivity" in err  # the twin measured how sensitive the response is


def test_the_full_run_at_h_is_stepped_once():
    lines = []
    sim = build(_paper(1e-4), log=lines.append)
    assert sim.ran is not None  # the check's run at h is the scene's run
    assert sim.ran[0].h == 1e-4 and sim.ran[0].steps == round(T_END / 1e-4)


def test_a_reduced_run_reuses_the_estimates_run():
    lines = []
    changes = {"reduction.method": "craig-bampton", "reduction.n_uv": 3, "reduction.n_theta": 12}
    sim = build(_paper(1e-4, **changes), log=lines.append)
    text = "\n".join(lines)
    assert "time-step check: run at h/2" in text
    assert "time-step check: run at h =" not in text  # the estimate's run of these sizes
    assert "estimate" in sim.report["time_step"]


def test_off_by_default_and_bad_input():
    assert "time_step" not in build(load_scene("paper", {"scheme.t_end": 0.01})).report
    with pytest.raises(SceneError, match="scheme.step_tolerance"):
        load_scene("paper", {"scheme.step_tolerance": 0.0})
    with pytest.raises(SceneError, match="scheme.step_check"):
        load_scene("paper", {"scheme.step_check": "sometimes"})


def test_a_coated_run_is_checked_against_a_fresh_coating(tmp_path):
    """The check builds its h/2 stepper before it runs at h: on an abradable coating that
    run must still start on a fresh coating, not on the one the run at h wore."""
    from test_abradable import SCENE

    path = tmp_path / "bar.toml"
    path.write_text(SCENE.format(e=50e-6))
    scene = load_scene(str(path), {"scheme.step_check": True, "scheme.t_end": 0.06})
    err = build(scene).report["time_step"]
    assert err["status_reference"] == "ok"
    assert err["estimate"] < 0.05  # a quasi-static cut: converged in h
