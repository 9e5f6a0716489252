"""Ownership of a results folder: its kind, its status, a lock, and safe default names.

Four commands write results folders: ``femrub run`` (kind ``run``), ``femrub sweep``
(``sweep``), ``femrub paper`` (``paper``) and ``femrub modes`` (``modes``). :func:`claim`
is called before any expensive work and guarantees, for the duration of the ``with`` block:

* the folder is writable (else a one-line :class:`FolderError`);
* it is not a folder of another kind (the marker file ``.femrub`` says which command owns
  it; older folders are recognised by their files), whatever ``overwrite`` says;
* it holds no finished result, and no unreadable ``summary.json`` (that may be a finished
  result damaged by hand or by a full disk) unless ``overwrite=True``;
* no other femrub process writes into it (an exclusive ``flock`` on ``.femrub.lock``,
  released when the block ends or the process dies);
* a folder that holds files but not femrub's marker (nor an older femrub's results) is not
  written into unless ``overwrite=True``, and even then femrub replaces none of its files:
  a file there with the name of one of femrub's outputs (:data:`OUTPUTS`: ``scene.toml``,
  ``history.csv``...) is refused by name;
* none of the names femrub writes (its outputs, their temporaries, the marker, the lock,
  the files in ``vtk/``) is a symbolic link (a write would go through it);
* a run folder of femrub's is emptied of the previous run's outputs (VTK series included)
  before the new run writes anything, so no file of another run stays beside it.
"""

from __future__ import annotations

import fcntl
import json
import os
import re
from contextlib import contextmanager
from pathlib import Path

from .jsonfile import read_json
from .safe_write import write_atomic

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
#: the names (glob patterns) each kind of folder writes at its top level
OUTPUTS = {
    "run": (
        "summary.json",
        "history.csv",
        "history.npz",
        "scene.toml",
        "explain.txt",
        "signals.png",
        "snapshot.png",
        "response.png",
        "spectrum.png",
        "contact_forces.png",
        "wear_map.csv",
        "wear_history.csv",
        "wear_map.png",
        "casing_temperature.csv",
        "vtk",
    ),
    "sweep": ("sweep.json", "scene.toml", "interaction.csv", "interaction.png", "runs"),
    "paper": ("summary.json", "runs", "fig*.png", "fig*.csv", "energy_*.png"),
    "periodic": ("summary.json", "branch.csv", "branch.png", "orbits"),
    "modes": ("summary.json", "modes.csv", "modes.png", "coincidences.csv", "campbell.png"),
}
#: the files of a run's VTK series (in ``vtk/``)
VTK_FILES = ("rub_*.vtu", "rub.pvd", "casing_*.vtu", "casing.pvd", "*.tmp")
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


class FolderError(ValueError):
    """The output folder cannot be used (one-line message naming the fix)."""


class ResultExists(FileExistsError):
    """The output folder already holds a finished result."""


def folder_status(out) -> str | None:
    """Status of ``out/summary.json``: ``None`` when absent, :data:`CORRUPT` when unreadable.

    Parameters
    ----------
    out : str or pathlib.Path
        A results folder.

    Returns
    -------
    str or None
        ``"ok"``, ``"inaccurate"``, ``"unstable"``, ``"diverged-physically"`` (finished,
        :data:`FINISHED`), ``"interrupted"``, ``"failed"``, ``"running"`` while a run writes
        it, ``"corrupt"`` or ``None``.
    """
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
    if (out / "summary.json").exists():  # an older femrub's folder: a summary with a status
        try:
            doc = read_json(out / "summary.json")
        except ValueError:
            return None  # not femrub's to judge: a user's file
        if "status" in doc:
            return "paper" if "runs" in doc else "run"
    return None


def safe_name(name: str, fallback: str = "scene") -> str:
    """A folder name from a scene name: letters, digits, ``_.-`` only; no path, no dot-start."""
    text = re.sub(r"[^A-Za-z0-9_.-]+", "_", str(name)).strip("._-")
    return text[:80] or fallback


