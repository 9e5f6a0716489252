"""Names of a package imported on first use (PEP 562), so `femrub --help` stays fast."""

from __future__ import annotations

import sys
from importlib import import_module


def lazy_attributes(package: str, table: dict[str, str], names):
    """``(__getattr__, __dir__)`` for ``package``: ``table`` maps a name to its submodule.

    The first access imports the submodule and stores the value in the package, so later
    accesses are plain attribute lookups.
    """

    def __getattr__(name):
        if name not in table:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(table[name], package), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(names))

    return __getattr__, __dir__
