"""SIGTERM like Ctrl-C, and writes that a second signal cannot cut in half.

:func:`interruptible` turns SIGTERM (``kill``, a batch system's time limit) into the
``KeyboardInterrupt`` that Ctrl-C raises, so a run stops the same way whichever signal ends
it: the recorder keeps every checked step and the status becomes ``interrupted``.
:func:`deferred` holds SIGINT and SIGTERM back while the results are written (a double
Ctrl-C would otherwise abort the writing of the history) and raises ``KeyboardInterrupt``
once the files are complete. Both do nothing outside the main thread (signal handlers can
only be installed there), e.g. in a sweep's worker threads.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["deferred", "interruptible"]


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


_state = {"depth": 0, "fired": False}


def _raise_interrupt(signum, frame):
    if _state["fired"]:  # a second signal while the first one unwinds: already stopping
        return
    _state["fired"] = True
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
    previous = {s: signal.signal(s, _raise_interrupt) for s in (signal.SIGINT, signal.SIGTERM)}
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        for s, handler in previous.items():
            signal.signal(s, handler)
        if _state["depth"] == 0:
            _state["fired"] = False


@contextmanager
def deferred():
    """Hold SIGINT/SIGTERM back during the block; raise ``KeyboardInterrupt`` after it."""
    if not _main_thread():
        yield
        return
    caught = []

    def hold(signum, frame):
        caught.append(signum)

    previous = {s: signal.signal(s, hold) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    if caught:
        raise KeyboardInterrupt("signal received while writing results")
