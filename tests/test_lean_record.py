"""Lean records (``Stepper.run(lean=k)``, femrub.output.kept_rows): runs held only to be
compared keep what the comparison reads, coarsened on the fly, and never store the rest;
their verdict is the one the whole arrays would give."""

import inspect
import tracemalloc

import numpy as np
import pytest
from test_rub_blocks import SCENE  # a frictional coated blade, power heat, 300 steps

import femrub as fr
from femrub.analysis import make_stepper
from femrub.analysis.step_check import coarsen
from femrub.contact.friction import coulomb_check


@pytest.fixture(scope="module")
def blade(model_cache):
    from femrub.app import build
    from femrub.app.scheme import scheme_options
    from femrub.scene import load_scene

    scene = load_scene("twisted-naca", SCENE)
    sim = build(scene, log=lambda s: None, cache=model_cache)
    return sim.model, scene["scheme"], scheme_options(scene)


def _blade_run(blade, h, blocks=True, **kw):
    model, scheme, opts = blade
    st = make_stepper(scheme["name"], model, h, **opts)
    st.block_steps = blocks
    return st.run(scheme["t_end"], **kw)


def _same_as_coarsened(lean, full, k):
    """``lean`` holds exactly ``coarsen(full, k).lean()``'s arrays, bit for bit."""
    ref = coarsen(full, k).lean()
    assert (lean.h, lean.steps, lean.status, lean.message) == (
        ref.h,
        ref.steps,
        ref.status,
        ref.message,
    )
    for name in ("t", "gap", "impulse", "states", "state_times", "friction_limit"):
        a, b = getattr(lean, name), getattr(ref, name)
        if b is None:
            assert a is None, name
            continue
        assert a.shape == b.shape and a.dtype == b.dtype, name
        np.testing.assert_array_equal(a, b, err_msg=name)
    assert lean.signals.keys() == ref.signals.keys()
    for key in ref.signals:
        np.testing.assert_array_equal(lean.signals[key], ref.signals[key], err_msg=key)
    assert lean.energy == {} and lean.extra == {}
    assert lean.friction_force is None and lean.contact_state is None


@pytest.mark.parametrize("chunk", [512, 7])  # 7: groups of k steps across chunks
@pytest.mark.parametrize("k", [1, 2, 3])
def test_a_lean_frictional_coated_run_is_its_full_run_coarsened(blade, monkeypatch, k, chunk):
    monkeypatch.setattr("femrub.output.recorder.CHUNK_STEPS", chunk)
    h = blade[1]["h"] / 2
    full = _blade_run(blade, h, store_every=2 * 50)
    lean = _blade_run(blade, h, store_every=2 * 50, lean=k)
    assert full.status == "ok" and int((full.contact_state == 2).sum()) > 50  # slides
    _same_as_coarsened(lean, full, k)
    # what the verdict reads of the rows it did not keep: the whole arrays' values
    assert lean.energy_error() == full.energy_error() > 0
    assert lean.heat_error() == full.heat_error() > 0
    check = coulomb_check(
        full.force, full.friction_force, full.slip_velocity, full.contact_state, full.friction_limit
    )
    assert lean.checks["coulomb"] == check and check["slip_steps"] > 0


def test_a_lean_run_of_the_per_step_path(blade):
    h = blade[1]["h"]
    full = _blade_run(blade, h, blocks=False, store_every=40)
    lean = _blade_run(blade, h, blocks=False, store_every=40, lean=2)
    _same_as_coarsened(lean, full, 2)
    assert lean.energy_error() == full.energy_error()


@pytest.mark.parametrize("tolerances", [{"energy": 1e-14}, {"heat": 1e-16}, {"coulomb": -1.0}])
def test_the_verdict_of_a_lean_run_is_the_full_runs(blade, tolerances):
    """Balance and Coulomb rules fire on a lean record as on the whole arrays."""
    h = blade[1]["h"]
    full = _blade_run(blade, h, tolerances=tolerances)
    lean = _blade_run(blade, h, tolerances=tolerances, lean=2)
    assert full.status == "inaccurate"
    assert (lean.status, lean.message) == (full.status, full.message)


