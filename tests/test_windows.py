"""The checks of a long run on windows (femrub.analysis.windows).

A long coated, heated rub (20 revolutions) is checked on five windows of one revolution: the
reference restarted from the run's own state (and the coating it had cut) at each window.
The windows must reproduce the run exactly when the reference is the run's own model (no
misaligned row, lost history or lifted state), cost five revolutions of the reference, and
see a coarser step as a larger error; a short run is checked whole.
"""

import math

import numpy as np
import pytest
from test_rub_blocks import SCENE

from femrub.analysis import windows
from femrub.analysis.reduction_check import _on_windows
from femrub.app import build
from femrub.app.scheme import bare_stepper
from femrub.scene import load_scene

#: 42,000 steps of 2 µs at 1500 rad/s: 20.05 revolutions of 2094 steps
LONG = {**SCENE, "scheme.t_end": 0.084, "scheme.step_check": True}


@pytest.fixture(scope="module")
def long_run(model_cache):
    scene = load_scene("twisted-naca", LONG)
    return scene, build(scene, log=lambda s: None, cache=model_cache)


def test_a_long_run_is_checked_on_windows_a_short_one_whole():
    scene = load_scene("twisted-naca", LONG)
    plan = windows.window_plan(scene)
    w = round(2 * math.pi / 1500.0 / 2e-6)
    assert [b - a for a, b in plan] == [w] * windows.N_WINDOWS
    assert plan[0][0] == 0 and plan[-1][1] == 42000  # from the run's start to its end
    assert windows.window_plan(scene.with_changes({"scheme.t_end": 0.03})) is None
    assert windows.window_plan(scene.with_changes({"loads.rotation_speed": 0.0})) is None


def test_the_run_and_both_checks_go_by_windows(long_run):
    scene, sim = long_run
    red, step = sim.report["reduction"]["error"], sim.report["time_step"]
    assert "windows" in red["method"] and "windows" in step["method"]
    assert len(red["windows"]) == len(step["windows"]) == windows.N_WINDOWS
    assert red["windows"][-1][1] == pytest.approx(0.084, rel=1e-12)
    assert 0 < red["estimate"] < 1 and 0 < step["estimate"] < 1
    assert "sensitivity" not in red and "sensitivity" not in step  # no twin
    res = sim.ran[0]  # the run itself, with the coating it cut
    assert res.steps == 42000 and res.contact_history.wear.max_depth > 1e-6


def test_windows_of_the_runs_own_model_reproduce_the_run(long_run):
    """The reference restarted from each snapshot with the run's own model: every measure
    vanishes (a window one step off, a coating not restored, a wrong lift would not)."""
    scene, sim = long_run
    red = sim.reductor
    most = (red.n_uv, red.n_theta)
    ref = bare_stepper(scene, red.reduce(*most))
    plan = windows.window_plan(scene)
    make = lambda m: bare_stepper(scene, m)  # noqa: E731
    res, _, _, err = _on_windows(red, sim.full, most, ref, make, scene, sim.limits, plan)
    for key in windows.DECISIVE:
        assert err[key] < 1e-8, (key, err[key])
    steps = sum(round((b - a) / res.h) for a, b in err["windows"])
    assert steps == sum(b - a for a, b in plan)  # five revolutions of the reference
    # row by row: each window's rows are the run's rows of its steps
    refs = windows.step_windows(ref, res, plan, limits=sim.limits)
    for (k0, k1), w in zip(plan, refs, strict=True):
        np.testing.assert_allclose(w.t, res.t[k0 : k1 + 1], rtol=0, atol=1e-12 * res.t[-1])
        scale = np.abs(res.impulse).max()
        np.testing.assert_allclose(w.impulse[1:], res.impulse[k0 + 1 : k1 + 1], atol=1e-9 * scale)
        T, T_run = w.signals["contact_temperature"], res.signals["contact_temperature"]
        np.testing.assert_allclose(T, T_run[k0 : k1 + 1], rtol=0, atol=1e-9 * np.abs(T_run).max())


def test_a_coarser_step_shows_a_larger_windowed_error(long_run, model_cache):
    scene, sim = long_run
    coarse = build(
        scene.with_changes({"scheme.h": 4e-6, "scheme.t_end": 0.084}),
        log=lambda s: None,
        cache=model_cache,
    )
    fine, rough = sim.report["time_step"], coarse.report["time_step"]
    assert "windows" in rough["method"]
    assert rough["estimate"] > 1.3 * fine["estimate"]


