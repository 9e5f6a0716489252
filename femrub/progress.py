"""Progress messages of the long stages (factorisations, eigen-solves, reduction phases).

The pipeline hands its ``log`` callable down once, with :func:`reporting`; the numerical
routines deep below (``fem.linalg``, ``fem.eigen``, the reductor) then say what they do
through :func:`note` and :func:`phase` without a ``log`` argument in every signature.
Outside :func:`reporting` they are silent. The callable is held in a context variable, so
threads and sweep workers do not mix their messages.
"""

from __future__ import annotations

import contextvars
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

__all__ = ["note", "phase", "reporting"]

_LOG: contextvars.ContextVar[Callable | None] = contextvars.ContextVar("femrub_log", default=None)


@contextmanager
def reporting(log: Callable | None) -> Iterator[None]:
    """Send the messages of the code run inside the block to ``log`` (``None``: silent)."""
    token = _LOG.set(log)
    try:
        yield
    finally:
        _LOG.reset(token)


def note(text: str) -> None:
    """One progress message (dropped outside :func:`reporting`)."""
    log = _LOG.get()
    if log is not None:
        log(text)


@contextmanager
def phase(what: str, start: bool = True) -> Iterator[dict]:
    """``what ...`` when the block starts (``start``), ``what done in X s`` when it ends.

    The block may add details to the closing message: ``with phase("x") as p: p["detail"]
    = "..."``.
    """
    if start:
        note(f"{what} ...")
    t0, c0 = time.perf_counter(), time.process_time()
    out: dict = {}
    yield out
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    detail = f": {out['detail']}" if out.get("detail") else ""
    note(f"{what} done in {wall:.2f} s (CPU {cpu:.2f} s){detail}")
