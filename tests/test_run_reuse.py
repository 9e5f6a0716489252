"""The reduction error estimate's run of the chosen sizes is the run (stepped once)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_cache import SMALL as CACHE_SMALL

from femrub.app.run import run_scene
from femrub.app.scheme import bare_stepper
from femrub.app.simulation import build
from femrub.output.run_folder import run_to_folder
from femrub.scene import load_scene

# a coarse twisted blade reduced with fixed sizes (tests/test_cache.py), long enough to rub
SMALL = {**CACHE_SMALL, "scheme.t_end": 4e-4, "outputs.vtk_stride": 0}
VARYING = {"timings", "wall_seconds", "cpu_seconds", "cpu_per_step_us"}


@pytest.fixture(scope="module")
def sim():
    return build(load_scene("twisted-naca", SMALL))


def _write(sim, out, ran, csv_stride=1, history_npz=True):
    s = sim.scene
    return run_to_folder(
        bare_stepper(s, sim.model),
        s["scheme"]["t_end"],
        out,
        limits=sim.limits or None,
        plots=False,
        reduction_error=sim.report["reduction"]["error"],
        ran=ran,
        rotation_speed=s["loads"]["rotation_speed"],
        csv_stride=csv_stride,
        history_npz=history_npz,
    )


def test_the_estimate_run_is_the_run(sim, tmp_path):
    assert sim.ran is not None
    res, wall = sim.ran
    assert wall > 0 and res.steps == sim.stepper.steps_to(sim.scene["scheme"]["t_end"])
    a = _write(sim, tmp_path / "reused", sim.ran)
    b = _write(sim, tmp_path / "stepped", None)  # the same model stepped again
    assert a.status == b.status and a.message == b.message and a.warnings == b.warnings
    assert np.abs(b.impulse).max() > 0  # it rubs
    with (
        np.load(tmp_path / "reused/history.npz") as ha,
        np.load(tmp_path / "stepped/history.npz") as hb,
    ):  # noqa: E501
        assert sorted(ha.files) == sorted(hb.files) and "states" not in ha.files
        for k in ha.files:
            if k != "meta":
                np.testing.assert_array_equal(ha[k], hb[k], err_msg=k)
    sa, sb = (
        json.loads((tmp_path / d / "summary.json").read_text()) for d in ("reused", "stepped")
    )  # noqa: E501
    assert sorted(sa) == sorted(sb) and sorted(sa["timings"]) == sorted(sb["timings"])
    assert {k: v for k, v in sa.items() if k not in VARYING} == {
        k: v for k, v in sb.items() if k not in VARYING
    }
    assert (tmp_path / "reused/history.csv").read_text() == (
        tmp_path / "stepped/history.csv"
    ).read_text()


def _csv(path):
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


@pytest.mark.parametrize("every", [7, 1000])
def test_csv_stride_streamed_or_written_at_the_end(sim, tmp_path, every):
    """``history.csv`` at one row in ``every``: the rows ``Results.save_csv(every=...)``
    writes, whether streamed while the run goes or written from a run stepped elsewhere;
    ``history.npz`` keeps every step; the impulses of the rows add up to the run's."""
    a = _write(sim, tmp_path / "reused", sim.ran, csv_stride=every)
    b = _write(sim, tmp_path / "stepped", None, csv_stride=every)
    n = len(a.t)
    assert len(b.t) == n > 2 * 7  # 7: several rows; 1000: the first and the last only
    ha, ta = _csv(tmp_path / "reused/history.csv")
    hb, tb = _csv(tmp_path / "stepped/history.csv")
    a.save_csv(tmp_path / "ref.csv", every=every)
    href, tref = _csv(tmp_path / "ref.csv")
    rows = np.unique(np.r_[np.arange(0, n, every), n - 1])
    assert ha == hb == href and ta.shape == tb.shape == tref.shape == (rows.size, len(href))
    np.testing.assert_array_equal(ta, tref)  # written by save_csv itself
    np.testing.assert_allclose(tb, tref, rtol=1e-12, atol=1e-12 * np.abs(tref).max())
    np.testing.assert_array_equal(tb[:, 0], a.t[rows])
    imp = [j for j, h in enumerate(hb) if h.startswith("contact_impulse")]
    assert imp and np.abs(a.impulse).max() > 0
    np.testing.assert_allclose(tb[:, imp].sum(axis=0), a.impulse.sum(axis=0), rtol=1e-12)
    with np.load(tmp_path / "stepped/history.npz") as h:
        assert h["t"].size == n  # every step


