"""The one compilation switch of the contact kernels.

:func:`njit` compiles a function written in the numba-compatible subset of Python and
numpy (``numba.njit(cache=True)``: the machine code is cached next to the module, so only
the first call on a machine pays the compilation). With ``NUMBA_DISABLE_JIT=1``, or without
numba, the same function runs as plain Python: there is one implementation, and the tests
exercise it both ways.

numba stamps a cached function with its own source file only, so a kernel cached in one
file would keep a stale copy of a callee changed in another. The kernel files of
:data:`KERNEL_FILES` are therefore stamped together (a change to any of them recompiles
all of their kernels), through a cache locator registered with numba below.

The first run on a machine compiles the kernels it needs (a family of
:data:`femrub.contact.activation.KERNEL_KINDS`, several seconds of one core each). A build
starts that compilation in a child process at its beginning when numba's cache of those
kernels is cold (:func:`compile_in_background`), so it overlaps the assembly of the model;
the first kernel call waits for the child (:func:`wait_background`) and loads the machine
code it cached.
"""

from __future__ import annotations

try:  # numba is a dependency; the fallback keeps a broken install importable
    import numba
except ImportError:  # pragma: no cover
    numba = None

import hashlib
import os
import subprocess
import sys

__all__ = [
    "njit",
    "compiled",
    "cold_kinds",
    "compile_in_background",
    "wait_background",
    "KERNEL_FILES",
]

#: the child process compiling the kernels (:func:`compile_in_background`), once per process
_CHILD: dict = {}
#: longest wait (s) for that child before the kernels are compiled here instead
WAIT_SECONDS = 300.0

_HERE = os.path.dirname(os.path.abspath(__file__))
#: the source files of compiled functions that call each other (one cache stamp)
KERNEL_FILES = tuple(
    os.path.join(_HERE, f) for f in ("coulomb.py", "theta_block.py", "wear_map.py", "rub_block.py")
)


def _stamp() -> bytes:
    h = hashlib.sha256()
    for path in KERNEL_FILES:
        with open(path, "rb") as f:
            h.update(f.read())
    return h.digest()


def _register_locator() -> None:
    """Put a locator stamping :data:`KERNEL_FILES` together first in numba's list (in
    ``__pycache__`` next to them, or under ``NUMBA_CACHE_DIR`` when set, as numba's own
    locators)."""
    from numba.core import caching, config

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    base = getattr(caching, "InTreeCacheLocator", None) or getattr(
        caching, "_InTreeCacheLocator", None
    )
    if impl is None or base is None:  # pragma: no cover - another numba layout
        return

    class KernelFilesLocator(base):
        def __init__(self, py_func, py_file):
            super().__init__(py_func, py_file)
            if config.CACHE_DIR:  # NUMBA_CACHE_DIR, as numba's own first locator
                sub = self.get_suitable_cache_subpath(py_file)
                self._cache_path = os.path.join(config.CACHE_DIR, sub)

        def get_source_stamp(self):
            return _stamp()

        @classmethod
        def from_function(cls, py_func, py_file):
            if os.path.abspath(py_file) not in KERNEL_FILES:
                return None
            return super().from_function(py_func, py_file)

    if not any(c.__name__ == "KernelFilesLocator" for c in impl._locator_classes):
        impl._locator_classes.insert(0, KernelFilesLocator)


if numba is not None:
    _register_locator()


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


def _cold(dispatcher) -> bool:
    """Whether numba's on-disk cache holds no machine code of ``dispatcher`` for the
    current kernel files (``False`` when numba's cache layout is not the one known)."""
    try:
        return not dispatcher._cache._cache_file._load_index()
    except Exception:  # pragma: no cover - another numba layout
        return False


def cold_kinds(kinds) -> tuple[str, ...]:
    """The kinds of ``kinds`` (``"one"``, ``"friction"``, ``"rub"``) whose kernels numba's
    on-disk cache does not hold yet (none without compilation)."""
    if not compiled():
        return ()
    from .rub_block import rub_block
    from .theta_block import friction_block, one_contact_block

    kernels = {"one": one_contact_block, "friction": friction_block, "rub": rub_block}
    return tuple(k for k in kinds if k in kernels and _cold(kernels[k]))


def compile_in_background(kinds=("one", "friction", "rub")) -> bool:
    """Compile the contact kernels of ``kinds`` in a child process if their on-disk cache is
    cold.

    The child runs :func:`femrub.contact.activation.compile_kernels` of ``kinds`` and writes
    numba's cache; this process goes on (the build's assembly) and :func:`wait_background`
    joins it before the first kernel call. At most one child per process; nothing without
    compilation, without kinds or with a warm cache. Returns whether a child was started.
    """
    if _CHILD or not compiled() or not kinds:
        return False
    _CHILD["started"] = True
    kinds = cold_kinds(kinds)
    if not kinds:
        return False
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join(filter(None, (root, os.environ.get("PYTHONPATH"))))
    )
    code = f"from femrub.contact.activation import compile_kernels; compile_kernels({kinds!r})"
    try:
        _CHILD["process"] = subprocess.Popen(
            [sys.executable, "-c", code],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError:  # pragma: no cover - no process to spare: compiled on first use
        return False
    return True


def wait_background() -> None:
    """Wait for the child of :func:`compile_in_background` (if any, at most
    :data:`WAIT_SECONDS`); the kernels then load from numba's cache."""
    proc = _CHILD.pop("process", None)
    if proc is None:
        return
    try:
        proc.wait(timeout=WAIT_SECONDS)
    except subprocess.TimeoutExpired:  # pragma: no cover - compiled here instead
        proc.kill()
