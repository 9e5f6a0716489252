"""A Python run reaches ``t_end`` or says why not: a step that does not divide the time to
``t_end`` ends up to half a step from it with a warning naming where and both fixes (a
scene refuses such a step before any work: scene/run_checks.py)."""

import pytest

import femrub as fr


def test_a_step_that_does_not_divide_t_end_says_where_the_run_ended():
    res = fr.ThetaMethod(fr.bar_model(), h=3e-5).run(1e-4)
    assert res.t[-1] == pytest.approx(9e-5)
    (warning,) = [w for w in res.warnings if "steps of h" in w]
    assert "3.33333 steps" in warning and "ended at t = 9e-05 s" in warning
    assert "t_end = 0.00012 s" in warning and "h = 2.5e-05 s" in warning


def test_a_whole_number_of_steps_reaches_t_end_without_a_warning():
    res = fr.ThetaMethod(fr.bar_model(), h=2.5e-5).run(1e-4)
    assert res.t[-1] == pytest.approx(1e-4, rel=1e-12) and res.t.size == 5
    assert not [w for w in res.warnings if "steps of h" in w]


def test_a_run_to_its_start_takes_no_step_and_no_warning():
    res = fr.ThetaMethod(fr.bar_model(), h=2.5e-5).run(0.0)
    assert res.t.size == 1 and not [w for w in res.warnings if "steps of h" in w]