def test_a_windowed_run_with_frames_is_stepped_once_its_frames_from_its_states(tmp_path):
    """With VTK frames the run the checks stepped is still the run (its states stored at the
    frames' stride): its frames equal those of the same model stepped with the frames
    streamed, and the folder holds the coating it cut."""
    import pyvista

    from femrub.app.run import run_scene
    from femrub.output.run_folder import run_to_folder

    scene = load_scene("twisted-naca", {**LONG, "outputs.vtk_stride": 600, "outputs.plots": False})
    steps = []
    res, built = run_scene(scene, tmp_path / "once", log=steps.append)
    assert built.ran is not None and "windows" in built.report["reduction"]["error"]["method"]
    assert (tmp_path / "once" / "wear_map.csv").exists()
    fresh = run_to_folder(
        bare_stepper(scene, built.model),
        0.084,
        tmp_path / "streamed",
        fields=built.fields,
        vtk_stride=600,
        limits=built.limits or None,
        plots=False,
        rotation_speed=1500.0,
    )
    np.testing.assert_array_equal(fresh.impulse, res.impulse)
    rubbing = 0
    for k in range(71):
        name = f"vtk/rub_{k:06d}.vtu"
        a, b = pyvista.read(tmp_path / "once" / name), pyvista.read(tmp_path / "streamed" / name)
        assert set(a.array_names) == set(b.array_names)
        for field in b.array_names:  # float32 fields
            scale = 2e-4 * (1e-30 + np.abs(b[field]).max())
            np.testing.assert_allclose(a[field], b[field], rtol=0, atol=scale)
        rubbing += bool(np.abs(b["friction_force"]).max() > 0)
    assert rubbing  # a frame with friction forces (read through the contacts' tangents)
    assert len(list((tmp_path / "once" / "vtk").glob("rub_*.vtu"))) == 71


def test_with_its_estimate_cached_the_step_checks_run_is_the_run(tmp_path, model_cache):
    """A second run of the scene finds its reduction (and its estimate) in the cache: the
    time-step check steps the run at ``h``, its states at the frames' stride, and that run
    is the scene's run (it is not stepped again for its frames)."""
    from femrub.app.run import run_scene

    scene = load_scene("twisted-naca", {**LONG, "outputs.vtk_stride": 600, "outputs.plots": False})
    first, _ = run_scene(scene, tmp_path / "first", cache=model_cache)
    lines = []
    res, built = run_scene(scene, tmp_path / "second", cache=model_cache, log=lines.append)
    assert any("cache: reduction loaded" in line for line in lines)
    assert "windows" in built.report["time_step"]["method"]
    assert built.ran is not None and built.ran[0] is res
    np.testing.assert_array_equal(res.impulse, first.impulse)
    assert len(list((tmp_path / "second" / "vtk").glob("rub_*.vtu"))) == 71


def test_a_run_stopped_before_its_last_window_is_checked_whole(model_cache):
    """A stop limit ends the run after its first window: windows would leave its end
    unchecked, so both checks compare it whole."""
    scene = load_scene("twisted-naca", {**LONG, "limits.tip_temperature": 35.0})
    sim = build(scene, log=lambda s: None, cache=model_cache)
    res = sim.ran[0]
    assert res.status == "diverged-physically" and 0.005 < res.t[-1] < 0.02
    for err in (sim.report["reduction"]["error"], sim.report["time_step"]):
        assert "windows" not in err and np.isfinite(err["estimate"]) and err["estimate"] > 0


