"""`femrub sweep`: a grid on a LocalCluster with 2 workers, resumed after a failure."""

import csv
import json

import pytest

from femrub.app.cli import main
from femrub.app.sweep import grid, parse_param
from femrub.scene import SceneError

TINY = """
name = "tiny"
[geometry]
kind = "bar"
n_elements = 4
[contact]
casing = { kind = "concentric", clearance = "15 um" }
heat_coefficient = 3.0
[loads]
rotation_speed = 200.0
tip_force = { law = "sin", amplitude = 7.0 }
[scheme]
h = 2e-4
t_end = 0.02
[outputs]
plots = false
"""


def test_parse_param():
    assert parse_param("rotation_speed=200:2000:50") == (
        "loads.rotation_speed",
        [200.0 + 50 * i for i in range(37)],
    )
    key, values = parse_param("loads.rotation_speed=1000:3000:1000rpm")
    assert values == ["1000 rpm", "2000 rpm", "3000 rpm"]
    assert parse_param("contact.restitution=0,0.5,1") == ("contact.restitution", [0, 0.5, 1])
    assert len(grid([("a.b", [1, 2]), ("c.d", [3, 4, 5])])) == 6
    for bad in ("rotation_speed", "rotation_speed=3:1:1", "rotation_speed=1:2:0", "nope=1:2:1"):
        with pytest.raises(SceneError):
            parse_param(bad)


def _csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


@pytest.mark.parametrize("cold", [False, True])
def test_sweep_runs_and_resumes(tmp_path, capsys, monkeypatch, cold):
    """A grid on this process and a local worker (the first point here, which fills the
    model cache, then each process the next point left), then rerun after a point failed:
    only that point runs again, here. The worker starts at once when numba's cache holds
    the kernels (its first point waits for the cache's entries), else after the first
    point, having loaded its modules meanwhile."""
    import femrub.app.sweep as sweep
    import femrub.contact.jit as jit
    from femrub.blas import one_blas_thread

    here, kept, serial = [], [], []
    monkeypatch.setattr(jit, "cold_kinds", lambda kinds: kinds if cold else ())

    def spy(scene, chunk, cache, bar, builds=None, claims=None):
        here.append([r["point"] for r in chunk])
        kept.append(builds)
        serial.append(one_blas_thread._inside > 0)
        return points_here(scene, chunk, cache, bar, builds, claims)

    points_here = sweep._points_here
    monkeypatch.setattr(sweep, "_points_here", spy)
    from distributed import Client

    sent, submit = [], Client.submit

    def submit_spy(client, function, *args, **kw):
        sent.append((function.__name__, args, len(kw.get("workers") or ())))
        return submit(client, function, *args, **kw)

    monkeypatch.setattr(Client, "submit", submit_spy)
    scene = tmp_path / "tiny.toml"
    scene.write_text(TINY)
    out = tmp_path / "sweep"
    args = [
        "sweep",
        str(scene),
        "--param",
        "rotation_speed=100:300:100",
        "-o",
        str(out),
        "--workers",
        "2",
        "-q",
    ]
    assert main(args) == 0
    # the first point here, then the others from the model it built, each point in the
    # process that claims it first; the worker walks the same points
    assert here == [[0], [1, 2]] and kept[0] is kept[1] is not None
    assert serial[:2] == [False, True]  # all cores for the build, one BLAS thread after
    names = [name for name, *_ in sent]
    assert names == (["prepare_worker", "run_points"] if cold else ["run_points"])
    assert [c["loads.rotation_speed"] for c, _ in sent[-1][1][3]] == [200.0, 300.0]
    assert not list((out / "runs").glob(".claims-*"))  # the claims go with the sweep
    rows = _csv(out / "interaction.csv")
    assert [r["loads.rotation_speed"] for r in rows] == ["100.0", "200.0", "300.0"]
    assert all(r["status"] == "ok" and r["skipped"] == "False" for r in rows)
    assert all(float(r["max_contact_force_N"]) > 0 and float(r["f1_hz"]) > 0 for r in rows)
    png = out / "interaction.png"
    assert png.read_bytes()[:4] == b"\x89PNG" and png.stat().st_size > 20_000
    runs = sorted((out / "runs").iterdir())
    assert len(runs) == 3 and all((r / "history.csv").is_file() for r in runs)
    # a point that failed (here: its summary says so) is rerun, finished ones are skipped
    stamps = {r.name: (r / "summary.json").stat().st_mtime_ns for r in runs}
    (runs[1] / "summary.json").write_text(json.dumps({"status": "failed"}))
    assert main(args) == 0
    rows = _csv(out / "interaction.csv")
    assert [r["skipped"] for r in rows] == ["True", "False", "True"]
    assert here[2:] == [[1]] and len(sent) == len(names)  # one point to run: here, no cluster
    assert all(r["status"] == "ok" for r in rows)
    for r in (runs[0], runs[2]):
        assert (r / "summary.json").stat().st_mtime_ns == stamps[r.name]
    assert capsys.readouterr().err == ""


def test_a_point_runs_in_the_process_that_claims_it_first(tmp_path):
    """Processes given the same points run each once: a point another process claimed is
    skipped (its row ``None``), the others run in order."""
    from femrub.app.sweep import claim_point, run_points
    from femrub.scene import load_scene

    scene = load_scene(str(_tiny(tmp_path)))
    claims = tmp_path / "claims"
    claims.mkdir()
    runs = tmp_path / "runs"
    points = [
        ({"loads.rotation_speed": w}, str(runs / f"{i:03d}")) for i, w in enumerate((1e2, 2e2))
    ]
    assert claim_point(claims, points[0][1])  # taken by another process
    assert not claim_point(claims, runs / "elsewhere" / "000")  # the point, not the path
    rows = run_points(scene.data, scene.source, str(scene.base_dir), points, claims=claims)
    assert rows[0] is None and rows[1]["status"] == "ok"
    assert not (runs / "000").exists() and (runs / "001" / "summary.json").is_file()
    again = run_points(scene.data, scene.source, str(scene.base_dir), points, claims=claims)
    assert again == [None, None]  # both claimed: nothing runs twice


