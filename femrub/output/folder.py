"""Ownership of a results folder: its kind, its status, a lock, and safe default names.

Three commands write results folders: ``femrub run`` (kind ``run``), ``femrub sweep``
(``sweep``) and ``femrub paper`` (``paper``). :func:`claim` is called before any expensive
work and guarantees, for the duration of the ``with`` block:

* the folder is writable (else a one-line :class:`FolderError`);
* it is not a folder of another kind (the marker file ``.femrub`` says which command owns
  it; older folders are recognised by their files), whatever ``overwrite`` says;
* it holds no finished result, and no unreadable ``summary.json`` (that may be a finished
  result damaged by hand or by a full disk) unless ``overwrite=True``;
* no other femrub process writes into it (an exclusive ``flock`` on ``.femrub.lock``,
  released when the block ends or the process dies).
"""

from __future__ import annotations

import fcntl
import json
import os
import re
from contextlib import contextmanager
from pathlib import Path

from .jsonfile import read_json

__all__ = [
    "CORRUPT",
    "FINISHED",
    "FolderError",
    "ResultExists",
    "claim",
    "folder_kind",
    "folder_status",
    "safe_name",
]

#: statuses of a finished run: never replaced without ``overwrite``
FINISHED = ("ok", "inaccurate", "unstable", "diverged-physically")
#: what :func:`folder_status` returns for a ``summary.json`` that cannot be read
CORRUPT = "corrupt"
MARKER = ".femrub"
LOCK = ".femrub.lock"


class FolderError(ValueError):
    """The output folder cannot be used (one-line message naming the fix)."""


class ResultExists(FileExistsError):
    """The output folder already holds a finished result."""


def folder_status(out) -> str | None:
    """Status of ``out/summary.json``: ``None`` when absent, :data:`CORRUPT` when unreadable."""
    path = Path(out) / "summary.json"
    if not path.exists():
        return None
    try:
        status = read_json(path).get("status")
    except ValueError:
        return CORRUPT
    return status if isinstance(status, str) else CORRUPT


def folder_kind(out) -> str | None:
    """Which command owns ``out``: the marker, else guessed from its files (``None``: empty)."""
    out = Path(out)
    try:
        kind = json.loads((out / MARKER).read_text()).get("kind")
        if isinstance(kind, str):
            return kind
    except (OSError, ValueError, AttributeError):
        pass
    if (out / "sweep.json").exists():
        return "sweep"
    if (out / "summary.json").exists():
        try:
            return "paper" if "runs" in read_json(out / "summary.json") else "run"
        except ValueError:
            return "run"
    return None


def safe_name(name: str, fallback: str = "scene") -> str:
    """A folder name from a scene name: letters, digits, ``_.-`` only; no path, no dot-start."""
    text = re.sub(r"[^A-Za-z0-9_.-]+", "_", str(name)).strip("._-")
    return text[:80] or fallback


def _check_writable(out: Path) -> None:
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".femrub-probe-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        why = exc.strerror or type(exc).__name__
        raise FolderError(
            f"cannot write to the output folder {out}: {why}; use another -o"
        ) from None


def _check_result(out: Path, kind: str, overwrite: bool) -> None:
    owner = folder_kind(out)
    if owner is not None and owner != kind:
        raise FolderError(
            f"{out} holds the results of `femrub {owner}`; `femrub {kind}` does not write "
            "there (even with --overwrite): use another folder"
        )
    status = folder_status(out)
    if overwrite:
        return
    if status == CORRUPT:
        raise ResultExists(
            f"{out}/summary.json is unreadable (a damaged result?); "
            "use another folder or --overwrite"
        )
    if status in FINISHED:
        raise ResultExists(
            f"{out} already holds a finished result (status {status}); "
            "use another folder or --overwrite"
        )


@contextmanager
def claim(out, kind: str, *, overwrite: bool = False, check_result: bool = True):
    """Own ``out`` for a ``kind`` of results while the block runs (module docstring).

    ``check_result=False`` skips the finished-result check (a sweep folder is resumed: its
    points carry their own results).
    """
    out = Path(out)
    _check_writable(out)
    fh = open(out / LOCK, "a+")  # noqa: SIM115 (held for the whole block)
    try:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.seek(0)
            who = fh.read().strip() or "?"
            raise FolderError(
                f"{out} is in use by another femrub process (pid {who}); wait for it or use "
                "another folder"
            ) from None
        if check_result:
            _check_result(out, kind, overwrite)
        elif folder_kind(out) not in (None, kind):
            _check_result(out, kind, True)
        fh.seek(0)
        fh.truncate()
        fh.write(str(os.getpid()))
        fh.flush()
        (out / MARKER).write_text(json.dumps({"kind": kind}) + "\n")
        yield out
    finally:
        fh.close()  # releases the lock