def test_run_scene_steps_once(tmp_path, monkeypatch):
    """``femrub run`` without VTK writes the estimate's run; its time is ``stepping``."""
    from femrub.analysis import steppers as runnable

    calls = []
    original = runnable.ThetaMethod.run

    def counted(self, *a, **kw):
        calls.append(kw.get("store_every", 0))
        return original(self, *a, **kw)

    monkeypatch.setattr(runnable.ThetaMethod, "run", counted)
    scene = load_scene("twisted-naca", {**SMALL, "outputs.plots": False})
    res, built = run_scene(scene, tmp_path / "run")
    s = json.loads((tmp_path / "run/summary.json").read_text())
    # the estimate's reference, its run at the chosen sizes (the run) and possibly a twin
    assert len(calls) in (2, 3) and all(c > 0 for c in calls)
    assert s["timings"]["stepping"] == pytest.approx(built.ran[1])
    assert s["reduction_error"]["sizes"] == [8, 4] and s["status"] == res.status


def test_a_run_that_keeps_no_build_lets_the_full_model_go_before_its_output(tmp_path, monkeypatch):
    """``femrub run`` (``keep_build=False``): the full model and the reductor are collected
    before the results are written, and the folder holds what a kept build writes."""
    import gc
    import weakref

    from femrub.output import run_folder

    alive, original = {}, run_folder._finish

    def on_built(built):
        alive.update(full=weakref.ref(built.full), reductor=weakref.ref(built.reductor))

    def finish(*a, **kw):  # the output stage
        gc.collect()
        alive["at_output"] = [k for k in ("full", "reductor") if alive[k]() is not None]
        return original(*a, **kw)

    monkeypatch.setattr(run_folder, "_finish", finish)
    scene = load_scene("twisted-naca", {**SMALL, "outputs.plots": False})
    kept, built = run_scene(scene, tmp_path / "kept", on_built=on_built)
    assert alive["at_output"] == ["full", "reductor"] and built.full is not None
    res, built = run_scene(scene, tmp_path / "run", on_built=on_built, keep_build=False)
    assert alive["at_output"] == [] and built.full is None and built.reductor is None
    a, b = (json.loads((tmp_path / d / "summary.json").read_text()) for d in ("kept", "run"))
    assert a["n_full"] == b["n_full"] > b["n_dofs"]
    assert a.keys() == b.keys() and a["status"] == b["status"]
    # two builds of one scene: the same model up to the eigen-solver's rounding
    assert np.allclose(kept.impulse, res.impulse, rtol=1e-6, atol=1e-9 * kept.impulse.max())


def test_builds_in_a_row_keep_the_assembly(tmp_path):
    """Builds in a row (a sweep worker's points) take the last assembly from memory."""
    from femrub.app.cache import ModelCache
    from femrub.app.simulation import SceneBuilds

    cache, notes = ModelCache(tmp_path / "cache"), []
    scene = load_scene("twisted-naca", {**SMALL, "scheme.t_end": 2e-5})
    first = build(scene, cache=cache)
    builds = SceneBuilds(cache)
    builds.build(scene.with_changes({"contact.friction": 0.1}), log=notes.append)
    assert any("assembly loaded" in n for n in notes)  # from the cache folder, then kept
    notes.clear()
    again = builds.build(scene.with_changes({"contact.friction": 0.2}), log=notes.append)
    assert any("assembly kept by this process" in n for n in notes)
    assert not any("assembly loaded" in n or "assembly stored" in n for n in notes)
    np.testing.assert_array_equal(again.full.A.toarray(), first.full.A.toarray())


