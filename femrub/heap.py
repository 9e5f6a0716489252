"""Large arrays mapped on their own, so that freeing one gives its memory back.

glibc's ``malloc`` maps an allocation on its own only above a threshold, and raises that
threshold, up to 32 MB, each time such a block is freed; below it, arrays go to its heap,
whose freed memory stays resident and cannot serve the large arrays mapped later. A 3D
build allocates and frees many arrays of 1–32 MB (blocks of right-hand sides, Lanczos
blocks, projection chunks): on Rotor 37 about 1 GB of freed heap was still resident when
the Craig–Bampton bases (0.6 GB each) were made. :func:`map_large_arrays` fixes the threshold
(``mallopt(M_MMAP_THRESHOLD, ...)``, which also stops the raise); ``femrub``'s command line
calls it first and a sweep's workers start with it. A Python program may call it before a
large build. It does nothing where the C library is not glibc, or when the environment
already sets ``MALLOC_MMAP_THRESHOLD_`` (the user's choice stands).
"""

from __future__ import annotations

import ctypes
import os
import sys

__all__ = ["ENV", "LARGE", "map_large_arrays"]

#: allocations of at least this many bytes are mapped on their own (1 MiB)
LARGE = 1 << 20
#: glibc's environment variable for the same setting (read when a process starts)
ENV = "MALLOC_MMAP_THRESHOLD_"
_M_MMAP_THRESHOLD = -3  # glibc's malloc.h


def map_large_arrays(threshold: int = LARGE) -> bool:
    """Map every allocation of at least ``threshold`` bytes on its own, for the rest of the
    process; ``True`` when the C library took the setting."""
    if not sys.platform.startswith("linux") or ENV in os.environ:
        return False
    try:
        libc = ctypes.CDLL(None)  # the C library the interpreter runs on
        libc.gnu_get_libc_version  # noqa: B018  (glibc only: its mallopt takes the threshold)
    except (OSError, AttributeError):
        return False
    return bool(libc.mallopt(_M_MMAP_THRESHOLD, int(threshold)))
