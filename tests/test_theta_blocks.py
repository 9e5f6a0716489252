"""Compiled blocks of θ-method steps (femrub.steppers.theta_blocks) against the per-step path.

``run()`` advances dense models with history-free contacts in blocks of steps inside one
compiled call; the results must be those of the per-step path (``block_steps = False``) to
round-off, with the energy balance, and the same code must run as Python under
``NUMBA_DISABLE_JIT=1``.
"""

import pickle
from pathlib import Path

import numpy as np
import pytest
from jit_child import child_json

import femrub as fr
from femrub.cases.bar import bar_model
from femrub.contact.activation import RULES
from femrub.contact.jit import compiled

ROOT = Path(__file__).resolve().parents[1]

NACA = {
    "physics.thermal": "off",
    "contact.friction": 0.3,
    "scheme.t_end": 0.0006,
    "outputs.vtk_stride": 0,
    "contact.casing.depth": "200 um",
    "contact.casing.clearance": "5 um",
    "reduction.method": "craig-bampton",
    "reduction.n_uv": 12,
    "reduction.n_theta": 0,
    "contact.reach": "all",
}


def _close(a, b, rel):
    scale = max(float(np.abs(b).max()), 1e-300)
    np.testing.assert_allclose(a, b, rtol=0, atol=rel * scale)


def _both(make, t_end):
    out = []
    for blocks in (True, False):
        st = make()
        st.block_steps = blocks
        out.append((st.run(t_end), st))
    return out


@pytest.mark.parametrize("rule", RULES)
def test_one_contact_blocks_equal_the_steps(rule):
    m = bar_model()
    (a, sa), (b, sb) = _both(lambda: fr.ThetaMethod(m, 1e-4, activation=rule), 0.1)
    assert sa._block_kind == "one" and a.status == b.status == "ok"
    assert int((a.impulse > 0).sum()) > 10  # the bar rubs
    _close(a.impulse, b.impulse, 1e-12)
    _close(a.gap, b.gap, 1e-12)
    for k in ("energy_error", "heat_error", "kinetic"):
        _close(a.energy[k], b.energy[k], 1e-12)
    _close(sa.X, sb.X, 1e-12)
    assert (sa.k, sa.t) == (sb.k, sb.t)
    # the stepper goes on from where the block left it, as after step() calls
    _close(sa.step().X, sb.step().X, 1e-12)


@pytest.fixture(scope="module")
def naca(model_cache):
    from femrub.app import build
    from femrub.scene import load_scene

    scene = load_scene("twisted-naca", NACA)
    return build(scene, log=lambda s: None, cache=model_cache), scene


def test_frictional_blocks_equal_the_steps(naca):
    from femrub.analysis import make_stepper
    from femrub.app.scheme import scheme_options

    sim, scene = naca
    s = scene["scheme"]
    (a, sa), (b, sb) = _both(
        lambda: make_stepper(s["name"], sim.model, s["h"], **scheme_options(scene)), s["t_end"]
    )
    assert sa._block_kind == "friction" and a.status == b.status == "ok", a.message
    assert int((a.contact_state > 0).any(axis=1).sum()) > 50  # rubs, several contacts
    _close(a.impulse, b.impulse, 1e-9)
    _close(a.friction_force, b.friction_force, 1e-9)
    _close(a.gap, b.gap, 1e-9)
    np.testing.assert_array_equal(a.contact_state, b.contact_state)
    scale = np.abs(b.energy["kinetic"]).max() + np.abs(b.energy["elastic"]).max()
    np.testing.assert_allclose(
        a.energy["energy_error"], b.energy["energy_error"], atol=1e-9 * scale
    )
    _close(sa.X, sb.X, 1e-9)
    _close(sa.step().X, sb.step().X, 1e-9)


def test_a_history_dependent_contact_keeps_the_per_step_path():
    m = bar_model()
    st = fr.ThetaMethod(m, 1e-4, activation="position")
    assert st._block_kind == "one"
    from femrub.steppers.theta_blocks import block_kind

    st._lu.dense = False  # a sparse model: no block
    assert block_kind(st) is None