def test_builds_in_a_row_keep_the_discretisation(tmp_path):
    """Builds in a row on the same mesh reuse its bases (with their own blade); the model is
    the one a fresh build gives; another mesh is discretised."""
    from femrub.app.cache import ModelCache
    from femrub.app.simulation import SceneBuilds

    cache = ModelCache(tmp_path / "cache")
    scene = load_scene("twisted-naca", {**SMALL, "scheme.t_end": 2e-5})
    other = scene.with_changes({"contact.friction": 0.1})
    fresh = build(other, cache=cache)
    builds, notes = SceneBuilds(cache), []
    builds.build(scene, log=notes.append)
    assert not any("discretisation kept" in n for n in notes)
    (disc,) = builds.kept.discretisation.values()
    # the assembly came from the cache: the quadrature bases were never built, only the
    # spaces on one point per cell (dof numbers, contact points, strain at the centroids)
    assert "basis_u" not in vars(disc.spaces) and "basis_t" not in vars(disc.spaces)
    assert "dofs_u" in vars(disc.spaces)
    notes.clear()
    kept = builds.build(other, log=notes.append)
    assert any("discretisation kept by this process" in n for n in notes)
    (disc,) = builds.kept.discretisation.values()
    assert kept.fields.vertex_dofs_u is disc.dofs_u.nodal_dofs  # the spaces shared, not rebuilt
    for name in ("A", "B"):
        a, b = getattr(kept.full, name), getattr(fresh.full, name)
        np.testing.assert_array_equal(a.toarray(), b.toarray())
    np.testing.assert_array_equal(kept.full.contact.G, fresh.full.contact.G)
    np.testing.assert_array_equal(kept.full.contact.gap_at(1e-5), fresh.full.contact.gap_at(1e-5))
    notes.clear()
    builds.build(scene.with_changes({"geometry.h": 0.035}), log=notes.append)
    assert not any("discretisation kept" in n for n in notes)  # another mesh


PROBE = {"name": "tip", "node": 5, "quantity": "displacement", "component": "radial"}


@pytest.fixture(scope="module")
def fresh_faster():
    """The probed small scene at 1650 rad/s, built from nothing (no cache, no kept model)."""
    scene = load_scene("twisted-naca", {**SMALL, "outputs.probes": [PROBE]})
    return build(scene.with_changes({"loads.rotation_speed": "1650 rad/s"}))


@pytest.mark.parametrize("cached", [False, True], ids=["no-cache", "cache"])
def test_a_point_at_another_speed_is_the_model_at_that_speed(tmp_path, cached, fresh_faster):
    """The next point of a speed sweep takes the previous point's model at its own speed (a
    parameter): no mesh, assembly or bases built; the same model and run as a fresh build."""
    from femrub.app.cache import ModelCache
    from femrub.app.simulation import SceneBuilds

    scene = load_scene("twisted-naca", {**SMALL, "outputs.probes": [PROBE]})
    faster = scene.with_changes({"loads.rotation_speed": "1650 rad/s"})
    builds, notes = SceneBuilds(ModelCache(tmp_path / "c") if cached else None), []
    first = builds.build(scene)
    assert "parametric" not in first.report
    sim = builds.build(faster, log=notes.append)
    assert sim.report["parametric"] == {"from_rotation_speed": 1500.0, "rotation_speed": 1650.0}
    assert "taken at 1650 rad/s" in sim.explain()
    assert not any(w in n for n in notes for w in ("assembly loaded", "assembly stored", "mesh"))
    assert sim.report["reduction"]["bases"].startswith("reused")
    assert sim.model.parameters["rotation_speed"] == 1650.0
    fresh = fresh_faster
    assert "parametric" not in fresh.report
    assert sim.model.n_dofs == fresh.model.n_dofs
    np.testing.assert_array_equal(sim.full.B.toarray(), fresh.full.B.toarray())
    np.testing.assert_array_equal(sim.model.contact.gap_at(3e-4), fresh.model.contact.gap_at(3e-4))
    a, b = sim.ran[0], fresh.ran[0]
    assert a.status == b.status
    assert np.abs(b.probe("tip")).max() > 1e-9  # a node that moves
    np.testing.assert_allclose(a.probe("tip"), b.probe("tip"), rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.impulse, b.impulse, rtol=0, atol=1e-9 * np.abs(b.impulse).max())
    assert sim.report["reduction"]["error"]["estimate"] == pytest.approx(
        fresh.report["reduction"]["error"]["estimate"], rel=1e-6
    )


def test_a_point_the_model_cannot_take_as_a_parameter_is_built_in_full():
    """At rest, or with a prestress that depends on the speed, the point is built again."""
    from femrub.app.simulation import SceneBuilds

    scene = load_scene("twisted-naca", {**SMALL, "scheme.t_end": 2e-5})
    builds = SceneBuilds()
    builds.build(scene)
    assert "parametric" not in builds.build(scene.with_changes({"contact.friction": 0.1})).report
    prestressed = {"loads.centrifugal": "linear"}
    builds.build(scene.with_changes(prestressed))
    other = builds.build(scene.with_changes({**prestressed, "loads.rotation_speed": 1400.0}))
    assert "parametric" not in other.report
    assert other.full.parameters["rotation_speed"] == 1400.0


