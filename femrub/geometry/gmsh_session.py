"""A leak-free gmsh session: initialise, quiet, clean up, restore."""

from __future__ import annotations

import ctypes
import itertools
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager

import gmsh

from .errors import GeometryError

__all__ = ["GmshSession", "gmsh_session"]

_COUNTER = itertools.count()


@contextmanager
def _quiet_output(enabled: bool) -> Iterator[None]:
    """Send file descriptors 1 and 2 to the null device.

    gmsh (and its bundled libraries) print some diagnostics with printf/fprintf,
    bypassing ``General.Terminal``; this silences them for the duration.
    """
    if not enabled:
        yield
        return
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(1), os.dup(2)]
    except (OSError, ValueError, AttributeError):  # pragma: no cover - no usable fds
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    try:
        yield
    finally:
        try:
            ctypes.CDLL(None).fflush(None)
        except (OSError, AttributeError):  # pragma: no cover - not a POSIX libc
            pass
        for fd, copy in zip((1, 2), saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)


class GmshSession:
    """Handle to the temporary gmsh model created by :func:`gmsh_session`.

    Options set through :meth:`set_option` are restored on exit when gmsh was
    already initialised by the caller, so no state leaks in either direction.
    """

    def __init__(self, model_name: str) -> None:
        self.model_name = model_name
        self._saved: dict[str, float | str] = {}

    def set_option(self, name: str, value: float | str) -> None:
        """Set a gmsh option, remembering its previous value for restoration."""
        if isinstance(value, str):
            self._saved.setdefault(name, gmsh.option.getString(name))
            gmsh.option.setString(name, value)
        else:
            self._saved.setdefault(name, gmsh.option.getNumber(name))
            gmsh.option.setNumber(name, float(value))

    def restore_options(self) -> None:
        """Put back every option changed through :meth:`set_option`."""
        for name, value in self._saved.items():
            if isinstance(value, str):
                gmsh.option.setString(name, value)
            else:
                gmsh.option.setNumber(name, value)
        self._saved.clear()

    def last_errors(self) -> str:
        """Last error/warning lines of the gmsh logger, joined on one line."""
        try:
            lines = [ln for ln in gmsh.logger.get() if ln.startswith(("Error", "Warning"))]
        except Exception:  # pragma: no cover - logger unavailable
            return ""
        return " | ".join(lines[-3:])


@contextmanager
def gmsh_session(verbose: bool = False, name: str = "femrub") -> Iterator[GmshSession]:
    """Run gmsh API calls in a fresh model and clean up afterwards.

    gmsh is initialised without signal handlers and without reading user
    configuration files when not yet initialised, and finalised on exit. If the
    caller already initialised gmsh, a new model is added and removed, the
    previous current model is reinstated and changed options are restored.

    Parameters
    ----------
    verbose : bool, optional
        Print gmsh messages on the terminal.
    name : str, optional
        Prefix of the temporary model name.

    Yields
    ------
    GmshSession
        Use :meth:`GmshSession.set_option` to change options.

    Raises
    ------
    GeometryError
        Wrapping any gmsh error raised inside the block, with gmsh's last messages.
    """
    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
        previous = None
    else:
        previous = gmsh.model.getCurrent()
    session = GmshSession(f"{name}-{next(_COUNTER)}")
    session.set_option("General.Terminal", 1 if verbose else 0)
    session.set_option("General.Verbosity", 5 if verbose else 2)
    if owner:
        gmsh.logger.start()
    gmsh.model.add(session.model_name)
    try:
        with _quiet_output(not verbose):
            yield session
    except Exception as exc:
        if type(exc) is not Exception:  # gmsh raises plain Exception; let others through
            raise
        detail = session.last_errors() or str(exc)
        raise GeometryError(
            f"gmsh failed: {detail}; try a larger mesh size h or h_min, fewer sections,"
            " or verbose=True for the full gmsh log."
        ) from exc
    finally:
        if owner:
            gmsh.logger.stop()
            gmsh.finalize()
        else:
            gmsh.model.setCurrent(session.model_name)
            gmsh.model.remove()
            if previous is not None:
                gmsh.model.setCurrent(previous)
            session.restore_options()