_CHILD = """
import json, pickle
import femrub as fr
from femrub.cases.bar import bar_model
from femrub.analysis import make_stepper
from femrub.contact.jit import compiled
r = fr.ThetaMethod(bar_model(), 1e-4, activation="paper").run(0.05)
d = pickle.load(open(%r, "rb"))
st = make_stepper(d["scheme"]["name"], d["model"], d["scheme"]["h"], **d["opts"])
f = st.run(d["scheme"]["t_end"])
print(json.dumps({"jit": compiled(), "kind": st._block_kind, "bar": r.impulse.tolist(),
                  "P": f.impulse.tolist(), "Pt": f.friction_force.tolist()}))
"""


@pytest.mark.skipif(not compiled(), reason="kernels not compiled (NUMBA_DISABLE_JIT)")
def test_blocks_run_as_python_without_jit(naca, tmp_path):
    """The bar and the frictional blade (the model built here, pickled) stepped in blocks by
    two fresh interpreters, numba off and on."""
    from femrub.app.scheme import scheme_options

    sim, scene = naca
    path = tmp_path / "model.pkl"
    model = {"model": sim.model, "scheme": scene["scheme"], "opts": scheme_options(scene)}
    path.write_bytes(pickle.dumps(model))
    code = _CHILD % str(path)
    py, jit = child_json(code, False), child_json(code, True)
    assert not py["jit"] and jit["jit"] and py["kind"] == jit["kind"] == "friction"
    _close(np.array(py["bar"]), np.array(jit["bar"]), 1e-12)
    # LLVM may contract a*b + c into one FMA on CPUs that have it (CI's did): the stick-slip
    # trajectory of the blade carries those last-bit differences to ~1e-9 after 300 steps.
    _close(np.array(py["P"]), np.array(jit["P"]), 1e-7)
    _close(np.array(py["Pt"]), np.array(jit["Pt"]), 1e-7)


def test_a_block_interrupted_or_failing_keeps_the_checked_rows(monkeypatch):
    """Ctrl-C or an exception inside a block: the rows of the blocks before it are kept."""
    import femrub.steppers.theta_blocks as tb

    real, calls, error = tb.one_contact_block, [0], [None]

    def block(*args):
        calls[0] += 1
        if calls[0] == 3:
            raise error[0]
        return real(*args)

    monkeypatch.setattr(tb, "one_contact_block", block)
    monkeypatch.setattr("femrub.output.recorder.CHUNK_STEPS", 64)
    for what, status in ((KeyboardInterrupt(), "interrupted"), (RuntimeError("x"), "failed")):
        calls[0], error[0] = 0, what
        res = fr.ThetaMethod(bar_model(), 1e-4).run(0.05)
        assert res.status == status and 64 <= res.steps <= 128, (res.status, res.steps)


def test_a_failed_frictional_solve_in_a_block_ends_the_run_unstable(naca, monkeypatch):
    """A contact solve that fails inside a block: the steps before it are checked and kept,
    the run ends ``unstable`` with the solver's message (as step by step)."""
    import femrub.steppers.theta_blocks as tb
    from femrub.analysis import make_stepper
    from femrub.app.scheme import scheme_options

    real = tb.friction_block

    def block(*args):
        args = list(args)
        for i in range(-5, 0):
            args[i] = args[i][:10]
        done, status, res, warm = real(*args)
        return done, 1, 0.5, warm  # NOT_SOLVED after 10 steps

    monkeypatch.setattr(tb, "friction_block", block)
    sim, scene = naca
    s = scene["scheme"]
    st = make_stepper(s["name"], sim.model, s["h"], **scheme_options(scene))
    res = st.run(s["t_end"])
    assert res.status == "unstable" and "not solved" in res.message
    assert res.steps == 10 and st.k == 10
