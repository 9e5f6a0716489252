"""Rigid casing profiles: the radial gap seen by a blade node as the rotor turns.

A contact node at angular position ``φ`` (rad, around the machine axis) of a blade turning
at ``Ω`` (rad/s) in the direction ``σ`` (+1 counterclockwise about the axis, −1 clockwise;
``loads.rotation_direction``) sees the casing at angle ``ψ = σ Ω t + φ``; its undeformed
radial gap is the profile ``g(ψ)`` (m). The deformed gap is ``g(ψ) − n · u`` with ``n`` the
outward radial direction at the node (see :mod:`femrub.model.rub`). In the blade's frame the
casing surface slides past the node at ``−σ Ω r`` along the circumferential tangent
``e_φ = a × n`` (:func:`sliding_velocity`): the phase and the sliding follow the rotation
together. ``contact.slip_direction = "reversed"`` turns the sliding alone (``+σ Ω r``), a
verification device for codes that prescribe the sliding velocity independently of the
lobe phase; it is not a physical set-up.

* :class:`Concentric`: ``g(ψ) = c``.
* :class:`Lobed`: ``g(ψ) = c − δ cos(k (ψ − ψ0))``, an ovalised casing with ``k`` lobes;
  with ``δ > c`` the casing intrudes at ``k`` places per revolution.
* :class:`TwoLobePiollet`: the two-lobe profile of Piollet, Nyssen & Batailly, J. Sound Vib.
  460 (2019) 114878, Eqs. 3–4: ``g(ψ) = g_m (1 − 2 exp(−((mod(ψ, π)/π − 0.5)/w)²))``,
  ``g_m = 0.356 mm``, ``w = 0.15``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..fem.material import check_finite_positive

__all__ = [
    "CasingProfile",
    "Concentric",
    "Lobed",
    "TwoLobePiollet",
    "casing_profile",
    "lobe_count",
    "lobe_passing_frequency",
    "PROFILES",
    "SLIP_DIRECTIONS",
    "sliding_velocity",
    "swept_gap",
    "SweptGap",
    "SweptGapRate",
]


class CasingProfile:
    """Base class: ``gap(angle)`` (m) of the undeformed blade at casing angle ``angle`` (rad)."""

    kind = "profile"
    #: gap minima a contact passes per revolution (0: a gap that does not change)
    lobes = 0

    def gap(self, angle):
        raise NotImplementedError

    def slope(self, angle):
        """``dg/dψ`` (m/rad); the gap rate of a node is ``Ω slope(Ω t + φ)``."""
        raise NotImplementedError

    def min_gap(self) -> float:
        """Smallest gap over a revolution (m); negative when the casing intrudes."""
        return float(np.min(self.gap(np.linspace(0.0, 2.0 * math.pi, 4001))))

    def as_dict(self) -> dict:
        return {"kind": self.kind, **asdict(self)}


@dataclass(frozen=True)
class Concentric(CasingProfile):
    """Round casing, constant clearance ``clearance`` (m)."""

    clearance: float
    kind = "concentric"

    def __post_init__(self):
        if not math.isfinite(self.clearance):
            raise ValueError(f"casing clearance must be finite, got {self.clearance!r}")

    def gap(self, angle):
        return np.full_like(np.asarray(angle, dtype=float), self.clearance)

    def slope(self, angle):
        return np.zeros_like(np.asarray(angle, dtype=float))


@dataclass(frozen=True)
class Lobed(CasingProfile):
    """Ovalised casing: ``clearance − depth cos(lobes (ψ − phase))`` (m)."""

    clearance: float
    depth: float
    lobes: int = 2
    phase: float = 0.0
    kind = "lobed"

    def __post_init__(self):
        check_finite_positive("casing depth", self.depth, allow_zero=True)
        if not (isinstance(self.lobes, int) and self.lobes >= 1):
            raise ValueError(f"casing lobes must be a positive integer, got {self.lobes!r}")
        if not math.isfinite(self.clearance):
            raise ValueError(f"casing clearance must be finite, got {self.clearance!r}")

    def gap(self, angle):
        return self.clearance - self.depth * np.cos(self.lobes * (np.asarray(angle) - self.phase))

    def slope(self, angle):
        k = self.lobes
        return self.depth * k * np.sin(k * (np.asarray(angle) - self.phase))


@dataclass(frozen=True)
class TwoLobePiollet(CasingProfile):
    """Two-lobe casing of Piollet et al. (2019), Eqs. 3–4 (gap in m)."""

    mean_gap: float = 0.356e-3
    width: float = 0.15
    kind = "two-lobe"
    lobes = 2

    def __post_init__(self):
        check_finite_positive("casing mean_gap", self.mean_gap)
        check_finite_positive("casing width", self.width)

    def gap(self, angle):
        s = np.mod(np.asarray(angle, dtype=float), math.pi) / math.pi - 0.5
        return self.mean_gap * (1.0 - 2.0 * np.exp(-((s / self.width) ** 2)))

    def slope(self, angle):
        s = np.mod(np.asarray(angle, dtype=float), math.pi) / math.pi - 0.5
        w2 = self.width**2
        return self.mean_gap * 4.0 * s / (w2 * math.pi) * np.exp(-(s**2) / w2)


PROFILES = {"concentric": Concentric, "lobed": Lobed, "two-lobe": TwoLobePiollet}


def casing_profile(kind: str, **params) -> CasingProfile:
    """Profile by name (``"concentric"``, ``"lobed"``, ``"two-lobe"``) and parameters."""
    if kind not in PROFILES:
        raise ValueError(f"unknown casing profile {kind!r}; use one of {', '.join(PROFILES)}")
    try:
        return PROFILES[kind](**params)
    except TypeError as exc:
        raise ValueError(f"casing profile {kind!r}: {exc}") from None


def lobe_count(casing) -> int:
    """Lobes of ``casing`` (a :class:`CasingProfile` or a scene's ``contact.casing`` table):
    the gap minima a contact passes per revolution, 0 for a round casing."""
    if isinstance(casing, CasingProfile):
        return int(casing.lobes)
    return int(casing.get("lobes", PROFILES[casing["kind"]].lobes))


def lobe_passing_frequency(casing, rotation_speed: float) -> float:
    """``lobes × |Ω|`` (rad/s): how often a casing lobe passes a contact (0 for a round
    casing or at rest); the one place this frequency is derived (:func:`lobe_count`)."""
    return float(lobe_count(casing)) * abs(float(rotation_speed))


#: the casing's sliding velocity relative to the rotation: ``"rotation"`` (``−σ Ω r``, the
#: physical one) or ``"reversed"`` (``+σ Ω r``, a verification device; module docstring)
SLIP_DIRECTIONS = {"rotation": 1.0, "reversed": -1.0}


def sliding_velocity(radii, rotation_speed: float, direction: float = 1.0, slip: float = 1.0):
    """Velocity (m/s, (n_c, 2): axial, circumferential) of the casing surface past contacts
    at ``radii`` (m) in the blade's frame: ``(0, −slip σ Ω r_i)``, ``σ = direction``
    (module docstring)."""
    radii = np.asarray(radii, dtype=float)
    vc = np.zeros((radii.size, 2))
    vc[:, 1] = -float(slip) * float(direction) * float(rotation_speed) * radii
    return vc


def swept_gap(
    profile: CasingProfile, angles, rotation_speed: float, offset=0.0, direction: float = 1.0
):
    """Gap ``g_i(t) = g(σ Ω t + φ_i) + offset_i`` of contacts at ``angles`` and its rate
    (``σ = direction``: +1 counterclockwise, −1 clockwise; module docstring).

    Returns ``(gap, gap_rate)``: constant arrays and ``None`` when the gap does not move
    (concentric casing or ``Ω = 0``), else callables ``t -> (n_c,)`` (m and m/s).
    """
    angles = np.asarray(angles, dtype=float)
    offset = np.broadcast_to(np.asarray(offset, dtype=float), angles.shape).copy()
    omega = float(direction) * float(rotation_speed)
    if isinstance(profile, Concentric) or omega == 0.0:
        return np.asarray(profile.gap(angles), dtype=float) + offset, None
    return SweptGap(profile, omega, angles, offset), SweptGapRate(profile, omega, angles)


class SweptGap:
    """``t -> g(ω t + φ_i) + offset_i`` (m, (n_c,); ``ω = σ Ω`` signed); :meth:`over_times`:
    rows at an array of times (m,) in one call, (m, n_c). A small class rather than a
    closure, so that a contact holding it can be pickled (a model sent to a worker or
    stored)."""

    def __init__(self, profile: CasingProfile, omega: float, angles, offset):
        self.profile, self.omega, self.angles, self.offset = profile, omega, angles, offset

    def __call__(self, t):
        return self.profile.gap(self.omega * t + self.angles) + self.offset

    def over_times(self, t):
        return self.profile.gap(self.omega * t[:, None] + self.angles) + self.offset


class SweptGapRate:
    """``t -> Ω g'(Ω t + φ_i)`` (m/s), the rate of :class:`SweptGap`, same calls."""

    def __init__(self, profile: CasingProfile, omega: float, angles):
        self.profile, self.omega, self.angles = profile, omega, angles

    def __call__(self, t):
        return self.omega * self.profile.slope(self.omega * t + self.angles)

    def over_times(self, t):
        return self.omega * self.profile.slope(self.omega * t[:, None] + self.angles)


def _ramp(t, duration: float):
    """``s(t) = (1 − cos(π t / T)) / 2`` up to ``T = duration``, 1 after, and ``ds/dt``."""
    t = np.asarray(t, dtype=float)
    x = np.clip(t / duration, 0.0, 1.0)
    on = (t > 0.0) & (t < duration)
    return 0.5 * (1.0 - np.cos(np.pi * x)), np.where(
        on, 0.5 * np.pi / duration * np.sin(np.pi * x), 0.0
    )


class RampedSweptGap:
    """The swept gap of a profile whose departure from its clearance grows from zero:
    ``g_i(t) = c + offset_i + s(t) (g(ω t + φ_i) − c)`` with the smooth ramp ``s`` of
    duration ``ramp`` (s) (a casing distorted progressively, so that no contact starts
    inside it when many blades sit around it); :meth:`rate` is its time derivative."""

    def __init__(self, profile: CasingProfile, omega: float, angles, offset, ramp: float):
        self.profile, self.omega, self.angles, self.offset = profile, omega, angles, offset
        self.ramp = float(ramp)
        self.clearance = float(profile.clearance)

    def _parts(self, t):
        psi = self.omega * t + self.angles
        s, ds = _ramp(t, self.ramp)
        return psi, s, ds

    def __call__(self, t):
        psi, s, _ = self._parts(t)
        return self.clearance + self.offset + s * (self.profile.gap(psi) - self.clearance)

    def over_times(self, t):
        return self(np.asarray(t, dtype=float)[:, None])


class RampedSweptGapRate:
    """``dg_i/dt`` of :class:`RampedSweptGap` (m/s), same calls."""

    def __init__(self, gap: RampedSweptGap):
        self.gap = gap

    def __call__(self, t):
        g = self.gap
        psi, s, ds = g._parts(t)
        return ds * (g.profile.gap(psi) - g.clearance) + s * g.omega * g.profile.slope(psi)

    def over_times(self, t):
        return self(np.asarray(t, dtype=float)[:, None])