def _check_writable(out: Path) -> None:
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".femrub-probe-{os.getpid()}"
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW, 0o600))
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


def _outputs(out: Path, kind: str) -> list[Path]:
    """The entries of ``out`` named like ``kind``'s outputs (links included)."""
    found = []
    for pattern in OUTPUTS[kind]:
        if any(c in pattern for c in "*?["):
            found += sorted(out.glob(pattern))
        elif os.path.lexists(out / pattern):
            found.append(out / pattern)
    return found


def _check_links(out: Path, kind: str) -> None:
    """Refuse a symbolic link where femrub writes (outputs, temporaries, marker, lock, vtk/)."""
    names = [*_outputs(out, kind), *out.glob("*.tmp"), *out.glob(".*.tmp")]
    names += [out / MARKER, out / LOCK]
    vtk = out / "vtk"
    if kind == "run" and vtk.is_dir() and not vtk.is_symlink():
        names += list(vtk.iterdir())
    for path in names:
        if path.is_symlink():
            raise FolderError(
                f"{path} is a symbolic link; femrub never writes through one: remove the link "
                "or use another folder"
            )


def _check_foreign(out: Path, kind: str, overwrite: bool) -> None:
    """A folder with files and no trace of femrub: refused without ``overwrite``; with it,
    none of its files may bear the name of one of femrub's outputs."""
    if folder_kind(out) is not None:
        return
    files = [p.name for p in out.iterdir() if p.name not in (LOCK,)]
    if not files:
        return
    if not overwrite:
        raise FolderError(
            f"{out} is not empty ({files[0]}, ...) and was not written by femrub (no {MARKER}); "
            "use an empty or new folder, or --overwrite to write beside its files"
        )
    clash = _outputs(out, kind)
    if clash:
        raise FolderError(
            f"{clash[0]} was not written by femrub and femrub does not replace it: move it or "
            "use another folder"
        )


def _clear_run(out: Path) -> None:
    """Remove the previous run's outputs (every file :data:`OUTPUTS` names, the VTK series)."""
    for path in _outputs(out, "run"):
        if path.name == "vtk":
            continue
        if path.is_file() or path.is_symlink():
            path.unlink(missing_ok=True)
    vtk = out / "vtk"
    if vtk.is_dir() and not vtk.is_symlink():
        for pattern in VTK_FILES:
            for path in vtk.glob(pattern):
                path.unlink(missing_ok=True)
        if not any(vtk.iterdir()):
            vtk.rmdir()


def _lock(out: Path):
    """``out/.femrub.lock`` opened (never through a link), locked exclusively."""
    try:
        fd = os.open(out / LOCK, os.O_RDWR | os.O_CREAT | _NOFOLLOW, 0o644)
    except OSError as exc:
        raise FolderError(
            f"cannot open the lock {out / LOCK} ({exc.strerror}); remove it or use another folder"
        ) from None
    fh = os.fdopen(fd, "r+")
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        fh.seek(0)
        who = fh.read().strip() or "?"
        fh.close()
        raise FolderError(
            f"{out} is in use by another femrub process (pid {who}); wait for it or use "
            "another folder"
        ) from None
    return fh


@contextmanager
def claim(out, kind: str, *, overwrite: bool = False, check_result: bool = True):
    """Own ``out`` for a ``kind`` of results while the block runs (module docstring).

    ``check_result=False`` skips the finished-result check (a sweep folder is resumed: its
    points carry their own results).
    """
    out = Path(out)
    _check_writable(out)
    _check_links(out, kind)
    fh = _lock(out)
    try:
        _check_foreign(out, kind, overwrite)
        if check_result:
            _check_result(out, kind, overwrite)
        elif folder_kind(out) not in (None, kind):
            _check_result(out, kind, True)
        if kind == "run" and folder_kind(out) == "run":
            _clear_run(out)
        fh.seek(0)
        fh.truncate()
        fh.write(str(os.getpid()))
        fh.flush()
        write_atomic(out / MARKER, json.dumps({"kind": kind}) + "\n")
        yield out
    finally:
        fh.close()  # releases the lock
