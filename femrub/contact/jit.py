"""The one compilation switch of the contact kernels.

:func:`njit` compiles a function written in the numba-compatible subset of Python and
numpy (``numba.njit(cache=True)``: the machine code is cached next to the module, so only
the first call on a machine pays the compilation). With ``NUMBA_DISABLE_JIT=1``, or without
numba, the same function runs as plain Python: there is one implementation, and the tests
exercise it both ways.
"""

from __future__ import annotations

try:  # numba is a dependency; the fallback keeps a broken install importable
    import numba
except ImportError:  # pragma: no cover
    numba = None

__all__ = ["njit", "compiled"]


def njit(fn):
    """``fn`` compiled in nopython mode (cached on disk), or ``fn`` itself without numba."""
    if numba is None:  # pragma: no cover
        return fn
    return numba.njit(cache=True, nogil=True)(fn)


def compiled() -> bool:
    """Whether the kernels run as machine code (numba present and JIT enabled)."""
    if numba is None:  # pragma: no cover
        return False
    from numba.core import config

    return not config.DISABLE_JIT
