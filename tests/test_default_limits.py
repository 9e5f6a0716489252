"""Physical stop limits are on by default for every entry point, derived from the model."""

import json
import math

import numpy as np
import pytest

import femrub as fr
from femrub.app.cli import main
from femrub.output.limits import (
    MAX_DISPLACEMENT_RATIO,
    MAX_TEMPERATURE_RISE,
    default_limits,
    model_limits,
    run_limits,
)


@pytest.fixture(scope="module")
def hot_bar():
    """The paper's bar with α = 7 m/s: a thermal runaway."""
    return fr.bar_model(alpha=7.0)


def test_default_limits_bound_temperature_and_displacement_by_the_size():
    lim = default_limits(["tip_temperature", "tip_displacement", "tip_velocity"], 0.3)
    assert lim == {
        "tip_temperature": MAX_TEMPERATURE_RISE,
        "tip_displacement": MAX_DISPLACEMENT_RATIO * 0.3,
    }
    # a model that does not know its size gets no displacement limit
    assert default_limits(["tip_displacement"], math.nan) == {}


def test_run_limits_given_ones_replace_defaults_inf_removes_one(hot_bar):
    defaults = model_limits(hot_bar)
    assert defaults["tip_temperature"] == MAX_TEMPERATURE_RISE
    size = getattr(hot_bar, "length_scale", math.nan)
    if math.isfinite(size):
        assert defaults["tip_displacement"] == pytest.approx(MAX_DISPLACEMENT_RATIO * size)
    assert run_limits(hot_bar, {"tip_temperature": 10.0})["tip_temperature"] == 10.0
    assert "tip_temperature" not in run_limits(hot_bar, {"tip_temperature": math.inf})
    assert run_limits(hot_bar, {"contact_force": 5.0}, defaults=False) == {"contact_force": 5.0}


def test_python_run_of_a_runaway_diverges_physically_like_the_cli(hot_bar, tmp_path):
    res = fr.ThetaMethod(hot_bar, h=1e-4).run(0.4)
    assert res.status == "diverged-physically"
    assert res.message.startswith("tip_temperature exceeded 1500 at t = ")
    assert np.abs(res.signals["tip_temperature"]).max() < 1.1 * MAX_TEMPERATURE_RISE
    out = tmp_path / "out"
    args = ["run", "paper", "-o", str(out), "--quiet", "--no-cache"]
    args += ["--set", "contact.heat_coefficient=7", "--set", "scheme.h=1e-4"]
    main(args)
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["status"], summary["message"]) == (res.status, res.message)


def test_default_limits_can_be_turned_off(hot_bar):
    res = fr.ThetaMethod(hot_bar, h=1e-4).run(0.25, default_limits=False)
    assert res.status != "diverged-physically"
    assert np.abs(res.signals["tip_temperature"]).max() > MAX_TEMPERATURE_RISE
