"""A content-addressed, size-limited on-disk store of built models (``femrub cache``).

An entry is data, never code. Its key is the SHA-256 (64 hex digits) of everything that
built it (:func:`content_key`: arrays by their bytes, shape and dtype, sparse matrices by
their canonical CSR or CSC arrays in the format they come in (no conversion), other values
by their ``repr``, plus :func:`code_version`, the hash of the source that shapes the
models). A key is checked to be 64 hex digits before any path is formed from it. Two files
per entry in the cache folder:

* ``KEY.npz``: the object as a JSON tree and the arrays it names
  (:mod:`femrub.app.cache_codec`), read with ``allow_pickle=False``; nothing in it is
  executed, and it can only hold instances of femrub's model-building classes;
* ``KEY.json``: its metadata (stage, size, SHA-256 of ``KEY.npz``, creation time, code
  version, a description), checked against :data:`ENTRY_SCHEMA` on every read.

and, once a process has built it, an empty ``KEY.lock``: :meth:`ModelCache.building` holds an
exclusive ``flock`` on it while the entry is built, so that processes that need the same
entry at once (the workers of a sweep) build it once: the others wait and load it. The
operating system releases the lock of a process that dies; the waiting one then finds no
entry and builds it itself.

The folder is femrub's when it holds the marker ``CACHEDIR.TAG`` (the cache directory tag
standard, naming femrub), written when femrub creates the folder or finds it empty: femrub
stores in, reads from, evicts from and clears only a marked folder, and only the files
named after a key (``KEY.npz``, ``KEY.json``, ``KEY.lock``, an older femrub's ``KEY.pkl``,
never read) and its own temporaries ``.KEY.*.tmp``; the metadata files are its manifest. A
folder holding other files and no marker is left alone (the run goes on without the cache,
with a notice).

Writes go to a temporary file beside the target renamed into place, the data before the
metadata, so concurrent runs (sweep workers) never see half an entry; files are opened
without following symbolic links. A reader checks the metadata's schema and the checksum
and treats a malformed, mismatched or unreadable entry as a miss: it removes it, says so
(``log``) and the caller rebuilds it.

The folder is bounded: after each store the least recently used entries (a hit touches its
metadata) are removed until the total fits ``limit`` bytes. ``clear()`` empties it,
``info()`` describes it. Where it lives and its size are options of the command line
(``--cache-dir``, ``$FEMRUB_CACHE_DIR``, default :func:`default_dir`; ``$FEMRUB_CACHE_SIZE``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import hashlib
import json
import os
import re
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from .cache_codec import decode, encode

__all__ = [
    "DEFAULT_LIMIT",
    "ENTRY_SCHEMA",
    "MARKER",
    "ModelCache",
    "check_key",
    "code_version",
    "content_key",
    "default_dir",
    "parse_size",
    "source_version",
]

#: Default size limit of the cache folder (bytes): a reduced Rotor 37 entry is a few
#: hundred MB (its map to the full mesh is dense).
DEFAULT_LIMIT = 8 * 2**30
#: Package folders (searched recursively) and modules whose source shapes the assembled
#: and reduced models and the format of their entries.
CODE_FOLDERS = ("fem", "model", "contact", "reduction", "steppers")
CODE_FILES = ("app/cached.py", "app/cache.py", "app/cache_codec.py")
#: The marker file of a femrub cache folder (https://bford.info/cachedir/).
MARKER = "CACHEDIR.TAG"
_TAG = "Signature: 8a477f597d28d172789f06886806bc55"
_MARKER_TEXT = (
    f"{_TAG}\n# This file is a cache directory tag created by femrub (model cache).\n"
    "# For information about cache directory tags see https://bford.info/cachedir/\n"
)
_FORMAT = "femrub-cache-entry"
_VERSION = 2
_HEX = re.compile(r"[0-9a-f]{64}")
_ENTRY_FILE = re.compile(r"([0-9a-f]{64})\.(npz|json|pkl|lock)")
_TEMP_FILE = re.compile(r"\.([0-9a-f]{64})\..*\.tmp")
_LEGACY_TEMP = re.compile(r"tmp[0-9a-z_]{8}\.tmp")
#: The metadata of an entry: field -> (types, check).
ENTRY_SCHEMA = {
    "format": (str, lambda v: v == _FORMAT),
    "version": (int, lambda v: v == _VERSION),
    "key": (str, lambda v: _HEX.fullmatch(v) is not None),
    "stage": (str, lambda v: 0 < len(v) <= 64),
    "size": (int, lambda v: v >= 0),
    "sha256": (str, lambda v: _HEX.fullmatch(v) is not None),
    "created": ((int, float), lambda v: v >= 0),
    "code": (str, lambda v: len(v) <= 200),
    "describe": (str, lambda v: len(v) <= 1000),
}
_CHUNK = 2**22
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


def default_dir() -> Path:
    """The user's cache folder for femrub (``platformdirs.user_cache_dir("femrub")``)."""
    import platformdirs

    return Path(platformdirs.user_cache_dir("femrub"))


