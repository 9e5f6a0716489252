"""Contact: casing profiles, contact points, reach, gap algebra and impulse solvers."""

from .casing import CasingProfile, Concentric, Lobed, TwoLobePiollet, casing_profile

__all__ = ["CasingProfile", "Concentric", "Lobed", "TwoLobePiollet", "casing_profile"]
