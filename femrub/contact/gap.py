"""Unilateral contacts in gap form (paper Eq. 8b), independent of the model's coordinates::

    g(t, X)  = g0(t) + Gᵀ X          normal gap at each contact (m), g >= 0 means open
    ġ(t, X)  = ġ0(t) + Gvᵀ X         normal gap velocity (m/s); ġ0 = dg0/dt (moving casing)
    force    = Hm λ + Ht (α λ)       reaction λ >= 0 (N) and frictional heat α λ (W)

The paper's tip node is the case ``G = −e_u(n)``, ``Gv = Hm = −e_v(n)``, ``Ht = e_θ(n)``:
the reaction pushes the tip away from the casing and the heat input ``α λ`` is never negative.

:class:`Contact` holds this algebra once for every stepper and post-processor: its methods
take one state ``X`` (N,) at a time ``t``, or rows of states (m, N) at an array of times (m,).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

__all__ = ["Contact"]


@dataclass
class Contact:
    """Unilateral contacts in gap form (see module docstring).

    Parameters
    ----------
    G, Gv, Hm, Ht : (N, n_c) arrays (dense; n_c is small).
    gap0 : (n_c,) initial gaps (m) or a callable ``t -> (n_c,)`` (rotating casing profile).
    gap_rate : ``dg0/dt``, a callable ``t -> (n_c,)`` (m/s) when ``gap0`` moves; ``None``: 0.
    restitution : Newton restitution coefficient e in [0, 1].
    heat_coefficient : α (m/s) per contact, scalar, array or callable ``t -> (n_c,)``.
    names : labels of the contacts.
    wear : optional :class:`~femrub.contact.abradable.Abradable` coating: its wear depth
        under each contact is added to ``g0(t)`` (the worn surface) and it bounds the
        impulses (``impulse_cap``); steppers update it after every step (:meth:`after_step`).
    casing_heat : optional :class:`~femrub.contact.casing_heat.CasingHeat`: the casing
        wall's thermal expansion under each contact is subtracted from ``g0(t)``.

    Callables are evaluated at one time per call (their contract is a scalar ``t``); the
    products with the states are vectorised over rows.
    """

    G: np.ndarray
    Gv: np.ndarray
    Hm: np.ndarray
    Ht: np.ndarray
    gap0: np.ndarray | Callable
    restitution: float = 0.0
    heat_coefficient: float | np.ndarray | Callable = 0.0
    names: list[str] = field(default_factory=list)
    gap_rate: Callable | None = None
    wear: object = None
    casing_heat: object = None

    def __post_init__(self):
        self.G, self.Gv, self.Hm, self.Ht = (
            np.atleast_2d(np.asarray(a, dtype=float).T).T
            for a in (self.G, self.Gv, self.Hm, self.Ht)
        )
        e = float(self.restitution)
        if not (0.0 <= e <= 1.0):
            raise ValueError(f"restitution must be in [0, 1], got {self.restitution!r}")
        if not callable(self.gap0):
            self.gap0 = np.broadcast_to(np.asarray(self.gap0, dtype=float), (self.n,)).copy()
            if not np.all(np.isfinite(self.gap0)):
                raise ValueError("contact gap must be finite")
        if not callable(self.heat_coefficient):
            a = np.broadcast_to(np.asarray(self.heat_coefficient, dtype=float), (self.n,)).copy()
            if not np.all(np.isfinite(a)) or np.any(a < 0):
                raise ValueError(f"heat coefficient alpha must be finite and >= 0, got {a}")
            self.heat_coefficient = a
        if not self.names:
            self.names = [f"c{i}" for i in range(self.n)]

    @property
    def n(self) -> int:
        return self.G.shape[1]

    # -- contiguous transposes, computed once per contact --------------------------------
    @cached_property
    def GT(self) -> np.ndarray:
        """``Gᵀ`` (n_c, N), C-contiguous: the gap rows."""
        return np.ascontiguousarray(self.G.T)

    @cached_property
    def GvT(self) -> np.ndarray:
        """``Gvᵀ`` (n_c, N), C-contiguous: the gap-velocity rows."""
        return np.ascontiguousarray(self.Gv.T)

    # -- time functions: (n_c,) at a scalar time, (m, n_c) at an array of times (m,) ------
    def gap_at(self, t) -> np.ndarray:
        """``g0(t)``: the gap of the undeformed structure (m), on the worn surface.

        With a wear map, rows at an array of times use the current map (post-processing).
        """
        g0 = self.gap0
        if callable(g0):
            if isinstance(t, np.ndarray) and t.ndim:
                g0 = _over_times(g0, t, self.n)
            else:
                g0 = np.asarray(g0(t), dtype=float)
        rows = isinstance(t, np.ndarray) and t.ndim
        if self.wear is not None:
            g0 = g0 + (
                _over_times(self.wear.depth_at, t, self.n) if rows else self.wear.depth_at(t)
            )
        if self.casing_heat is not None:
            ch = self.casing_heat
            g0 = g0 - (_over_times(ch.closure_at, t, self.n) if rows else ch.closure_at(t))
        return g0

    def impulse_cap(self, t: float, h: float):
        """Upper bound of the impulses over the step ending at ``t`` (``None``: unbounded)."""
        return None if self.wear is None else self.wear.impulse_cap(t, h)

    def after_step(self, t: float, X: np.ndarray, impulse: np.ndarray, h: float) -> None:
        """Remove the coating the blade penetrated where it yielded (impulse at its cap), and
        heat the casing with its share of the step's frictional heat."""
        if impulse.size == 0:
            return
        if self.casing_heat is not None:
            self.casing_heat.update(t, impulse, h)
        if self.wear is None:
            return
        yielded = impulse >= (1.0 - 1e-9) * self.wear.impulse_cap(t, h)
        if np.any(yielded):
            self.wear.update(t, self.gap(t, X), yielded)

    def rate_at(self, t) -> np.ndarray | float:
        """``ġ0(t) = dg0/dt`` (m/s); the scalar 0 for a fixed obstacle."""
        rate, ch = self.gap_rate, self.casing_heat
        rows = isinstance(t, np.ndarray) and t.ndim
        out = 0.0
        if rate is not None:
            out = _over_times(rate, t, self.n) if rows else np.asarray(rate(t), dtype=float)
        if ch is not None:
            out = out - (
                _over_times(ch.closure_rate_at, t, self.n) if rows else ch.closure_rate_at(t)
            )
        return out

    def alpha_at(self, t) -> np.ndarray:
        """Heat coefficient ``α(t)`` (m/s)."""
        a = self.heat_coefficient
        if not callable(a):
            return a
        if isinstance(t, np.ndarray) and t.ndim:
            return _over_times(a, t, self.n)
        return np.asarray(a(t), dtype=float)

    # -- the gap algebra -------------------------------------------------------------------
    def gap(self, t, X: np.ndarray) -> np.ndarray:
        """``g = g0(t) + Gᵀ X`` (m): (n_c,) for X (N,), (m, n_c) for X (m, N) and t (m,)."""
        GT = self.GT
        return self.gap_at(t) + (GT @ X if X.ndim == 1 else X @ GT.T)

    def gap_velocity(self, t, X: np.ndarray) -> np.ndarray:
        """``ġ = ġ0(t) + Gvᵀ X`` (m/s), shaped as :meth:`gap`."""
        return self.rate_at(t) + self.structure_velocity(X)

    def structure_velocity(self, X: np.ndarray) -> np.ndarray:
        """``Gvᵀ X`` (m/s): the gap velocity without the casing's own motion ``ġ0``.

        Its product with the impulse is the work of the contact force on the structure.
        """
        GvT = self.GvT
        return GvT @ X if X.ndim == 1 else X @ GvT.T

    @property
    def has_heat(self) -> bool:
        a = self.heat_coefficient
        return callable(a) or bool(np.any(np.asarray(a) > 0) and np.any(self.Ht))

    def project(self, left: np.ndarray, right: np.ndarray) -> Contact:
        """Contact of the model reduced by ``X = right X̄`` and left projection ``leftᵀ``."""
        return replace(
            self,
            G=right.T @ self.G,
            Gv=right.T @ self.Gv,
            Hm=left.T @ self.Hm,
            Ht=left.T @ self.Ht,
        )


def _over_times(value: Callable, t: np.ndarray, n: int) -> np.ndarray:
    """``value(t_i)`` (n,) stacked over the times ``t`` (m,): an (m, n) array."""
    return np.array([value(ti) for ti in t], dtype=float).reshape(t.size, n)
