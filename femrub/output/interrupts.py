"""SIGTERM like Ctrl-C, and writes that a second signal cannot cut in half.

:func:`interruptible` turns SIGTERM (``kill``, a batch system's time limit) and SIGHUP (a
closed terminal or SSH connection) into the ``KeyboardInterrupt`` that Ctrl-C raises, so a run
stops the same way whichever signal ends it: the recorder keeps every checked step and the
status becomes ``interrupted`` (exit status 129 after SIGHUP, 130 otherwise:
:func:`exit_status`).
:func:`deferred` holds these signals back while the results are written (a double
Ctrl-C would otherwise abort the writing of the history) and raises ``KeyboardInterrupt``
once the files are complete. Both do nothing outside the main thread (signal handlers can
only be installed there), e.g. in a sweep's worker threads.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["SIGNALS", "deferred", "exit_status", "interruptible"]

#: the signals that stop a run: Ctrl-C, ``kill`` (a batch system's limit), a closed terminal
SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


_state = {"depth": 0, "fired": False, "signum": None}


def _raise_interrupt(signum, frame):
    if _state["fired"]:  # a second signal while the first one unwinds: already stopping
        return
    _state["fired"] = True
    _state["signum"] = signum
    raise KeyboardInterrupt(f"signal {signal.Signals(signum).name}")


@contextmanager
def interruptible():
    """Within the block, SIGINT and SIGTERM raise ``KeyboardInterrupt``, once.

    Later signals are held while the first one unwinds (the recorder keeps its rows, the
    run folder writes its summary), so a double Ctrl-C or SIGTERM followed by Ctrl-C cannot
    cut that in half; blocks nest and share this state until the outermost one ends.
    """
    if not _main_thread():
        yield
        return
    previous = {s: signal.signal(s, _raise_interrupt) for s in SIGNALS}
    if _state["depth"] == 0:
        _state["signum"] = None
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        for s, handler in previous.items():
            signal.signal(s, handler)
        if _state["depth"] == 0:
            _state["fired"] = False


def exit_status() -> int:
    """The exit status of a command a signal stopped: 129 after SIGHUP, else 130."""
    hup = getattr(signal, "SIGHUP", None)
    return 129 if hup is not None and _state["signum"] == hup else 130


@contextmanager
def deferred(reraise: bool = True):
    """Hold :data:`SIGNALS` back during the block; raise ``KeyboardInterrupt`` after it
    (``reraise=False``: not raised; the block's value, the list of signals held, says)."""
    caught: list = []
    if not _main_thread():
        yield caught
        return

    def hold(signum, frame):
        caught.append(signum)
        _state["signum"] = signum

    previous = {s: signal.signal(s, hold) for s in SIGNALS}
    try:
        yield caught
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    if caught and reraise:
        raise KeyboardInterrupt("signal received while writing results")
