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


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt(f"signal {signal.Signals(signum).name}")


@contextmanager
def interruptible():
    """Within the block, SIGTERM raises ``KeyboardInterrupt`` like SIGINT does."""
    if not _main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


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