def parse_size(text) -> int:
    """Bytes of ``"500MB"``, ``"8 GiB"``, ``"2e9"`` (decimal and binary units)."""
    m = re.fullmatch(r"\s*([0-9.eE+]+)\s*([kKMGT]?i?B?)?\s*", str(text))
    if not m:
        raise ValueError(f"cache size {text!r}: use a number of bytes or e.g. 500MB, 8GiB")
    unit = (m.group(2) or "").upper().rstrip("B")
    scale = {"": 1, "K": 1e3, "M": 1e6, "G": 1e9, "T": 1e12}
    scale.update({"KI": 2**10, "MI": 2**20, "GI": 2**30, "TI": 2**40})
    if unit not in scale:
        raise ValueError(f"cache size {text!r}: unknown unit")
    try:
        return int(float(m.group(1)) * scale[unit])
    except (ValueError, OverflowError):
        raise ValueError(f"cache size {text!r}: use a number of bytes or e.g. 500MB") from None


_VERSIONS: dict = {}


def _hash_sources(folders, files=()) -> str:
    from .. import __version__

    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256(__version__.encode())
    paths = [p for f in folders for p in sorted((root / f).rglob("*.py"))]
    for path in paths + [root / f for f in files]:
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return f"{__version__}+{h.hexdigest()[:16]}"


def code_version() -> str:
    """femrub's version and the SHA-256 of the model-building source (:data:`CODE_FOLDERS`,
    :data:`CODE_FILES`)."""
    if "models" not in _VERSIONS:
        _VERSIONS["models"] = _hash_sources(CODE_FOLDERS, CODE_FILES)
    return _VERSIONS["models"]


def source_version() -> str:
    """femrub's version and the SHA-256 of all of its source (what shapes a run's result:
    the key of a sweep's points)."""
    if "all" not in _VERSIONS:
        _VERSIONS["all"] = _hash_sources(("",))
    return _VERSIONS["all"]


def _feed(h, x) -> None:
    """Update hash ``h`` with the content of ``x`` (arrays, sparse, containers, scalars)."""
    if isinstance(x, np.ndarray):
        a = np.ascontiguousarray(x)
        h.update(f"nd{a.dtype.str}{a.shape}".encode())
        h.update(a.view(np.uint8).reshape(-1) if a.size else b"")
    elif sp.issparse(x):
        c = x if x.format in ("csr", "csc") else sp.csr_matrix(x)  # hashed in its own format
        if not c.has_canonical_format:  # sorted, no duplicates: one matrix, one key
            c = c.copy()
            c.sum_duplicates()
        h.update(f"sp{c.format}{c.shape}".encode())
        for a in (c.indptr, c.indices, c.data):
            _feed(h, a)
    elif isinstance(x, dict):
        h.update(b"{")
        for k in sorted(x, key=str):
            _feed(h, str(k))
            _feed(h, x[k])
        h.update(b"}")
    elif isinstance(x, list | tuple):
        h.update(b"[")
        for v in x:
            _feed(h, v)
        h.update(b"]")
    elif dataclasses.is_dataclass(x) and not isinstance(x, type):
        h.update(type(x).__name__.encode())
        _feed(h, {f.name: getattr(x, f.name) for f in dataclasses.fields(x)})
    else:
        h.update(repr(x).encode())
        h.update(b";")


