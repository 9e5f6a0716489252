"""One BLAS thread for the small dense products of a run.

A reduced model's per-step products and set-up (a few hundred coordinates) are too small for
BLAS threads to pay: threads only add latency, and OpenBLAS workers woken by a threaded call
spin on the other core for a while after it returns, so their CPU lands in the next phase
(the first steps of a run). :data:`one_blas_thread` is a context in which every BLAS
library of the process (numpy's and scipy's OpenBLAS alike) runs on one thread.

It is shared by every thread of the process: the limits hold while any thread is inside
(the stepping and a background VTK writer may be inside together) and the last one out
restores them, whichever thread that is (threadpoolctl otherwise lets only the first thread
that limited a process-wide pool change it again). The libraries are found on first use (a
few ms) and again after :func:`libraries_loaded` (femrub calls it when it loads MKL for
Pardiso, :func:`femrub.fem.linalg.pardiso_available`). MKL's number of threads, as
threadpoolctl sets and reads it, belongs to the calling thread: inside the context MKL runs
on one thread in the thread that entered it first, not in the others (femrub calls MKL only
through Pardiso, in set-ups, never in the stepping).
"""

from __future__ import annotations

import threading

from threadpoolctl import ThreadpoolController

__all__ = ["SERIAL_SETUP_DOFS", "libraries_loaded", "one_blas_thread"]

#: models of at most this many coordinates are also set up on one BLAS thread (dense
#: reduced models; larger ones, full sparse models, keep the threads for their set-up)
SERIAL_SETUP_DOFS = 1000


class _OneBLASThread:
    """Context: BLAS libraries on one thread while any thread is inside it (the last one
    out restores their limits); re-entrant."""

    def __init__(self):
        self._lock, self._inside, self._limiter = threading.Lock(), 0, None
        self._controller: ThreadpoolController | None = None
        self._stale = False

    def forget(self) -> None:
        """Find the libraries again at the next outermost entry (limits in force stay)."""
        self._stale = True

    def __enter__(self):
        with self._lock:
            if not self._inside:
                if self._controller is None or self._stale:
                    self._controller, self._stale = ThreadpoolController(), False
                _take_control(self._controller)
                self._limiter = self._controller.limit(limits=1, user_api="blas")
            self._inside += 1
        return self

    def __exit__(self, *exc) -> None:
        with self._lock:
            self._inside -= 1
            if not self._inside:
                _take_control(self._controller)
                self._limiter.restore_original_limits()
                self._limiter = None


def _take_control(controller: ThreadpoolController) -> None:
    """Let the calling thread set the process-wide pools (our lock serialises the calls)."""
    for lib in controller.lib_controllers:
        clear = getattr(type(lib), "clear_controlling_thread", None)
        if clear is not None:
            clear(force=True)


one_blas_thread = _OneBLASThread()


def libraries_loaded() -> None:
    """Tell :data:`one_blas_thread` that the process loaded a BLAS library since its last
    entry (MKL with Pardiso): the next outermost entry limits it too."""
    one_blas_thread.forget()
