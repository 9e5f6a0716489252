"""A content-addressed, size-limited on-disk store of built models (``femrub cache``).

An entry is one pickled object under a key that is the SHA-256 of everything that built it
(:func:`content_key`: arrays by their bytes, shape and dtype, sparse matrices by their
canonical CSR or CSC arrays in the format they come in (no conversion), other values by
their ``repr``, plus :func:`code_version`, the hash of femrub's model-building source). Two
files per entry in the cache folder: ``KEY.pkl`` (the object) and ``KEY.json`` (stage,
size, SHA-256 of ``KEY.pkl``, creation time, femrub version, a description). Writes go to a
temporary file renamed into place, the data before the metadata, so concurrent runs (sweep
workers) never see half an entry; a reader checks the checksum and treats a mismatch or an
unreadable entry as a miss, deletes it and says so (``log``): the caller rebuilds it.

The folder is bounded: after each store the least recently used entries (a hit touches its
metadata) are removed until the total fits ``limit`` bytes. ``clear()`` empties it,
``info()`` describes it. Where it lives and its size are options of the command line
(``--cache-dir``, ``$FEMRUB_CACHE_DIR``, default :func:`default_dir`; ``$FEMRUB_CACHE_SIZE``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import pickle
import re
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

__all__ = [
    "DEFAULT_LIMIT",
    "ModelCache",
    "code_version",
    "content_key",
    "default_dir",
    "parse_size",
]

#: Default size limit of the cache folder (bytes): a reduced Rotor 37 entry is a few
#: hundred MB (its map to the full mesh is dense).
DEFAULT_LIMIT = 8 * 2**30
#: Package folders whose source code shapes the assembled and reduced matrices.
CODE_FOLDERS = ("fem", "model", "contact", "reduction")
_CHUNK = 2**22


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
    return int(float(m.group(1)) * scale[unit])


_CODE: str | None = None


def code_version() -> str:
    """femrub's version and the SHA-256 of the model-building source (:data:`CODE_FOLDERS`)."""
    global _CODE
    if _CODE is None:
        from .. import __version__

        root = Path(__file__).resolve().parents[1]
        h = hashlib.sha256(__version__.encode())
        for folder in CODE_FOLDERS:
            for path in sorted((root / folder).glob("*.py")):
                h.update(path.name.encode())
                h.update(path.read_bytes())
        _CODE = f"{__version__}+{h.hexdigest()[:16]}"
    return _CODE


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


class _HashingWriter:
    """A file wrapper that hashes what it writes (one pass to store and checksum)."""

    def __init__(self, f):
        self.f, self.h, self.size = f, hashlib.sha256(), 0

    def write(self, b) -> int:
        self.h.update(b)
        self.size += memoryview(b).nbytes
        return self.f.write(b)


