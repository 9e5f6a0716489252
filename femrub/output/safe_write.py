"""Writes into results folders that never follow a symbolic link.

A finished file is written to a temporary file created beside it (``O_EXCL``: never an
existing file or link) and renamed onto its name (the rename replaces a link planted there,
not what it points to); a file streamed while a run goes is opened with ``O_NOFOLLOW``.
"""

from __future__ import annotations

import errno
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

__all__ = ["atomic_file", "describe_os_error", "naming", "open_nofollow", "write_atomic"]

_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


@contextmanager
def atomic_file(path, mode: str = "wb"):
    """A file object whose content replaces ``path`` when the block ends without error
    (temporary ``.NAME.*.tmp`` beside it, flushed and synced, then renamed); on an error
    the temporary is removed and ``path`` is unchanged."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, mode, **({} if "b" in mode else {"newline": ""})) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_atomic(path, data: str | bytes) -> Path:
    """Write ``data`` (text is UTF-8) to ``path`` through :func:`atomic_file`."""
    with atomic_file(path, "wb") as fh:
        fh.write(data.encode() if isinstance(data, str) else data)
    return Path(path)


def open_nofollow(path, mode: str = "w", **kw):
    """``open(path, mode)`` for writing, refusing a symbolic link at ``path`` (``OSError``)."""
    flags = os.O_WRONLY | os.O_CREAT | _NOFOLLOW
    flags |= os.O_APPEND if mode.startswith("a") else os.O_TRUNC
    return os.fdopen(os.open(path, flags, 0o644), mode, **kw)


@contextmanager
def naming(path):
    """Within the block, an ``OSError`` that names no file names ``path`` (a full disk
    raised by ``write()`` otherwise says only ``[Errno 28]``)."""
    try:
        yield
    except OSError as exc:
        if exc.filename is None and exc.errno is not None:
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
        raise


_FIXES = {
    errno.ENOSPC: "free space on that disk (or write to another folder with -o) and rerun",
    errno.EDQUOT: "free space within your quota (or write to another folder with -o) and rerun",
    errno.EIO: "check the disk and the file (copy it elsewhere) and rerun",
    errno.EACCES: "give yourself access to it or use another file or folder",
    errno.EROFS: "use a writable folder (-o)",
}


def describe_os_error(exc: OSError, doing: str = "access") -> str:
    """One line: what failed on which file and the fix."""
    what = exc.strerror or type(exc).__name__
    name = f" {exc.filename}" if exc.filename else ""
    fix = _FIXES.get(exc.errno, "check the file and the disk and rerun")
    return f"cannot {doing}{name}: {what}; {fix}"
