"""Which contact points the casing can reach, decided before the model exists.

A contact point whose smallest gap over a revolution stays above the reach never touches
the casing: it is dropped (with its dofs, it would only make the model and its reduction
larger). ``contact.reach = "auto"`` takes ``2 × deflection + intrusion + margin``, with
``deflection`` the largest normal displacement of a contact point under the tip force
amplitude (static and at the forcing frequency) and ``intrusion`` the deepest casing
intrusion. With ``gap_reference = "outermost"`` the casing is a cylinder around the
outermost point: every other point sees the extra clearance ``r_max − r_i``.

A spinning blade grows radially by ``g_i`` at contact ``i`` (centrifugal prestress). With
``clearance = "running"`` (default) the casing clearance is measured from the tip at
speed, so the radii above are ``r_i + g_i`` and the growth closes nothing; with
``"cold"`` it is measured at rest and the growth closes the gap: ``offset_i −= g_i``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..fem.linalg import sparse_lu

__all__ = ["Reach", "contact_reach", "normal_deflection"]


@dataclass(frozen=True)
class Reach:
    """Reach of a casing over contact points (lengths in m).

    Attributes: ``min_gap`` (smallest gap of each point over a revolution), ``offset``
    (clearance added to each point), ``reach``, ``deflection``, ``intrusion`` and the
    boolean ``keep``.
    """

    min_gap: np.ndarray
    offset: np.ndarray
    reach: float
    deflection: float
    intrusion: float
    keep: np.ndarray


def normal_deflection(mats, normal_rows, force, omega: float | None = None) -> float:
    """Largest ``|n_i · u|`` under the load vector ``force`` (static, and harmonic at ``ω``).

    ``inf`` when ``K − ω² M`` is singular (a free structure, or exact resonance).
    """
    if force is None:
        return 0.0
    out = 0.0
    for w in [0.0] + ([omega] if omega else []):
        try:
            u = sparse_lu(mats.K - w * w * mats.M, symmetric=True).solve(force)
        except ValueError:
            return math.inf
        out = max(out, float(np.max(np.abs(normal_rows @ u))))
    return out


def contact_reach(
    points,
    casing,
    *,
    rotation_speed: float,
    gap_reference: str = "per-node",
    reach="auto",
    margin: float = 0.0,
    deflection: float = 0.0,
    growth=0.0,
    clearance: str = "running",
) -> Reach:
    """The :class:`Reach` of ``casing`` over ``points`` (module docstring).

    ``reach`` is a length (m), ``"auto"`` or ``"all"``; ``growth`` the radial tip growth
    at speed of each point (m) and ``clearance`` ``"running"`` or ``"cold"``.
    """
    if clearance not in ("running", "cold"):
        raise ValueError(f"clearance must be 'running' or 'cold', got {clearance!r}")
    n = points.n
    growth = np.broadcast_to(np.asarray(growth, dtype=float), (n,))
    running = clearance == "running"
    radii = points.radii + growth if running else points.radii
    offset = radii.max() - radii if gap_reference == "outermost" and n else np.zeros(n)
    if not running:
        offset = offset - growth
    if rotation_speed > 0.0:
        min_gap = casing.min_gap() + offset
    else:
        min_gap = np.asarray(casing.gap(points.angles), dtype=float) + offset
    intrusion = max(0.0, -float(min_gap.min())) if n else 0.0
    if reach == "all":
        reach = math.inf
    elif reach == "auto":
        reach = 2.0 * deflection + intrusion + margin
    return Reach(min_gap, offset, float(reach), deflection, intrusion, min_gap <= reach)
