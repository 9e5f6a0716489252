"""Contact: casing profiles, contact points, reach, gap algebra and impulse solvers."""

from importlib import import_module as _import

# imported on first use (PEP 562): `femrub --help` and `femrub scenes` stay fast
_LAZY = {
    "CasingProfile": ".casing",
    "Concentric": ".casing",
    "Lobed": ".casing",
    "TwoLobePiollet": ".casing",
    "casing_profile": ".casing",
}

__all__ = ["CasingProfile", "Concentric", "Lobed", "TwoLobePiollet", "casing_profile"]


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
