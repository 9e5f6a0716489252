"""The model cache holds data, never code, and touches only what femrub wrote in it."""

from __future__ import annotations

import hashlib
import io
import json
import pickle

import numpy as np
import pytest

from femrub.app.cache import MARKER, ModelCache, check_key, content_key
from femrub.app.cli import main


class _Exploit:
    """Pickles as a call that writes a file: what a crafted pickle entry would run."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def _plant(cache, name, tree, arrays, stage="assembly", **meta):
    """Write a crafted entry (data file and metadata with a matching checksum)."""
    buf = io.BytesIO()
    np.savez(buf, __tree__=np.frombuffer(json.dumps(tree).encode(), np.uint8), **arrays)
    data = buf.getvalue()
    (cache.root / f"{name}.npz").write_bytes(data)
    info = {
        "format": "femrub-cache-entry",
        "version": 2,
        "key": name,
        "stage": stage,
        "size": len(data),
        "sha256": hashlib.sha256(data).hexdigest(),
        "created": 0.0,
        "code": "x",
        "describe": "",
        **meta,
    }
    (cache.root / f"{name}.json").write_text(json.dumps(info))


@pytest.fixture
def cache(tmp_path):
    notes = []
    c = ModelCache(tmp_path / "cache", log=notes.append)
    assert c.store(content_key("seed"), np.ones(3), stage="test")  # a femrub folder
    c.notes = notes
    return c


def test_an_object_array_is_never_unpickled(cache, tmp_path):
    key = content_key("crafted")
    sentinel = tmp_path / "executed"
    exploit = np.empty(1, dtype=object)
    exploit[0] = _Exploit(sentinel)
    _plant(cache, key, {"$": "array", "ref": "a0"}, {"a0": exploit})
    assert cache.load(key) is None
    assert not sentinel.exists()
    assert any("malformed" in n and "rebuilding" in n for n in cache.notes)
    assert not (cache.root / f"{key}.npz").exists()  # removed: the caller rebuilds it


@pytest.mark.parametrize(
    "cls", ["os:system", "subprocess:Popen", "builtins:open", "femrub.fem.x:__class__"]
)
def test_a_tree_naming_a_callable_is_refused(cache, tmp_path, cls):
    key = content_key("crafted", cls)
    sentinel = tmp_path / "executed"
    tree = {"$": "object", "class": cls, "state": {"args": f"touch {sentinel}"}}
    _plant(cache, key, tree, {})
    assert cache.load(key) is None and not sentinel.exists()
    assert "malformed" in cache.notes[-1]


def test_a_pickle_entry_of_an_older_format_is_never_read(cache, tmp_path):
    key = content_key("legacy")
    sentinel = tmp_path / "executed"
    data = pickle.dumps(_Exploit(sentinel))
    (cache.root / f"{key}.pkl").write_bytes(data)
    info = {"key": key, "stage": "assembly", "size": len(data)}
    info["sha256"] = hashlib.sha256(data).hexdigest()
    (cache.root / f"{key}.json").write_text(json.dumps(info))
    assert cache.load(key) is None and not sentinel.exists()
    assert main(["cache", "clear", "--cache-dir", str(cache.root)]) == 0
    assert not (cache.root / f"{key}.pkl").exists() and not sentinel.exists()


def test_metadata_naming_a_path_outside_never_deletes_it(cache, tmp_path):
    outside = tmp_path / "results" / "summary.pkl"
    outside.parent.mkdir()
    outside.write_text("keep me")
    (outside.parent / "summary.json").write_text("{}")
    key = content_key("evil")
    _plant(cache, key, {"$": "array", "ref": "a0"}, {"a0": np.ones(2)}, key="../results/summary")
    # eviction: a store into a cache that is over its limit
    cache.limit = 1
    cache.store(content_key("next"), np.zeros(10), stage="test")
    assert main(["cache", "clear", "--cache-dir", str(cache.root)]) == 0
    assert outside.read_text() == "keep me" and (outside.parent / "summary.json").exists()


@pytest.mark.parametrize("key", ["../results/summary", "A" * 64, "abc", "/etc/passwd", 7])
def test_keys_are_checked_before_any_path(cache, key):
    with pytest.raises(ValueError, match="not a SHA-256 hex digest"):
        check_key(key)
    with pytest.raises(ValueError, match="not a SHA-256 hex digest"):
        cache.load(key)
    with pytest.raises(ValueError, match="not a SHA-256 hex digest"):
        cache.store(key, np.ones(2), stage="t")


@pytest.mark.parametrize("text", ["[1, 2, 3]", "null", '{"key": 5}', "{", '"x"'])
def test_malformed_metadata_is_skipped_and_rebuilt(cache, text, capsys):
    key = content_key("m")
    assert cache.store(key, np.arange(4.0), stage="test")
    (cache.root / f"{key}.json").write_text(text)
    assert [e["key"] for e in cache.entries()] == [content_key("seed")]
    assert main(["cache", "info", "--cache-dir", str(cache.root)]) == 0
    assert cache.load(key) is None
    assert "malformed" in cache.notes[-1] and "rebuilding" in cache.notes[-1]
    assert cache.store(key, np.arange(4.0), stage="test")
    np.testing.assert_array_equal(cache.load(key), np.arange(4.0))


def test_clear_removes_only_femrub_entries_and_counts_them(cache, capsys):
    own = ["mine.pkl", "notes.tmp", "data.json", "x.npz"]
    for name in own:
        (cache.root / name).write_text("user's")
    cache.store(content_key("two"), {"a": np.ones(2), "b": (1, "x")}, stage="test")
    assert main(["cache", "clear", "--cache-dir", str(cache.root)]) == 0
    assert "removed 2 entries" in capsys.readouterr().out
    assert sorted(p.name for p in cache.root.iterdir()) == sorted([*own, MARKER])


def test_a_folder_that_is_not_femrubs_is_left_alone(tmp_path, capsys):
    folder = tmp_path / "home"
    folder.mkdir()
    (folder / "thesis.pkl").write_text("user's")
    (folder / "run.tmp").write_text("user's")
    assert main(["cache", "clear", "--cache-dir", str(folder)]) == 0
    out = capsys.readouterr().out
    assert "removed 0 entries" in out and "not femrub's" in out
    notes = []
    cache = ModelCache(folder, log=notes.append)
    assert not cache.store(content_key("k"), np.ones(2), stage="t")
    assert "did not write" in notes[0] and "--cache-dir" in notes[0]
    assert sorted(p.name for p in folder.iterdir()) == ["run.tmp", "thesis.pkl"]


def test_symlinks_in_the_cache_are_not_followed(cache, tmp_path):
    outside = tmp_path / "outside.json"
    outside.write_text("precious")
    key = content_key("link")
    assert cache.store(key, np.ones(2), stage="test")
    meta = cache.root / f"{key}.json"
    meta.unlink()
    meta.symlink_to(outside)
    before = outside.stat().st_mtime_ns
    assert cache.load(key) is None  # not read through the link: rebuilt
    assert outside.read_text() == "precious" and outside.stat().st_mtime_ns == before
    data = cache.root / f"{content_key('link2')}.npz"
    data.symlink_to(outside)
    assert cache.store(content_key("link2"), np.ones(2), stage="test")  # replaces the link
    assert outside.read_text() == "precious" and not data.is_symlink()


def test_every_kind_of_value_round_trips(cache):
    import scipy.sparse as sp

    value = {
        "f": 1.5,
        "nan": float("nan"),
        "c": 1 + 2j,
        "i": np.int32(3),
        "t": (1, None, True, "s"),
        "l": [np.arange(3), sp.csr_matrix(np.eye(3)), sp.csc_array(np.eye(2))],
        4: "int key",
    }
    key = content_key("round trip")
    assert cache.store(key, value, stage="test")
    back = cache.load(key)
    assert back["f"] == 1.5 and np.isnan(back["nan"]) and back["c"] == 1 + 2j
    assert back["i"] == 3 and back["i"].dtype == np.int32 and back["t"] == (1, None, True, "s")
    assert back[4] == "int key" and isinstance(back["l"][2], sp.csc_array)
    assert (back["l"][1] != sp.csr_matrix(np.eye(3))).nnz == 0


def test_an_array_held_in_several_places_is_stored_once_and_comes_back_shared(cache):
    """A reductor holds its basis as its left basis and its map to the mesh too: one array
    in the entry (not three copies on disk and in every process that loads it); an equal
    array that is another object stays its own."""
    from femrub.app.cache_codec import decode, encode

    basis = np.arange(12.0).reshape(4, 3)
    value = {"R": basis, "left": basis, "map": [basis], "copy": basis.copy()}
    tree, arrays = encode(value)
    assert len(arrays) == 2
    key = content_key("shared arrays")
    assert cache.store(key, value, stage="test")
    back = cache.load(key)
    assert back["R"] is back["left"] is back["map"][0] and back["copy"] is not back["R"]
    assert np.array_equal(back["copy"], basis) and np.array_equal(back["R"], basis)
    assert decode(tree, arrays)["left"] is basis


def test_code_is_not_stored(cache):
    assert not cache.store(content_key("f"), {"f": print}, stage="test")
    assert "not stored" in cache.notes[-1]


def test_femrub_check_on_a_cache_of_crafted_entries_runs_no_code(tmp_path, capsys, monkeypatch):
    """Every entry of a real cache replaced by a crafted one with a matching checksum (an
    object array that would run code when unpickled, a legacy pickle): `femrub check` runs
    no code, rebuilds each entry and stores it again (a build keeps nothing in memory for
    another: every stage goes through the disk cache)."""
    folder = tmp_path / "shared-cache"
    argv = ["check", "paper", "-q", "--cache-dir", str(folder)]
    assert main(argv) == 0
    keys = [p.stem for p in folder.glob("*.json")]
    assert keys
    sentinel = tmp_path / "executed"
    crafted = ModelCache(folder)
    for key in keys:
        exploit = np.empty(1, dtype=object)
        exploit[0] = _Exploit(sentinel)
        _plant(crafted, key, {"$": "array", "ref": "a0"}, {"a0": exploit})
        (folder / f"{key}.pkl").write_bytes(pickle.dumps(_Exploit(sentinel)))
    assert main(argv) == 0
    assert not sentinel.exists()
    assert all(ModelCache(folder).load(k) is not None for k in keys)  # rebuilt and stored