def content_key(*parts) -> str:
    """SHA-256 (hex) of ``parts`` and of :func:`code_version`."""
    h = hashlib.sha256(code_version().encode())
    for p in parts:
        _feed(h, p)
    return h.hexdigest()


def check_key(key) -> str:
    """``key`` when it is 64 lowercase hex digits (a :func:`content_key`), else ValueError."""
    if not isinstance(key, str) or _HEX.fullmatch(key) is None:
        raise ValueError(f"cache key {key!r} is not a SHA-256 hex digest")
    return key


def validate_entry(info, key: str) -> dict:
    """``info`` when it is the metadata of entry ``key`` (:data:`ENTRY_SCHEMA`), else
    ValueError naming the first field that is not."""
    if not isinstance(info, dict):
        raise ValueError(f"metadata is a {type(info).__name__}, not a mapping")
    for field, (types, ok) in ENTRY_SCHEMA.items():
        value = info.get(field)
        if isinstance(value, bool) or not isinstance(value, types) or not ok(value):
            raise ValueError(f"metadata field {field!r} is {value!r}")
    if info["key"] != key:
        raise ValueError(f"metadata names key {info['key'][:12]}, not {key[:12]}")
    return info


def _mark_used(meta: Path) -> bool:
    """Touch an entry's metadata (the least recently used order); ``False`` if it cannot be."""
    try:
        os.utime(meta, follow_symlinks=False)
    except OSError:
        return False
    return True


def _open_read(path: Path):
    """``path`` opened for reading without following a symbolic link."""
    return os.fdopen(os.open(path, os.O_RDONLY | _NOFOLLOW), "rb")


def _file_hash(f) -> str:
    h = hashlib.sha256()
    while chunk := f.read(_CHUNK):
        h.update(chunk)
    return h.hexdigest()


def _read_npz(path: Path, sha256: str) -> tuple[bytes, dict]:
    """The tree and arrays of an entry's data file, after its checksum."""
    with _open_read(path) as f:
        if _file_hash(f) != sha256:
            raise ValueError("checksum mismatch")
        f.seek(0)
        with np.load(f, allow_pickle=False) as z:
            arrays = {name: z[name] for name in z.files}
    tree = arrays.pop("__tree__", None)
    if tree is None or tree.dtype != np.uint8:
        raise ValueError("no tree in the data file")
    return tree.tobytes(), arrays


