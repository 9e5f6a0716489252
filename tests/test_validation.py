"""Bad input gets a clear one-line error."""

import math

import pytest

import femrub as fr


@pytest.mark.parametrize("h", [0.0, -1e-4, math.nan, math.inf, "abc"])
def test_bad_step(h):
    with pytest.raises(ValueError, match="time step h"):
        fr.ThetaMethod(fr.bar_model(), h)
    with pytest.raises(ValueError, match="time step h"):
        fr.Carpenter(fr.bar_model(), h)


@pytest.mark.parametrize("t_end", [-0.1, math.nan])
def test_bad_end_time(t_end):
    with pytest.raises(ValueError, match="t_end"):
        fr.ThetaMethod(fr.bar_model(), 1e-4).run(t_end)


@pytest.mark.parametrize("e", [-0.1, 1.5, math.nan])
def test_bad_restitution(e):
    with pytest.raises(ValueError, match="restitution"):
        fr.bar_model(restitution=e)


def test_unknown_scheme_and_rule():
    with pytest.raises(ValueError, match="unknown scheme 'rk4'; use one of theta, carpenter"):
        fr.make_stepper("rk4", fr.bar_model(), 1e-4)
    with pytest.raises(ValueError, match="activation rule"):
        fr.ThetaMethod(fr.bar_model(), 1e-4, activation="sometimes")
    with pytest.raises(ValueError, match="gamma"):
        fr.ThetaMethod(fr.bar_model(), 1e-4, gamma=0.2)


@pytest.mark.parametrize(
    "key,value,match",
    [
        ("gap", math.nan, "gap must be finite"),
        ("young", math.nan, "young must be finite"),
        ("young", -1.0, "young must be > 0"),
        ("alpha", -1.0, "alpha must be >= 0"),
        ("length", 0.0, "length must be > 0"),
        ("n_elements", 0, "n_elements"),
        ("coupling", "magic", "unknown coupling"),
        ("beta", math.nan, "finite beta"),
    ],
)
def test_bad_parameters(key, value, match):
    with pytest.raises(ValueError, match=match):
        fr.bar_model(**{key: value})


def test_unknown_stop_signal():
    with pytest.raises(ValueError, match="unknown signal"):
        fr.ThetaMethod(fr.bar_model(), 1e-4).run(0.01, limits={"tip_pressure": 1.0})


def test_errors_are_one_line():
    for call in (
        lambda: fr.bar_model(gap=math.nan),
        lambda: fr.ThetaMethod(fr.bar_model(), -1),
        lambda: fr.make_stepper("x", fr.bar_model(), 1e-4),
    ):
        with pytest.raises(ValueError) as info:
            call()
        assert "\n" not in str(info.value)