def _file_hash(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(_CHUNK):
            h.update(chunk)
    return h.hexdigest()


class ModelCache:
    """The cache folder ``root`` (default :func:`default_dir`), at most ``limit`` bytes.

    ``log``: callable for notices (a corrupt entry rebuilt, an entry too large to keep).
    """

    def __init__(self, root=None, limit: int = DEFAULT_LIMIT, log=None):
        self.root = Path(root) if root is not None else default_dir()
        self.limit = int(limit)
        self.log = log

    def __repr__(self) -> str:
        return f"ModelCache({str(self.root)!r}, limit={self.limit})"

    def __reduce__(self):  # sweep workers get the folder and the limit, not the log
        return (ModelCache, (str(self.root), self.limit))

    def _paths(self, key: str) -> tuple[Path, Path]:
        return self.root / f"{key}.pkl", self.root / f"{key}.json"

    def _notice(self, text: str) -> None:
        if self.log:
            self.log(text)

    # -- entries ----------------------------------------------------------------------------
    def load(self, key: str):
        """The object stored under ``key``, or ``None`` (a miss, or a corrupt entry removed)."""
        data, meta = self._paths(key)
        try:
            info = json.loads(meta.read_text())
        except (OSError, ValueError):
            return None
        try:
            if _file_hash(data) != info["sha256"]:
                raise ValueError("checksum mismatch")
            with open(data, "rb") as f:
                obj = pickle.load(f)
        except Exception as exc:  # noqa: BLE001 - any unreadable entry is rebuilt
            what = exc if isinstance(exc, ValueError) else type(exc).__name__
            self._notice(
                f"cache: entry {key[:12]} ({info.get('stage', '?')}) is corrupt ({what}); "
                "removed, rebuilding it"
            )
            self._remove(key)
            return None
        try:
            os.utime(meta)  # least recently used order
        except OSError:
            pass
        return obj

    def store(self, key: str, obj, *, stage: str, describe: str = "") -> bool:
        """Store ``obj`` under ``key``; ``False`` when it cannot be (unpicklable, too large,
        or the folder not writable: the run goes on without the cache)."""
        data, meta = self._paths(key)
        tmp = None
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=self.root, suffix=".tmp")
            with os.fdopen(fd, "wb") as f:
                w = _HashingWriter(f)
                pickle.dump(obj, w, protocol=5)
            if w.size > self.limit:
                self._notice(
                    f"cache: {stage} entry of {w.size / 1e6:.0f} MB exceeds the cache size "
                    f"{self.limit / 1e6:.0f} MB; not kept"
                )
                os.unlink(tmp)
                return False
            os.replace(tmp, data)
            tmp = None
            info = {
                "key": key,
                "stage": stage,
                "size": w.size,
                "sha256": w.h.hexdigest(),
                "created": time.time(),
                "code": code_version(),
                "describe": describe,
            }
            fd, tmp = tempfile.mkstemp(dir=self.root, suffix=".tmp")
            with os.fdopen(fd, "w") as f:
                json.dump(info, f)
            os.replace(tmp, meta)
            tmp = None
        except (OSError, pickle.PicklingError, TypeError, AttributeError) as exc:
            self._notice(f"cache: {stage} entry not stored ({type(exc).__name__}: {exc})")
            return False
        finally:
            if tmp is not None:
                Path(tmp).unlink(missing_ok=True)
        self._evict(keep=key)
        return True

    def _remove(self, key: str) -> int:
        freed = 0
        for p in self._paths(key):
            try:
                freed += p.stat().st_size
                p.unlink()
            except OSError:
                pass
        return freed

    def entries(self) -> list[dict]:
        """Metadata of every entry, least recently used first (``used``: last access time)."""
        out = []
        if not self.root.is_dir():
            return out
        for meta in self.root.glob("*.json"):
            try:
                info = json.loads(meta.read_text())
                info["used"] = meta.stat().st_mtime
            except (OSError, ValueError):
                continue
            out.append(info)
        return sorted(out, key=lambda e: e["used"])

    def _evict(self, keep: str | None = None) -> None:
        entries = self.entries()
        total = sum(e.get("size", 0) for e in entries)
        for e in entries:
            if total <= self.limit:
                break
            if e["key"] != keep:
                self._remove(e["key"])
                total -= e.get("size", 0)

    def clear(self) -> tuple[int, int]:
        """Remove every entry (and stray temporary files); return ``(entries, bytes)``."""
        n = freed = 0
        for e in self.entries():
            freed += self._remove(e["key"])
            n += 1
        if self.root.is_dir():
            for p in list(self.root.glob("*.pkl")) + list(self.root.glob("*.tmp")):
                freed += p.stat().st_size
                p.unlink(missing_ok=True)
        return n, freed

    def info(self) -> dict:
        """Folder, limit, number of entries and bytes, per stage."""
        entries = self.entries()
        stages: dict[str, dict] = {}
        for e in entries:
            s = stages.setdefault(e.get("stage", "?"), {"entries": 0, "bytes": 0})
            s["entries"] += 1
            s["bytes"] += e.get("size", 0)
        return {
            "root": str(self.root),
            "limit": self.limit,
            "entries": len(entries),
            "bytes": sum(e.get("size", 0) for e in entries),
            "stages": stages,
            "code": code_version(),
        }