def test_a_frictionless_lean_run_and_a_stop(monkeypatch):
    """The paper's bar (one frictionless contact, exponential and θ steppers), a run that a
    stop limit ends: the rows up to the stop, coarsened; the same verdict."""
    monkeypatch.setattr("femrub.output.recorder.CHUNK_STEPS", 64)
    model = fr.bar_model(alpha=3.0)
    for st in (lambda: fr.ThetaMethod(model, 1e-4), lambda: fr.ExponentialMoreau(model, 2e-4)):
        full, lean = st().run(0.1, store_every=30), st().run(0.1, store_every=30, lean=3)
        _same_as_coarsened(lean, full, 3)
        assert lean.energy_error() == full.energy_error()
        assert lean.heat_error() == full.heat_error()
        assert lean.checks["coulomb"] == coulomb_check(
            full.force,
            full.friction_force,
            full.slip_velocity,
            full.contact_state,
            full.friction_limit,
        )
    limits = {"tip_temperature": 0.5}
    full = fr.ThetaMethod(model, 1e-4).run(0.1, limits=limits)
    lean = fr.ThetaMethod(model, 1e-4).run(0.1, limits=limits, lean=2)
    assert full.status == "diverged-physically" and 10 < full.steps < 999
    _same_as_coarsened(lean, full, 2)


