"""The content-addressed model cache: hits, misses on changed inputs, corruption, limits."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from femrub.app.cache import ModelCache, content_key, parse_size
from femrub.app.cli import main
from femrub.app.simulation import build
from femrub.scene import load_scene

# a coarse twisted blade (a few hundred tetrahedra) reduced with fixed sizes; every contact
# kept whatever the speed, so a speed change keeps the same boundary dofs; no centrifugal
# prestress (it makes the stiffness depend on the speed: test_prestress_is_cached_per_speed)
SMALL = {
    "loads.centrifugal": "off",
    "geometry.h": 0.03,
    "geometry.n_sections": 2,
    "contact.reach": "all",
    "reduction.method": "craig-bampton",
    "reduction.n_uv": 8,
    "reduction.n_theta": 4,
    "scheme.t_end": 2e-5,
}


def _scene(**changes):
    return load_scene("twisted-naca", {**SMALL, **changes})


def _build(cache, notes=None, **changes):
    log = notes.append if notes is not None else None
    return build(_scene(**changes), log=log, cache=cache)


def _close(a, b, tol=1e-8):
    """Equal up to the eigen-solver's tolerance (ARPACK's random start vector)."""
    a, b = np.asarray(a), np.asarray(b)
    np.testing.assert_allclose(a, b, rtol=tol, atol=tol * max(np.abs(b).max(), 1e-300))


def _same_model(a, b):
    _close(a.A.toarray(), b.A.toarray())
    _close(a.B.toarray(), b.B.toarray())
    ca, cb = a.contact, b.contact
    for name in ("G", "Gv", "Hm", "Ht"):
        _close(getattr(ca, name), getattr(cb, name))
    for t in (0.0, 1.3e-4):
        np.testing.assert_array_equal(ca.gap_at(t), cb.gap_at(t))
        np.testing.assert_array_equal(ca.alpha_at(t), cb.alpha_at(t))
    _close(a.to_full, b.to_full)
    assert sorted(a.observations) == sorted(b.observations)


def _states(sim, steps=15):
    return np.array([s.X for _, s in zip(range(steps), sim.stepper.iterate(1.0))])


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    cache = ModelCache(tmp_path_factory.mktemp("cache"))
    notes = []
    sim = _build(cache, notes)
    return cache, sim, notes


def test_first_build_stores_assembly_and_reduction(first):
    cache, sim, notes = first
    info = cache.info()
    assert info["stages"]["assembly"]["entries"] == 1
    assert info["stages"]["reduction"]["entries"] == 1
    assert any("assembly stored" in n for n in notes)
    assert sim.reductor is not None and "cache" not in sim.report["reduction"]


def test_second_build_hits_and_runs_the_same(first):
    cache, sim, _ = first
    notes = []
    again = _build(cache, notes)
    assert any("assembly loaded" in n for n in notes)
    assert again.report["reduction"]["cache"] == "hit" and again.reductor is None
    _same_model(sim.model, again.model)
    np.testing.assert_array_equal(_states(again), _states(sim))  # the same bits


def test_speed_change_reuses_the_matrices_with_the_new_gap_and_heat(first):
    cache, _, _ = first
    notes = []
    hit = _build(cache, notes, **{"loads.rotation_speed": 1700.0})
    assert any("assembly loaded" in n for n in notes)
    # the reduction error estimate steps the run at this speed: the reduced model is rebuilt,
    # on the bases built for the first speed (same matrices), loaded from the cache
    assert "cache" not in hit.report["reduction"]
    assert hit.report["reduction"]["bases"].startswith("reused")
    assert not any("static shapes" in n for n in notes if n.startswith("reduction phases"))
    fresh = _build(None, None, **{"loads.rotation_speed": 1700.0})
    _same_model(hit.model, fresh.model)
    _close(_states(hit), _states(fresh), 1e-6)


def test_another_process_loads_the_bases(first, monkeypatch):
    """A process that did not build the bases (the other sweep worker) loads them."""

    cache, _, _ = first
    assert cache.info()["stages"]["bases"]["entries"] == 1
    notes = []
    hit = _build(cache, notes, **{"loads.rotation_speed": 1600.0})
    assert any("bases loaded" in n for n in notes)
    assert hit.report["reduction"]["bases"].startswith("reused")
    assert not any("static shapes" in n for n in notes if n.startswith("reduction phases"))
    fresh = _build(None, None, **{"loads.rotation_speed": 1600.0})
    _same_model(hit.model, fresh.model)
    _close(_states(hit), _states(fresh), 1e-6)


def test_prestress_is_cached_per_speed(tmp_path):
    cache = ModelCache(tmp_path / "cache")
    on = {"loads.centrifugal": "nonlinear"}
    notes = []
    a = _build(cache, notes, **on)
    assert any("prestress stored" in n for n in notes)
    notes = []
    b = _build(cache, notes, **on)
    assert any("prestress loaded" in n for n in notes)
    assert any("assembly loaded" in n for n in notes)
    _close(a.model.B.toarray(), b.model.B.toarray())
    notes = []
    _build(cache, notes, **on, **{"loads.rotation_speed": 1000.0})
    assert any("prestress stored" in n for n in notes)  # another speed: another K_T
    assert any("assembly stored" in n for n in notes)


def test_changed_material_misses(first):
    cache, sim, _ = first
    notes = []
    other = _build(cache, notes, **{"material.young": "120 GPa"})
    assert any("assembly stored" in n for n in notes)
    assert "cache" not in other.report["reduction"]
    assert not np.allclose(other.model.B.toarray(), sim.model.B.toarray())


def test_corrupt_entry_is_detected_and_rebuilt(first, tmp_path):
    cache, sim, _ = first
    local = ModelCache(tmp_path / "c")
    _build(local)
    for e in local.entries():
        if e["stage"] == "reduction":
            path = local.root / f"{e['key']}.npz"
            data = bytearray(path.read_bytes())
            data[len(data) // 2] ^= 0xFF
            path.write_bytes(bytes(data))
    notes = []
    rebuilt = _build(local, notes)
    assert any("corrupt" in n and "rebuilding" in n for n in notes)
    assert "cache" not in rebuilt.report["reduction"]  # rebuilt, not loaded
    _same_model(rebuilt.model, sim.model)
    assert _build(local).report["reduction"]["cache"] == "hit"  # and stored again


def _stored(cache, stage):
    return [e for e in cache.entries() if e["stage"] == stage]


def test_one_map_to_the_mesh_for_every_speed(tmp_path, monkeypatch):
    """The reduced model's map to the mesh (columns of the reductor's largest map, which is
    its basis with the constrained rows put back) is not stored a second time: each speed's
    reduction refers to the basis of the ``bases`` entry by its columns."""
    from femrub.reduction.truncation import ColumnMap

    local = ModelCache(tmp_path / "c")
    notes = []
    a = _build(local, notes)
    b = _build(local, None, **{"loads.rotation_speed": 1700.0})
    assert isinstance(a.model.to_full, ColumnMap)
    reductions, (bases,) = _stored(local, "reduction"), _stored(local, "bases")
    assert len(reductions) == 2 and not _stored(local, "map")
    assert not any("map stored" in n for n in notes), notes
    assert all(e["size"] < bases["size"] for e in reductions)
    for e in reductions:
        entry = local.load(e["key"])
        assert entry["model"].to_full is None and entry["map"]["basis"] is True
        np.testing.assert_array_equal(entry["map"]["columns"], a.model.to_full.cols)
    notes = []
    hit = _build(local, notes, **{"loads.rotation_speed": 1700.0})
    assert hit.report["reduction"]["cache"] == "hit"
    assert any("bases loaded" in n for n in notes), notes
    assert hit.model.to_full.full is not None
    _same_model(hit.model, b.model)
    np.testing.assert_array_equal(np.asarray(hit.model.to_full), np.asarray(b.model.to_full))


def test_a_map_that_is_not_the_basis_has_its_own_entry(tmp_path):
    """Without a ``bases`` entry (``reduction.method = "auto"`` stores none) the map to the
    mesh is its own entry, stored once: a build at another speed with nothing kept in memory
    (another run or process) finds it and does not write it again."""
    local = ModelCache(tmp_path / "c")
    notes = []
    auto = {k: v for k, v in SMALL.items() if not k.startswith("reduction.n_")}
    auto["reduction.method"] = "auto"

    def built(**changes):
        return build(load_scene("twisted-naca", {**auto, **changes}), log=notes.append, cache=local)

    built()
    assert any("map stored" in n for n in notes) and not _stored(local, "bases")
    (entry,) = _stored(local, "map")
    data = local.root / f"{entry['key']}.npz"
    written = data.stat().st_mtime_ns
    notes.clear()
    faster = built(**{"loads.rotation_speed": 1700.0})
    assert "cache" not in faster.report["reduction"]  # reduced anew, its map not stored
    assert not any("map stored" in n for n in notes), notes
    assert data.stat().st_mtime_ns == written and len(_stored(local, "map")) == 1
    notes.clear()
    hit = built(**{"loads.rotation_speed": 1700.0})
    assert hit.report["reduction"]["cache"] == "hit"
    assert any("map loaded" in n for n in notes), notes
    _same_model(hit.model, faster.model)


def test_a_model_at_another_speed_is_not_hashed_again(monkeypatch):
    """Builds in a row key a model at another speed (the same arrays) by the key of the one
    before, without hashing its arrays again; a model with other arrays is hashed (the same
    content, the same key; another content, another key)."""
    import dataclasses

    import femrub as fr
    from femrub.app import cached
    from femrub.scene.units import rpm

    model = fr.bar_model()
    kept = cached.Kept()
    key = cached.Stages(kept=kept)._model_key(model)
    faster = model.with_parameters(rotation_speed=rpm(3000.0))
    with monkeypatch.context() as m:
        m.setattr(cached, "content_key", lambda *a: pytest.fail("hashed again"))
        assert cached.Stages(kept=kept)._model_key(faster) == key
    assert cached.Stages()._model_key(faster) == key  # nothing kept: hashed, the same key
    copied = dataclasses.replace(faster, B=faster.B.copy())
    assert cached.Stages(kept=kept)._model_key(copied) == key
    changed = dataclasses.replace(faster, B=2.0 * faster.B)
    assert cached.Stages(kept=kept)._model_key(changed) != key


@pytest.mark.parametrize("damage", ["corrupt", "missing"])
def test_corrupt_or_missing_basis_rebuilds_the_reduction(first, tmp_path, monkeypatch, damage):

    cache, sim, _ = first
    local = ModelCache(tmp_path / "c")
    _build(local)
    (entry,) = _stored(local, "bases")  # the basis the reduction's map is
    path = local.root / f"{entry['key']}.npz"
    if damage == "corrupt":
        data = bytearray(path.read_bytes())
        data[len(data) // 2] ^= 0xFF
        path.write_bytes(bytes(data))
    else:  # evicted (the size limit): both files gone
        path.unlink()
        path.with_suffix(".json").unlink()
    notes = []
    rebuilt = _build(local, notes)
    assert any("map to the mesh is not in the cache; rebuilding" in n for n in notes)
    assert any("is corrupt" in n for n in notes) == (damage == "corrupt"), notes
    assert "cache" not in rebuilt.report["reduction"]  # rebuilt, not loaded
    _same_model(rebuilt.model, sim.model)
    assert len(_stored(local, "bases")) == 1  # stored again
    again = _build(local)
    assert again.report["reduction"]["cache"] == "hit"
    _same_model(again.model, sim.model)


def test_sparse_keys_are_canonical_without_conversion_or_change(monkeypatch):
    """A sparse matrix is hashed in its own format (a CSC model operator is not converted to
    CSR), the same key for its canonical and duplicated forms, and the input is unchanged."""
    import scipy.sparse as sp

    rng = np.random.default_rng(2)
    dense = rng.standard_normal((6, 5)) * (rng.random((6, 5)) < 0.5)
    csc = sp.csc_matrix(dense)
    assert content_key(csc) != content_key(sp.csr_matrix(dense))  # the format is part of it
    unsorted = sp.csr_matrix(dense)
    for i in range(unsorted.shape[0]):  # reverse each row's entries: same matrix, unsorted
        s = slice(unsorted.indptr[i], unsorted.indptr[i + 1])
        unsorted.indices[s], unsorted.data[s] = unsorted.indices[s][::-1], unsorted.data[s][::-1]
    unsorted.has_sorted_indices = False
    before = unsorted.indices.copy()
    assert content_key(unsorted) == content_key(sp.csr_matrix(dense))
    np.testing.assert_array_equal(unsorted.indices, before)  # not sorted in place
    j = int(np.flatnonzero(np.diff(csc.indptr))[0])  # a column with an entry: split it in two
    k = csc.indptr[j]
    data = np.insert(csc.data, k, 0.25 * csc.data[k])
    data[k + 1] *= 0.75  # the entry as two duplicates, 0.25 x and 0.75 x
    indices = np.insert(csc.indices, k, csc.indices[k])
    indptr = np.r_[csc.indptr[: j + 1], csc.indptr[j + 1 :] + 1]
    dup = sp.csc_matrix((data, indices, indptr), shape=csc.shape)
    assert not dup.has_canonical_format
    key = content_key(csc)
    monkeypatch.setattr(sp.csc_matrix, "tocsr", lambda *a, **k: pytest.fail("converted"))
    assert content_key(csc) == key
    summed = dup.copy()
    summed.sum_duplicates()
    assert content_key(dup) == content_key(summed)  # duplicates summed before hashing


def test_store_load_clear_and_info(tmp_path):
    cache = ModelCache(tmp_path)
    obj = {"a": np.arange(10.0), "b": "text"}
    key = content_key("x", obj["a"])
    assert cache.load(key) is None and not cache.holds(key)
    assert cache.store(key, obj, stage="test")
    assert cache.holds(key)
    back = cache.load(key)
    np.testing.assert_array_equal(back["a"], obj["a"])
    assert cache.info()["entries"] == 1
    data = cache.root / f"{key}.npz"
    data.write_bytes(data.read_bytes()[:-1])  # cut short: not held (a load finds it corrupt)
    assert not cache.holds(key)
    assert cache.clear()[0] == 1 and cache.info()["entries"] == 0
    assert cache.load(key) is None and not cache.holds(key)


def test_keys_follow_content():
    a = np.arange(5.0)
    assert content_key(a, {"k": 1}) == content_key(a.copy(), {"k": 1})
    assert content_key(a, {"k": 1}) != content_key(a, {"k": 2})
    b = a.copy()
    b[3] += 1e-15
    assert content_key(a) != content_key(b)


def test_size_limit_evicts_least_recently_used(tmp_path):
    blob = np.zeros(100_000)  # 800 kB
    a, b, c = (content_key(name) for name in "abc")
    cache = ModelCache(tmp_path, limit=2_000_000)
    cache.store(a, blob, stage="t")
    cache.store(b, blob, stage="t")
    now = time.time()
    os.utime(tmp_path / f"{a}.json", (now - 100, now - 100))
    os.utime(tmp_path / f"{b}.json", (now - 50, now - 50))
    assert cache.load(a) is not None  # a becomes the most recently used
    cache.store(c, blob, stage="t")
    keys = {e["key"] for e in cache.entries()}
    assert keys == {a, c}
    assert cache.info()["bytes"] <= cache.limit
    notes = []
    small = ModelCache(tmp_path / "small", limit=1000, log=notes.append)
    assert not small.store(content_key("big"), blob, stage="t")
    assert small.entries() == [] and "exceeds the cache size" in notes[0]


def test_parse_size():
    assert parse_size("500MB") == 500_000_000
    assert parse_size("2GiB") == 2 * 2**30
    assert parse_size(1e6) == 1_000_000
    with pytest.raises(ValueError, match="cache size"):
        parse_size("lots")


def test_cli_cache_info_and_clear(tmp_path, capsys):
    cache = ModelCache(tmp_path)
    cache.store(content_key("k"), np.ones(3), stage="assembly")
    assert main(["cache", "info", "--cache-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert str(tmp_path) in out and "assembly" in out and "entries       1" in out
    assert main(["cache", "clear", "--cache-dir", str(tmp_path)]) == 0
    assert "removed 1 entries" in capsys.readouterr().out
    assert cache.entries() == []


def test_an_entry_another_process_is_building_is_waited_for_and_loaded(tmp_path):
    """Two builders of one entry at once (the workers of a sweep): the second waits while
    the first builds it, then loads what it stored instead of building it too."""
    import threading

    from femrub.app.cached import Stages

    cache = ModelCache(tmp_path)
    key = content_key("entry built once")
    inside, release, order = threading.Event(), threading.Event(), []

    def first():
        with Stages(cache)._building("test", key) as hit:
            order.append(("first", hit))
            inside.set()
            release.wait(10)
            cache.store(key, {"a": np.arange(3.0)}, stage="test")

    notes = []

    def second():
        with Stages(cache, notes.append)._building("test", key) as hit:
            order.append(("second", None if hit is None else hit["a"].tolist()))

    builder = threading.Thread(target=first)
    builder.start()
    assert inside.wait(10)
    waiter = threading.Thread(target=second)
    waiter.start()
    waiter.join(0.5)
    assert waiter.is_alive() and order == [("first", None)]  # waiting, not building
    release.set()
    builder.join(10)
    waiter.join(10)
    assert order == [("first", None), ("second", [0.0, 1.0, 2.0])]
    assert any("being built by another process" in n for n in notes)
    assert (tmp_path / f"{key}.lock").is_file()
    assert cache.clear()[0] == 1 and not (tmp_path / f"{key}.lock").exists()  # an entry


def test_a_builder_that_died_leaves_no_lock(tmp_path):
    """The operating system releases the lock of a process that dies while building: the
    next builder goes on at once (and builds the entry itself)."""
    import subprocess
    import sys

    cache = ModelCache(tmp_path)
    key = content_key("builder killed")
    with cache.building(key):
        pass  # the folder marked, the lock file made
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import fcntl, os, sys, time\n"
            f"fd = os.open({str(tmp_path / (key + '.lock'))!r}, os.O_RDWR)\n"
            "fcntl.flock(fd, fcntl.LOCK_EX); print('held', flush=True); time.sleep(60)",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "held"
    finally:
        holder.kill()
        holder.wait(10)
    t0 = time.perf_counter()
    with cache.building(key):
        assert time.perf_counter() - t0 < 5.0
