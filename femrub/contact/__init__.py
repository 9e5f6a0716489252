"""Contact: casing profiles, contact points, reach, gap algebra and impulse solvers."""

from .._lazy import lazy_attributes

# imported on first use (PEP 562): `femrub --help` and `femrub scenes` stay fast
_LAZY = {
    "CasingProfile": ".casing",
    "Concentric": ".casing",
    "Lobed": ".casing",
    "TwoLobePiollet": ".casing",
    "casing_profile": ".casing",
}

__all__ = ["CasingProfile", "Concentric", "Lobed", "TwoLobePiollet", "casing_profile"]


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, __all__)