def test_a_coated_reduced_run_is_the_estimates_run_with_the_coating_it_cut(tmp_path):
    """A run that carries state outside X (a coating) is the estimate's run too: stepped
    once, with the wear map it cut; the time-step check steps only the run at h/2. Its
    folder's wear map and history equal those of the same model stepped afresh."""
    from test_rub_blocks import SCENE

    scene = load_scene("twisted-naca", {**SCENE, "scheme.step_check": True})
    kept = []
    sim = build(scene, log=kept.append)
    assert sim.ran is not None and sim.report["reduction"]["error"]["estimate"] < 1.0
    err = sim.report["time_step"]
    assert err["status_reference"] == "ok" and np.isfinite(err["estimate"])
    assert any("time-step check: run at h/2" in line for line in kept)
    assert not any("time-step check: run at h =" in line for line in kept)
    wear = sim.ran[0].contact_history.wear
    assert wear.surface.max() > 1e-7  # the run cut the coating
    assert sim.model.contact.wear.surface.max() == 0.0  # the model's own coating is unworn

    res = _write(sim, tmp_path / "reused", sim.ran)
    fresh = _write(sim, tmp_path / "fresh", None)
    assert res.contact_history.wear is wear and fresh.contact_history.wear is not wear
    np.testing.assert_allclose(
        fresh.contact_history.wear.surface, wear.surface, rtol=0, atol=1e-12 * wear.surface.max()
    )
    np.testing.assert_allclose(fresh.impulse, res.impulse, rtol=0, atol=1e-9 * res.impulse.max())


def test_a_run_that_writes_frames_is_stepped_again_and_its_checks_only_compared(monkeypatch):
    """With VTK frames the scene's run is stepped again (its frames written as it steps): the
    reduction estimate's and the time-step check's runs are then all only compared (no
    energy meter), with the estimates of a build whose run is reused (two builds: the same
    to round-off; bit for bit on one model: tests/test_lean_record.py)."""
    from test_lean_record import count_meters

    metered = count_meters(monkeypatch)
    scene = load_scene("twisted-naca", {**SMALL, "scheme.step_check": True})
    reused = build(scene)
    assert reused.ran is not None and len(metered) == 1  # the run; its checks' runs compared
    metered.clear()
    framed = build(scene.with_changes({"outputs.vtk_stride": 5}))
    assert framed.fields is not None and framed.ran is None and not metered
    for key in ("reduction", "time_step"):
        a = reused.report[key].get("error", reused.report[key])
        b = framed.report[key].get("error", framed.report[key])
        assert a["status_reference"] == b["status_reference"] == "ok"
        assert b["estimate"] == pytest.approx(a["estimate"], rel=1e-6)


def test_no_history_csv_at_stride_zero(sim, tmp_path):
    """``outputs.csv_stride = 0``: no ``history.csv``, stepped or reused, and the same
    ``history.npz`` as with one."""
    a = _write(sim, tmp_path / "reused", sim.ran, csv_stride=0)
    b = _write(sim, tmp_path / "stepped", None, csv_stride=0)
    c = _write(sim, tmp_path / "with", None, csv_stride=1)
    assert not (tmp_path / "reused/history.csv").exists()
    assert not (tmp_path / "stepped/history.csv").exists()
    assert (tmp_path / "with/history.csv").is_file()
    assert a.status == b.status == c.status == "ok"
    with (
        np.load(tmp_path / "stepped/history.npz") as hb,
        np.load(tmp_path / "with/history.npz") as hc,
    ):
        assert sorted(hb.files) == sorted(hc.files)
        np.testing.assert_array_equal(hb["impulse"], hc["impulse"])


def test_no_history_npz_keeps_the_measures(sim, tmp_path):
    """``outputs.history_npz = false``: no ``history.npz``, stepped or reused, and the
    summary's largest magnitudes and root mean squares of every signal are those of the
    ``history.npz`` the same run writes with it."""
    a = _write(sim, tmp_path / "reused", sim.ran, history_npz=False)
    b = _write(sim, tmp_path / "stepped", None, history_npz=False)
    _write(sim, tmp_path / "with", None)
    assert not (tmp_path / "reused/history.npz").exists()
    assert not (tmp_path / "stepped/history.npz").exists()
    assert a.status == b.status == "ok"
    summary = json.loads((tmp_path / "stepped/summary.json").read_text())
    assert set(summary["signals_rms"]) == set(b.signals) and b.signals
    with np.load(tmp_path / "with/history.npz") as h:
        for name, rms in summary["signals_rms"].items():
            x = h[name if name.startswith("probe_") else f"signal_{name}"]
            assert rms == np.sqrt(np.mean(x**2))
            assert summary["signals_max_abs"][name] == np.abs(x).max()
