"""Activation rules (femrub.contact.activation): closed forms, no force at an open gap."""

import numpy as np
import pytest

import femrub as fr
from femrub.cases.paper import Run, run_case
from femrub.contact.activation import RULES, impulse_one, impulses


@pytest.mark.parametrize("rule", RULES)
def test_scalar_closed_form_matches_general_solver(rule):
    rng = np.random.default_rng(0)
    h, gamma = 1e-4, 0.5
    for _ in range(200):
        g_k, gd_k, gd_p = rng.normal(0, 1e-6), rng.normal(0, 1e-2), rng.normal(0, 1e-2)
        g_p = g_k + 0.5 * h * (gd_k + gd_p)  # trapezoidal free step
        w, e = rng.uniform(1, 10), rng.choice([0.0, 0.5, 1.0])
        gz = 0.5 * h * w
        a = impulse_one(rule, g_k, gd_k, g_p, gd_p, w, gz, e, h, gamma)
        b = impulses(
            rule,
            *(np.array([x]) for x in (g_k, gd_k, g_p, gd_p)),
            np.array([[w]]),
            np.array([[gz]]),
            np.array([e]),
            h,
            gamma,
        )[0]
        assert a == pytest.approx(b, rel=1e-9, abs=1e-18)


@pytest.mark.parametrize("rule", ["position", "capped"])
def test_default_rules_never_push_at_an_open_gap(rule):
    res, _ = run_case(Run("x", h=1e-4, activation=rule))
    F, gap = res.force[:, 0], res.gap[:, 0]
    assert F.max() > 0
    assert np.all(gap[F > 0] <= 1e-15)
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)
    assert res.energy_error() < 1e-9


def test_position_rule_accuracy_on_the_paper_case():
    # tip temperature at 0.4 s: h = 1e-4 s against h = 1e-5 s (docs/paper-reproduction.md
    # compares every rule with h = 1e-6 s)
    T = [run_case(Run("x", h=h))[0].signal("tip_temperature")[-1] for h in (1e-4, 1e-5)]
    assert T[0] == pytest.approx(T[1], rel=0.02)


def test_plain_rule_can_create_energy():
    res, _ = run_case(Run("x", h=1e-4, activation="plain"))
    assert np.diff(res.energy["contact_work"]).max() > 1e-9


def test_unknown_rule_is_rejected():
    with pytest.raises(ValueError, match="position"):
        fr.ThetaMethod(fr.bar_model(), 1e-4, activation="sometimes")


@pytest.mark.parametrize("rule", ["position", "capped"])
def test_two_contacts_complementarity_and_no_open_push(rule):
    from test_multicontact import _two_contact_bar

    model = _two_contact_bar()
    st = fr.ThetaMethod(model, 1e-4, activation=rule)
    both, prev = 0, None
    for s in st.iterate(0.1):
        P = s.impulse
        assert np.all(P >= 0.0)
        both += int(np.all(P > 0))
        if prev is not None:
            target = np.minimum(prev, 0.0)  # e = 0
            assert np.all(s.gap[P > 0] <= target[P > 0] + 1e-15)  # never lifted, never open
            if rule == "position":  # Signorini at the target: closed exactly where P > 0
                assert np.all(s.gap >= target - 1e-15)
                assert np.all(np.abs(s.gap - target)[P > 0] <= 1e-15)
        prev = s.gap.copy()
    assert both > 10
    res = fr.ThetaMethod(model, 1e-4, activation=rule).run(0.1)
    assert res.status == "ok" and res.energy_error() < 1e-9
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)


def _landing(rule=None):
    """A mass falling 10.85 µm onto a belt (friction 0.3), lands, slides: a θ-method run.
    At t = 1.4 ms its gap ``g_k`` is 0.75 h |ġ_k|: the free step crosses the belt (``"paper"``
    acts) but ``g_k + h ġ_k / 2 > 0`` (``"predicted"`` waits a step)."""
    from dataclasses import replace

    from test_friction import block_model

    model = block_model(v_belt=0.1)
    model = model.with_(contact=replace(model.contact, gap0=1.085e-5))
    st = fr.ThetaMethod(model, 1e-4, activation=rule)
    return st, st.run(0.01)


@pytest.mark.parametrize("rule", ["position", "capped", "plain"])
def test_a_rule_without_a_frictional_form_is_refused_with_friction(rule):
    with pytest.raises(ValueError, match=f"activation '{rule}' with friction.*'paper' or"):
        _landing(rule)


def test_frictional_contacts_run_the_paper_rule_by_default_and_the_rule_changes_the_run():
    st, default = _landing()
    assert st.activation == "paper"
    _, paper = _landing("paper")
    _, predicted = _landing("predicted")
    for res in (default, paper, predicted):
        assert res.status == "ok" and res.impulse.max() > 0
    np.testing.assert_array_equal(default.impulse, paper.impulse)
    assert not np.array_equal(paper.impulse, predicted.impulse)
    assert not np.array_equal(paper.friction_force, predicted.friction_force)


def test_the_scene_refuses_a_rule_without_a_frictional_form_and_explain_prints_the_rule():
    from femrub.app.scheme import stepper_of
    from femrub.scene import SceneError, load_scene

    with pytest.raises(SceneError, match=r"scheme\.activation.*'position'.*contact\.friction"):
        load_scene("twisted-naca", {"contact.friction": 0.3, "scheme.activation": "position"})
    scene = load_scene("twisted-naca", {"contact.friction": 0.3})
    assert scene["scheme"].get("activation") is None  # the stepper's default for its contacts
    st, _ = _landing()
    report = {}
    stepper_of(scene, st.model, report)
    assert report["scheme"]["activation"] == "paper"