def _tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


def test_a_worker_s_preparation_never_raises_and_cold_kinds_reads_numba_s_cache():
    from femrub.app.sweep import prepare_worker
    from femrub.contact.activation import compile_kernels
    from femrub.contact.jit import cold_kinds

    compile_kernels(("one",))
    assert cold_kinds(("one", "no such kernels")) == ()  # cached now (or not compiled)
    prepare_worker(("no such kernels",))  # a preparation that fails is the point's to redo


@pytest.mark.parametrize("cold, loaded", [((), ["one", "friction"]), (("friction",), ["one"])])
def test_a_worker_loads_only_the_kernels_numba_has_cached(monkeypatch, cold, loaded):
    import femrub.contact.activation as activation
    import femrub.contact.jit as jit
    from femrub.app.sweep import prepare_worker

    seen = []
    monkeypatch.setattr(jit, "compiled", lambda: True)
    monkeypatch.setattr(jit, "cold_kinds", lambda kinds: cold)
    compilers = {k: (lambda k=k: seen.append(k)) for k in activation.KERNEL_KINDS}
    monkeypatch.setattr(activation, "_COMPILE", compilers)
    prepare_worker(("one", "friction"))
    assert seen == loaded  # a cold kind is the first point's build's to compile, once


def test_sweep_rejects_an_invalid_point_before_any_work(tmp_path, capsys):
    scene = tmp_path / "tiny.toml"
    scene.write_text(TINY)
    args = [
        "sweep",
        str(scene),
        "--param",
        "contact.restitution=0,2",
        "-o",
        str(tmp_path / "s"),
        "-q",
    ]
    assert main(args) == 2
    assert "contact.restitution = 2: must be" in capsys.readouterr().err
    assert not (tmp_path / "s").exists()


def test_the_map_draws_temperature_and_wear_only_where_the_scene_models_them():
    from femrub.output.interaction import panels
    from femrub.scene import load_scene

    names = lambda rows, scene: [p[0] for p in panels(rows, scene)]  # noqa: E731
    cold = [{"max_temperature": 0.0, "max_wear_depth": 0.0}] * 2
    rigid = load_scene("paper", {"physics.thermal": "off"})
    assert "max_temperature" not in names(cold, rigid)
    assert "max_wear_depth" not in names(cold, rigid)
    assert names(cold, rigid)[:3] == [
        "max_tip_displacement",
        "rms_tip_displacement",
        "max_contact_force",
    ]
    hot = [{"max_temperature": 0.0}, {"max_temperature": 3.5}]
    assert "max_temperature" in names(hot, rigid)  # a point that heated is shown
    thermal = load_scene("paper", {"physics.thermal": "on"})
    assert "max_temperature" in names(cold, thermal)
    coated = load_scene(
        "paper", {"contact.abradable.thickness": "1 mm", "contact.abradable.yield": 10.0}
    )
    assert "max_wear_depth" in names(cold, coated)


def test_the_first_point_fills_the_cache_alone():
    """With a cache the first point runs alone and the others load what it stored; the
    points then run as one chunk per worker, every N-th point (at most one per point)."""
    from femrub.app.sweep import _batches, _chunks

    todo, cache = [{"point": i} for i in range(4)], object()
    assert _batches(todo, cache, 2) == [[todo[:1]], [[todo[1], todo[3]], [todo[2]]]]
    assert _batches(todo, None, 2) == [[todo[0::2], todo[1::2]]]
    assert _batches(todo, None, 8) == [[[r] for r in todo]]
    assert _batches(todo[:1], cache, 2) == [[todo[:1]]]
    # a map whose cost grows with the speed: each chunk spans it, the first one the largest
    assert _chunks(list(range(7)), 2) == [[0, 2, 4, 6], [1, 3, 5]]
    assert _chunks([], 2) == [[]]


def test_sweep_with_no_worker_runs_here_and_gives_the_cluster_rows(tmp_path, monkeypatch):
    """`--workers 0` runs the points in this process, one after the other (no dask
    cluster: a script without a `__main__` guard can sweep) with the same results."""
    import femrub.app.sweep as sweep

    scene = tmp_path / "tiny.toml"
    scene.write_text(TINY)
    args = ["sweep", str(scene), "--param", "rotation_speed=100:300:100", "-q"]
    assert main([*args, "-o", str(tmp_path / "cluster"), "--workers", "2"]) == 0

    def no_cluster(*_):
        raise AssertionError("--workers 0, or one chunk, started a dask cluster")

    monkeypatch.setattr(sweep, "_client", no_cluster)
    assert main([*args, "-o", str(tmp_path / "here"), "--workers", "0"]) == 0
    two = ["sweep", str(scene), "--param", "rotation_speed=100:200:100", "-q"]
    assert main([*two, "-o", str(tmp_path / "two")]) == 0  # the first, then the other: here
    cluster, here = (
        _csv(tmp_path / "cluster" / "interaction.csv"),
        _csv(tmp_path / "here" / "interaction.csv"),
    )
    keys = ("loads.rotation_speed", "status", "max_contact_force_N", "f1_hz")
    assert [[r[k] for k in keys] for r in here] == [[r[k] for k in keys] for r in cluster]
    assert main([*args, "-o", str(tmp_path / "bad"), "--workers", "-1"]) == 2
