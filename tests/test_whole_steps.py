"""A Python run reaches ``t_end`` or says why not: a step that does not divide the time to
``t_end`` is refused with both fixes (the scene path refuses it too: scene/run_checks.py)."""

import pytest

import femrub as fr


def test_a_step_that_does_not_divide_t_end_is_refused_with_both_fixes():
    stepper = fr.ThetaMethod(fr.bar_model(), h=3e-5)
    with pytest.raises(ValueError, match=r"3\.33333 steps.*t_end = 0\.00012 s.*h = 2\.5e-05 s"):
        stepper.run(1e-4)
    with pytest.raises(ValueError, match="not a whole number"):
        next(iter(stepper.iterate(1e-4)))


def test_a_whole_number_of_steps_reaches_t_end():
    res = fr.ThetaMethod(fr.bar_model(), h=2.5e-5).run(1e-4)
    assert res.t[-1] == pytest.approx(1e-4, rel=1e-12) and res.t.size == 5
