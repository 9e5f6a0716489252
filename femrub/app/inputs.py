"""The files a scene names and the digest of their bytes (part of every run's key).

A scene's result depends on more than its text: the mesh or deck file (every node, mid-side
nodes included), the files that deck includes (``*INCLUDE, INPUT=...``, followed as the
reader follows them), the section files of a ``sections`` blade (the folder's files matching
``pattern``, or ``files``). :func:`input_files` lists them; :func:`inputs_digest` is the
SHA-256 of their names and contents, which :func:`femrub.app.run.scene_hash` folds in with
the source version (:func:`femrub.app.cache.source_version`): an edited mesh file or a new
femrub gives a new key, and a resumed sweep runs its points again.

A process reads a file once for its digest and its includes while the file's status (size,
modification and change times, inode, device) stays the same: the 40 points of a map on one
deck hash it once, not 40 times (Rotor 37: 23 ms each).
"""

from __future__ import annotations

import hashlib
import re
import stat
from pathlib import Path

__all__ = ["input_files", "inputs_digest"]

_INCLUDE = re.compile(r"^\s*\*\s*INCLUDE\s*,(.*)$", re.IGNORECASE)
_INPUT = re.compile(r"INPUT\s*=\s*([^,]+)", re.IGNORECASE)
_CHUNK = 2**22
#: include nesting followed (the deck reader refuses deeper ones)
MAX_DEPTH = 10


#: what was read of a file, by ``(kind, path)``, and digests, by the files' status:
#: ``(status, value)``; at most this many
MEMO_FILES = 64
_memo: dict = {}


def _status(path: Path):
    """What changes when a file is written or replaced (``None``: not a regular file)."""
    try:
        st = path.stat()
    except OSError:
        return None
    if not stat.S_ISREG(st.st_mode):
        return None
    return st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino, st.st_dev


def _read_once(kind: str, path: Path, read):
    """``read(path)``, again only when the file's :func:`_status` changed."""
    status = _status(path)
    hit = _memo.get((kind, path))
    if status is not None and hit is not None and hit[0] == status:
        return hit[1]
    value = read(path)
    if status is not None and status == _status(path):  # not written while read
        _remember((kind, path), (status, value))
    return value


def _remember(key, value) -> None:
    if len(_memo) >= MEMO_FILES:
        _memo.pop(next(iter(_memo)))  # the oldest
    _memo[key] = value


def _includes(path: Path) -> list[Path]:
    """The files ``*INCLUDE``d by the Abaqus/CalculiX deck ``path`` (relative to it)."""
    return list(_read_once("includes", path, _read_includes))


def _read_includes(path: Path) -> tuple:
    out = []
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                m = _INCLUDE.match(line)
                name = _INPUT.search(m.group(1)) if m else None
                if name:
                    out.append((path.parent / name.group(1).strip().strip("'\"")).resolve())
    except OSError:
        pass
    return tuple(out)


def _deck_files(path: Path, depth: int = 0, seen=None) -> list[Path]:
    seen = set() if seen is None else seen
    if path in seen or depth > MAX_DEPTH:
        return []
    seen.add(path)
    files = [path]
    if path.suffix.lower() in (".inp", ".msh") and _is_regular(path):
        for inc in _includes(path):
            files += _deck_files(inc, depth + 1, seen)
    return files


def _is_regular(path: Path) -> bool:
    return _status(path) is not None


def input_files(scene) -> list[Path]:
    """Every file the scene's geometry reads, in reading order."""
    g = scene["geometry"]
    if g["kind"] == "mesh":
        return _deck_files(scene.path(g["path"]).resolve())
    if g["kind"] != "sections":
        return []
    if g.get("files"):
        return [scene.path(f).resolve() for f in g["files"]]
    if g.get("path") is None:
        return []
    folder = scene.path(g["path"]).resolve()
    return sorted(folder.glob(g.get("pattern") or "*.csv"))


def _feed_file(h, path: Path) -> None:
    h.update(str(path).encode() + b"\0")
    if not _is_regular(path):  # missing, a device, a folder: named, not read
        h.update(b"<not a regular file>")
        return
    with open(path, "rb") as f:
        while chunk := f.read(_CHUNK):
            h.update(chunk)
    h.update(b"\0")


def inputs_digest(scene) -> str:
    """SHA-256 (hex) of the names and bytes of :func:`input_files` (read again only when a
    file's status changed)."""
    files = tuple(input_files(scene))
    status = tuple((str(p), _status(p)) for p in files)
    hit = _memo.get(("digest", status))
    if hit is not None:
        return hit[1]
    h = hashlib.sha256()
    for path in files:
        _feed_file(h, path)
    digest = h.hexdigest()
    if status == tuple((str(p), _status(p)) for p in files):  # none written while read
        _remember(("digest", status), (status, digest))
    return digest