def _write_beside(target: Path, write) -> None:
    """``write(file)`` into a temporary file beside ``target``, renamed onto it."""
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.stem}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class ModelCache:
    """The cache folder ``root`` (default :func:`default_dir`), at most ``limit`` bytes.

    ``log``: callable for notices (a corrupt entry rebuilt, an entry too large to keep, a
    folder that is not femrub's).
    """

    def __init__(self, root=None, limit: int = DEFAULT_LIMIT, log=None):
        self.root = Path(root) if root is not None else default_dir()
        self.limit = int(limit)
        self.log = log
        self._refused = False

    def __repr__(self) -> str:
        return f"ModelCache({str(self.root)!r}, limit={self.limit})"

    def __reduce__(self):  # sweep workers get the folder and the limit, not the log
        return (ModelCache, (str(self.root), self.limit))

    def _paths(self, key: str) -> tuple[Path, Path]:
        check_key(key)
        return self.root / f"{key}.npz", self.root / f"{key}.json"

    def _notice(self, text: str) -> None:
        if self.log:
            self.log(text)

    # -- the folder ---------------------------------------------------------------------------
    def is_marked(self) -> bool:
        """Whether the folder holds femrub's marker (a regular file, not a link)."""
        path = self.root / MARKER
        try:
            with _open_read(path) as f:
                return f.read(len(_TAG)).decode("ascii", "replace") == _TAG
        except OSError:
            return False

    def _claim(self) -> bool:
        """Make the folder femrub's (created, or empty but for femrub's own files) or say
        why not."""
        if self.is_marked():
            return True
        self.root.mkdir(parents=True, exist_ok=True)
        foreign = [
            p.name
            for p in self.root.iterdir()
            if not (_ENTRY_FILE.fullmatch(p.name) or _LEGACY_TEMP.fullmatch(p.name))
        ]
        if foreign:
            if not self._refused:
                self._notice(
                    f"cache: {self.root} holds files femrub did not write ({foreign[0]}, ...) "
                    f"and no {MARKER}; models are not cached there (give --cache-dir an empty "
                    "or new folder)"
                )
            self._refused = True
            return False
        _write_beside(self.root / MARKER, lambda f: f.write(_MARKER_TEXT.encode()))
        return True

    # -- entries ----------------------------------------------------------------------------
    def _read_meta(self, key: str) -> dict | None:
        meta = self._paths(key)[1]
        try:
            with _open_read(meta) as f:
                text = f.read(1_000_000)
        except FileNotFoundError:
            return None
        return validate_entry(json.loads(text), key)

    def load(self, key: str):
        """The object stored under ``key``, or ``None`` (a miss, or a malformed or corrupt
        entry, removed with a notice)."""
        data, meta = self._paths(key)
        if not self.is_marked():
            return None
        stage = "?"
        try:
            info = self._read_meta(key)
            if info is None:
                return None
            stage = info["stage"]
            obj = decode(*_read_npz(data, info["sha256"]))
        except (OSError, ValueError, EOFError) as exc:
            self._notice(
                f"cache: entry {key[:12]} ({stage}) is corrupt or malformed ({exc}); "
                "skipped and removed, rebuilding it"
            )
            self._remove(key)
            return None
        _mark_used(meta)
        return obj

    @contextlib.contextmanager
    def building(self, key: str, stage: str = "entry"):
        """Hold the right to build the entry ``key`` for the block (single flight).

        An exclusive ``flock`` on ``KEY.lock``: while another process holds it (it builds
        the same entry) this one waits, says so (``log``) and then goes on, the entry
        stored by then (the caller loads it again before building). Nothing is locked when
        the folder is not femrub's or the lock file cannot be opened: the entry may then be
        built twice, never half-read (stores are atomic)."""
        fd = None
        try:
            if self._claim():
                path = self.root / f"{check_key(key)}.lock"
                fd = os.open(path, os.O_RDWR | os.O_CREAT | _NOFOLLOW, 0o600)
        except OSError:
            fd = None
        try:
            if fd is not None:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except BlockingIOError:
                    t0 = time.perf_counter()
                    self._notice(f"cache: {stage} ({key[:12]}) is being built by another process")
                    fcntl.flock(fd, fcntl.LOCK_EX)
                    self._notice(f"cache: waited {time.perf_counter() - t0:.1f} s for {stage}")
            yield
        finally:
            if fd is not None:
                os.close(fd)  # releases the lock

    def holds(self, key: str) -> bool:
        """Whether the folder holds an entry ``key`` (valid metadata and a data file of the
        size it records), marked as just used; its checksum is checked when it is loaded. An
        entry is content-addressed: storing it again would write the same bytes."""
        data, meta = self._paths(key)
        if not self.is_marked():
            return False
        try:
            info = self._read_meta(key)
            if info is None or data.lstat().st_size != info["size"]:
                return False
        except (OSError, ValueError):
            return False
        return _mark_used(meta)

    def store(self, key: str, obj, *, stage: str, describe: str = "") -> bool:
        """Store ``obj`` under ``key``; ``False`` when it cannot be (not data, too large,
        the folder not femrub's or not writable: the run goes on without the cache)."""
        data, meta = self._paths(key)
        try:
            tree, arrays = encode(obj)
        except TypeError as exc:
            self._notice(f"cache: {stage} entry not stored ({exc})")
            return False
        size = len(tree) + sum(a.nbytes for a in arrays.values())
        if size > self.limit:
            self._notice(
                f"cache: {stage} entry of {size / 1e6:.0f} MB exceeds the cache size "
                f"{self.limit / 1e6:.0f} MB; not kept"
            )
            return False
        arrays["__tree__"] = np.frombuffer(tree, dtype=np.uint8)
        try:
            if not self._claim():
                return False
            _write_beside(data, lambda f: np.savez(f, **arrays))
            with _open_read(data) as f:
                digest = _file_hash(f)
            info = {
                "format": _FORMAT,
                "version": _VERSION,
                "key": key,
                "stage": stage,
                "size": data.lstat().st_size,
                "sha256": digest,
                "created": time.time(),
                "code": code_version(),
                "describe": describe[:1000],
            }
            _write_beside(meta, lambda f: f.write(json.dumps(info).encode()))
        except OSError as exc:
            self._notice(f"cache: {stage} entry not stored ({type(exc).__name__}: {exc})")
            return False
        self._evict(keep=key)
        return True

    def _remove(self, key: str) -> int:
        freed = 0
        for p in (*self._paths(key), self.root / f"{check_key(key)}.pkl"):  # not its lock
            try:
                freed += p.lstat().st_size
                p.unlink()
            except OSError:
                pass
        return freed

    def entries(self) -> list[dict]:
        """Metadata of every valid entry, least recently used first (``used``: last access
        time); a malformed metadata file is skipped."""
        out = []
        if not self.root.is_dir() or not self.is_marked():
            return out
        for meta in self.root.glob("*.json"):
            key = meta.stem
            if _HEX.fullmatch(key) is None:
                continue
            try:
                info = self._read_meta(key)
                if info is None:
                    continue
                info["used"] = meta.lstat().st_mtime
            except (OSError, ValueError):
                continue
            out.append(info)
        return sorted(out, key=lambda e: e["used"])

    def _evict(self, keep: str | None = None) -> None:
        entries = self.entries()
        total = sum(e["size"] for e in entries)
        for e in entries:
            if total <= self.limit:
                break
            if e["key"] != keep:
                self._remove(e["key"])
                total -= e["size"]

    def clear(self) -> tuple[int, int]:
        """Remove every entry femrub wrote and its temporaries; return ``(entries, bytes)``
        actually removed. A folder without femrub's marker is left alone (``(0, 0)``)."""
        if not self.root.is_dir() or not self.is_marked():
            if self.root.exists():
                self._notice(f"cache: {self.root} has no {MARKER}: not femrub's, nothing removed")
            return 0, 0
        keys, freed = set(), 0
        for p in self.root.iterdir():
            m = _ENTRY_FILE.fullmatch(p.name) or _TEMP_FILE.fullmatch(p.name)
            if m is None:
                continue
            try:
                size = p.lstat().st_size
                p.unlink()
            except OSError:
                continue
            freed += size
            if not p.name.endswith((".tmp", ".lock")):
                keys.add(m.group(1))
        return len(keys), freed

    def info(self) -> dict:
        """Folder, limit, number of entries and bytes, per stage."""
        entries = self.entries()
        stages: dict[str, dict] = {}
        for e in entries:
            s = stages.setdefault(e["stage"], {"entries": 0, "bytes": 0})
            s["entries"] += 1
            s["bytes"] += e["size"]
        return {
            "root": str(self.root),
            "marked": self.is_marked(),
            "limit": self.limit,
            "entries": len(entries),
            "bytes": sum(e["size"] for e in entries),
            "stages": stages,
            "code": code_version(),
        }
