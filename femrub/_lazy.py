"""Names of a package imported on first use (PEP 562), so `femrub --help` stays fast."""

from __future__ import annotations

import sys
from importlib import import_module
from types import ModuleType


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

    _keep_names_over_submodules(package, table)
    return __getattr__, __dir__


class _LazyPackage(ModuleType):
    """A package whose lazy names win over its submodules of the same name.

    Importing a submodule binds it on its package under its own name
    (``import femrub.geometry.naca_blade`` sets ``femrub.geometry.naca_blade`` to the
    module), which would hide the function of that name; the package keeps the function.
    The submodule's other names stay importable (``from femrub.geometry.naca_blade import
    naca_sections``).
    """

    _lazy_table: dict[str, str] = {}

    def __setattr__(self, name, value):
        table = self.__dict__.get("_lazy_table", {})
        if isinstance(value, ModuleType) and value.__name__ == f"{self.__name__}.{name}":
            if name in table and table[name] == f".{name}":
                value = getattr(value, name)
        super().__setattr__(name, value)


def _keep_names_over_submodules(package: str, table: dict[str, str]) -> None:
    module = sys.modules[package]
    module.__class__ = _LazyPackage
    module.__dict__["_lazy_table"] = table