def test_a_lean_record_does_not_allocate_the_rows_it_drops():
    """Traced peak of a lean run: its kept rows and one chunk's buffers, not the n rows of
    every per-step array (nor the results' friction and energy arrays)."""
    model = fr.bar_model(alpha=3.0)
    n = 40_000

    def peak(**kw):
        tracemalloc.start()
        res = fr.ThetaMethod(model, 1e-6).run(n * 1e-6, **kw)
        out = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        return res, out

    full, full_peak = peak()
    lean, lean_peak = peak(lean=2)
    per_row = 8 + sum(v.shape[1] * 8 for v in lean.signals.values()) + 8 * model.n_contacts
    kept = (n // 2 + 1) * per_row  # t, signals and impulses every second step
    every_row = sum(a.nbytes for a in full.per_step().values()) / (n + 1)
    assert every_row > 8 * per_row / 2  # the full record: energy, gaps, friction rows, ...
    assert lean_peak < kept + 2_000_000  # + one chunk's buffers (and the stepper's own)
    assert full_peak > 5 * lean_peak


@pytest.mark.parametrize("chunk", [512, 7])
@pytest.mark.parametrize("k", [1, 2])
def test_a_compared_run_keeps_the_signals_of_its_whole_record(blade, monkeypatch, k, chunk):
    """A run only compared (``compared=True``) keeps, bit for bit, what its whole record
    coarsened keeps (times, signals, impulses, checkpoint states, status), and no checks."""
    monkeypatch.setattr("femrub.output.recorder.CHUNK_STEPS", chunk)
    h = blade[1]["h"] / 2
    full = _blade_run(blade, h, store_every=2 * 50)
    compared = _blade_run(blade, h, store_every=2 * 50, lean=k, compared=True)
    assert full.status == "ok" and int((full.contact_state == 2).sum()) > 50  # slides
    _same_as_coarsened(compared, full, k)
    assert compared.checks == {} and np.isnan(compared.energy_error())


def test_a_compared_run_stops_where_its_whole_record_stops():
    """The stop checks stay: a stop limit ends a compared run at the same row, for the
    θ-method and the exponential stepper (whose works of each step are not measured)."""
    model = fr.bar_model(alpha=3.0)
    limits = {"tip_temperature": 0.5}
    for st in (lambda: fr.ThetaMethod(model, 1e-4), lambda: fr.ExponentialMoreau(model, 2e-4)):
        full = st().run(0.1, limits=limits, store_every=30)
        compared = st().run(0.1, limits=limits, store_every=30, lean=2, compared=True)
        assert full.status == "diverged-physically" and 10 < full.steps < 499
        _same_as_coarsened(compared, full, 2)
    with pytest.raises(ValueError, match="compared = True needs lean >= 1"):
        fr.ThetaMethod(model, 1e-4).run(0.1, compared=True)


class _UnreadableForms:
    """Energy forms that fail when read: a recorder that meters the balance fails."""

    def _read(self):
        raise AssertionError("an energy form was read")

    Qk = Qe = Pth = Pd = heat_content = heat_outflow = Wth = property(_read)


def test_a_compared_run_evaluates_no_balance_coulomb_check_or_gap_rows(blade, monkeypatch):
    """No energy form is read, no Coulomb check made, no gaps or slip velocities of the
    recorded rows computed; the same run judged (lean, not compared) reads the forms."""
    model, scheme, opts = blade
    unreadable = model.with_(energy=_UnreadableForms())

    from femrub.output import kept_rows

    rows = []  # Coulomb checks, and the contact's rows evaluated on blocks of recorded states

    def check(*args, _original=kept_rows.coulomb_check_rows):
        rows.append("coulomb")
        return _original(*args)

    monkeypatch.setattr(kept_rows, "coulomb_check_rows", check)
    cls = type(model.contact)

    def spy(name):
        original = getattr(cls, name)

        def rows_of(self, *args):
            if np.ndim(args[-1]) == 2 and len(args[-1]) > 1:
                rows.append(name)
            return original(self, *args)

        return rows_of

    for name in ("gap", "slip_velocity"):
        monkeypatch.setattr(cls, name, spy(name))

    def run(**kw):
        st = make_stepper(scheme["name"], unreadable, scheme["h"], **opts)
        return st.run(scheme["t_end"], store_every=50, **kw)

    res = run(lean=1, compared=True)
    assert res.status == "ok" and res.steps > 100 and not rows
    with pytest.raises(AssertionError, match="energy form"):
        run(lean=1)
    assert run(lean=1, energy=False).status == "ok"  # not metered, still judged
    assert {"coulomb", "slip_velocity"} <= set(rows) and "gap" not in rows
    run(energy=False)  # a whole record keeps the gaps
    assert "gap" in rows


def count_meters(monkeypatch) -> list:
    """The sizes of the models whose runs meter their energy balance, as they start."""
    from femrub.output import recorder

    metered = []

    class Meter(recorder.EnergyMeter):
        def __init__(self, model, capacity):
            metered.append(model.n_dofs)
            super().__init__(model, capacity)

    monkeypatch.setattr(recorder, "EnergyMeter", Meter)
    return metered


def _recorded_whole(monkeypatch, module):
    """``module._simulate`` recording every row and coarsening afterwards, as before lean
    records (the step check: ``coarsen(res, 2)``; the estimate: ``res.lean()``)."""
    original = module._simulate
    signature = inspect.signature(original)

    def whole(*args, **kw):
        bound = signature.bind(*args, **kw)
        bound.apply_defaults()
        lean, bound.arguments["lean"] = bound.arguments["lean"], 0
        res, states = original(*bound.args, **bound.kwargs)
        return (coarsen(res, lean) if lean > 1 else res.lean() if lean else res), states

    monkeypatch.setattr(module, "_simulate", whole)


def test_the_step_check_and_the_estimate_are_those_of_whole_records(blade, monkeypatch):
    """The time-step error (fine run and twin recorded lean at k = 2) and the reduction
    estimate (its runs recorded lean), all runs only compared, equal, bit for bit, what
    whole records coarsened afterwards gave, with the same statuses; of these runs only the
    run at h of the run's sizes, which may be the scene's run, meters its energy balance."""
    from femrub.analysis import reduction_check as est
    from femrub.analysis import step_check as sc
    from femrub.app import build
    from femrub.app.scheme import bare_stepper
    from femrub.scene import load_scene

    metered = count_meters(monkeypatch)

    # a step tolerance low enough that the round-off twin is stepped too
    changes = {**SCENE, "scheme.step_check": True, "scheme.step_tolerance": 1e-6}
    scene = load_scene("twisted-naca", changes)
    sim = build(scene, log=lambda s: None)
    assert sim.ran is not None  # the estimate's run, with the coating it cut, is the run
    metered.clear()

    def check():
        err, _, _ = sc.check_step(
            scene, sim.model, sim.full, lambda m, h: bare_stepper(scene, m, h), sim.limits
        )
        return {k: v for k, v in err.items() if k != "seconds"}

    def estimate():
        report, red = {}, sim.reductor
        want = (scene["reduction"]["n_uv"], scene["reduction"]["n_theta"])
        est.checked_sizes(
            red, red.fom, want, lambda m: bare_stepper(scene, m), scene, report, None, sim.limits
        )
        return {k: v for k, v in report["error"].items() if k != "seconds"}

    lean = check()
    assert "sensitivity" in lean and lean["status_reference"] == "ok"
    assert len(metered) == 1  # the run at h; not the run at h/2 nor its twin
    with monkeypatch.context() as mp:
        _recorded_whole(mp, sc)
        assert check() == lean
    with monkeypatch.context() as mp:
        _recorded_whole(mp, est)
        whole = estimate()
    metered.clear()
    assert estimate() == whole and whole["status_reference"] == "ok"
    assert len(metered) == 1  # the run of the scene's sizes; not the reference


@pytest.mark.parametrize("lean", [0, 1])
def test_rows_a_step_leaves_unwritten_stay_zero_across_chunks(monkeypatch, lean):
    """The per-step buffers are reused chunk after chunk: a step without friction rows
    (or works) reads as zeros, not as the row a previous chunk left there."""
    from femrub.output.recorder import Recorder
    from femrub.steppers.record import Friction, StepRecord

    monkeypatch.setattr("femrub.output.recorder.CHUNK_STEPS", 4)
    model = fr.bar_model(alpha=3.0)
    n, k = 11, iter(range(1, 12))
    st = fr.ThetaMethod(model, 1e-4)

    def advance():  # friction rows on odd steps only
        i = next(k)
        friction = (
            Friction(np.zeros((0, 2)), np.array([float(i)]), np.array([1])) if i % 2 else None
        )
        return StepRecord(i * 1e-4, model.x0, np.zeros(1), friction)

    rec = Recorder(model, 1e-4, n, scheme="test", stability_limit=np.inf, energy=False, lean=lean)
    rows = []
    rec.on_rows = lambda a: rows.append(a)
    res = rec.record(st.state, advance)
    assert res.steps == n and res.status == "ok"
    if not lean:
        np.testing.assert_array_equal(res.contact_state[:, 0], [0, 1] * 6)
    streamed = np.concatenate([a["t"] for a in rows])
    np.testing.assert_array_equal(streamed, np.arange(n + 1) * 1e-4)


def test_a_lean_record_saved_and_loaded_keeps_its_checks(tmp_path):
    model = fr.bar_model(alpha=3.0)
    lean = fr.ThetaMethod(model, 1e-4).run(0.05, lean=2)
    back = fr.Results.load_npz(lean.save_npz(tmp_path / "lean.npz"))
    assert back.checks == lean.checks and back.energy_error() == lean.energy_error() > 0
    one = fr.ThetaMethod(model, 1e-4).run(0.0, lean=2)  # no step: no balance, NaN
    back = fr.Results.load_npz(one.save_npz(tmp_path / "one.npz"))
    assert np.isnan(one.energy_error()) and np.isnan(back.energy_error())


def test_a_whole_record_writes_no_chunk_of_zeros():
    """A whole record's arrays start as zeros the system maps only when written: a chunk of
    zero rows (a contact open, no friction) is not written, a chunk with values is."""
    from femrub.output.kept_rows import _put

    rows = np.zeros((10, 2))
    rows.flags.writeable = False  # a write would raise
    _put(rows, slice(2, 5), np.zeros((3, 2)))
    rows.flags.writeable = True
    _put(rows, slice(2, 5), np.array([[0.0, 0.0], [0.0, 1.5], [0.0, 0.0]]))
    np.testing.assert_array_equal(rows[:, 1], [0, 0, 0, 1.5, 0, 0, 0, 0, 0, 0])