def test_the_window_comparison_reads_the_runs_rows_of_each_window():
    """``compare_windows`` on a run whose windows are its own rows gives zero; the same
    windows read one step late do not (impulses that vary from step to step)."""
    from types import SimpleNamespace

    from femrub.output.results import Snapshot
    from femrub.reduction.estimate import compare_windows

    rng = np.random.default_rng(1)
    n, h, plan = 400, 1e-3, [(0, 50), (170, 220), (350, 400)]
    t = np.arange(n + 1) * h
    impulse = rng.random((n + 1, 3))
    temp = np.cumsum(rng.random((n + 1, 3)), axis=0)
    snaps = [Snapshot(k, t[k], np.zeros(2), ()) for w in plan for k in w]
    run = SimpleNamespace(
        t=t, impulse=impulse, signals={"contact_temperature": temp}, snapshots=snaps
    )

    def window(k0, k1):
        rows = slice(k0, k1 + 1)
        return SimpleNamespace(
            t=t[rows],
            impulse=impulse[rows],
            signals={"contact_temperature": temp[rows]},
            states=None,
        )

    same = compare_windows(run, [window(*w) for w in plan], plan, None, None, {}, 10 * h)
    late = compare_windows(
        run, [window(a + 1, b + 1) for a, b in plan], plan, None, None, {}, 10 * h
    )
    assert same["contact_force"] == 0 and same["contact_temperature"] == 0
    assert late["contact_force"] > 0.03 and late["contact_temperature"] > 0.01


def test_the_window_fields_are_the_windows_end_states_through_one_product_each():
    """The field measures of ``compare_windows`` read each window's states at its ends
    (the run's snapshots, the reference's last state), every window's through one call of
    each map to the full states: the same numbers as the states taken one at a time."""
    from types import SimpleNamespace

    import scipy.sparse as sp

    from femrub.output.results import Snapshot
    from femrub.reduction.estimate import compare_windows

    rng = np.random.default_rng(2)
    n, h, plan, r = 60, 1e-3, [(0, 10), (20, 30), (40, 50)], 4
    t = np.arange(n + 1) * h
    X = rng.standard_normal((n + 1, r))
    R = rng.standard_normal((6, r))
    snaps = [Snapshot(k, t[k], X[k], ()) for w in plan for k in w]
    run = SimpleNamespace(t=t, impulse=np.zeros((n + 1, 1)), signals={}, snapshots=snaps)
    refs = [
        SimpleNamespace(
            t=t[a : b + 1],
            impulse=np.zeros((b - a + 1, 1)),
            signals={},
            states=np.stack([X[a], X[b] + 0.1 * (j + 1)]),
        )
        for j, (a, b) in enumerate(plan)
    ]
    calls = []

    def full(Xr):
        calls.append(len(Xr))
        return Xr @ R.T

    norms = {"u": (slice(0, 3), sp.identity(3)), "theta": (slice(3, 6), sp.identity(3))}
    out = compare_windows(run, refs, plan, full, full, norms, 10 * h)
    assert calls == [2 * len(plan), len(plan)]
    diff = [np.linalg.norm((R @ X[b] - R @ ref.states[-1])[:3]) for (_, b), ref in zip(plan, refs)]
    size = [np.linalg.norm((R @ ref.states[-1])[:3]) for ref in refs]
    rise = [np.linalg.norm((R @ (ref.states[-1] - X[a]))[3:]) for (a, _), ref in zip(plan, refs)]
    miss = [np.linalg.norm((R @ (X[b] - ref.states[-1]))[3:]) for (_, b), ref in zip(plan, refs)]
    assert out["displacement"] == pytest.approx(max(diff) / max(size), rel=1e-12)
    assert out["displacement_end"] == pytest.approx(diff[-1] / size[-1], rel=1e-12)
    assert out["temperature"] == pytest.approx(max(miss) / max(rise), rel=1e-12)
    assert out["temperature_end"] == pytest.approx(sum(miss) / sum(rise), rel=1e-12)


def test_the_estimates_runs_hold_a_released_reductor(model_cache):
    """With given sizes, the reductor's bases are handed on (to be stored) before any run,
    then the checks and the build keep it released: no left basis through the runs, and the
    model returned is the one the reductor made for those sizes."""
    from femrub.analysis.reduction_check import reduce_checked

    scene = load_scene("twisted-naca", SCENE)
    sim = build(scene, log=lambda s: None, cache=model_cache)
    handed = []
    model, red, report = reduce_checked(
        sim.full, scene, None, lambda m: bare_stepper(scene, m), on_bases=handed.append
    )
    (bases,) = handed
    assert bases.left is not None and red.left is None
    sizes = (report["n_uv"], report["n_theta"])
    assert red.reduce(*sizes) is model
    assert "error" in report and report["error"]["estimate"] < 1
