"""Unilateral contacts in gap form (paper Eq. 8b), independent of the model's coordinates::

    g(t, X)  = g0(t) + Gᵀ X          normal gap at each contact (m), g >= 0 means open
    ġ(t, X)  = ġ0(t) + Gvᵀ X         normal gap velocity (m/s); ġ0 = dg0/dt (moving casing)
    force    = Hm λ + Ht (α λ)       reaction λ >= 0 (N) and frictional heat α λ (W)

With Coulomb friction each contact also has two tangents (casing frame: axial and
circumferential) and a tangential reaction ``λ_t`` (N)::

    w_t(X)   = Gvtᵀ X − v_c           slip velocity: structure minus casing surface (m/s)
    force   += Hmt λ_t                |λ_t| <= μ λ, λ_t = −μ λ w_t/|w_t| when sliding
    heat     = η (−λ_t · w_t)          heat law "power": the blade's share η of the friction power

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
    Gvt, Hmt : (N, 2 n_c) tangential velocity rows and force columns (contact-major:
        columns ``2 i, 2 i + 1`` are the two tangents of contact ``i``); ``None``: no
        tangential force.
    friction : Coulomb coefficient μ per contact (scalar or (n_c,)).
    casing_velocity : (n_c, 2) velocity of the casing surface along the tangents (m/s).
    frames : (n_c, 3, dim) unit normal and tangents of each contact in global axes (output).
    heat_law : ``"alpha"`` (heat ``α λ``) or ``"power"`` (heat ``η`` × friction power).
    heat_partition : η, the blade's share of the friction power (``"power"`` law).
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
    Gvt: np.ndarray | None = None
    Hmt: np.ndarray | None = None
    friction: float | np.ndarray = 0.0
    casing_velocity: np.ndarray | None = None
    frames: np.ndarray | None = None
    heat_law: str = "alpha"
    heat_partition: float | np.ndarray = 1.0
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
        mu = np.broadcast_to(np.asarray(self.friction, dtype=float), (self.n,)).copy()
        if not np.all(np.isfinite(mu)) or np.any(mu < 0):
            raise ValueError(f"friction coefficient must be finite and >= 0, got {mu}")
        self.friction = mu
        if self.heat_law not in ("alpha", "power"):
            raise ValueError(f"heat_law must be 'alpha' or 'power', got {self.heat_law!r}")
        eta = np.broadcast_to(np.asarray(self.heat_partition, dtype=float), (self.n,)).copy()
        if np.any(~((eta >= 0) & (eta <= 1))):
            raise ValueError(f"heat_partition must be in [0, 1], got {eta}")
        self.heat_partition = eta
        if self.Gvt is not None:
            self.Gvt = np.asarray(self.Gvt, dtype=float).reshape(self.G.shape[0], 2 * self.n)
            self.Hmt = (
                self.Gvt.copy()
                if self.Hmt is None
                else np.asarray(self.Hmt, dtype=float).reshape(self.Gvt.shape)
            )
            vc = np.zeros((self.n, 2)) if self.casing_velocity is None else self.casing_velocity
            self.casing_velocity = np.broadcast_to(np.asarray(vc, dtype=float), (self.n, 2)).copy()

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
        if self.wear is not None:  # rows: one broadcast interpolation (m, n_c)
            g0 = g0 + (self.wear.depth_at(t[:, None]) if rows else self.wear.depth_at(t))
        if self.casing_heat is not None:
            ch = self.casing_heat
            g0 = g0 - (_over_times(ch.closure_at, t, self.n) if rows else ch.closure_at(t))
        return g0

    def impulse_cap(self, t: float, h: float, gap_k=None, gap_p=None):
        """Upper bound of the impulses over the step ending at ``t`` (``None``: unbounded);
        ``gap_k``, ``gap_p``: the gaps at ``t_k`` and of the free step at ``t``
        (:meth:`Abradable.impulse_cap <femrub.contact.abradable.Abradable.impulse_cap>`)."""
        return None if self.wear is None else self.wear.impulse_cap(t, h, gap_k, gap_p)

    def after_step(
        self,
        t: float,
        X: np.ndarray,
        impulse: np.ndarray,
        h: float,
        friction_impulse: np.ndarray | None = None,
    ) -> None:
        """Remove the coating the blade penetrated where it yielded (impulse at its cap), and
        heat the casing with its share of the step's frictional heat.

        ``friction_impulse``: the step's tangential impulses (n_c, 2) (N s) for the
        ``"power"`` heat law: the casing takes ``(1 − η) (−P_t · w_t)`` with the slip
        velocity ``w_t`` at the end of the step; with the ``"alpha"`` law it takes
        ``(1 − η)/η α P`` (:mod:`femrub.contact.casing_heat`).
        """
        if impulse.size == 0:
            return
        if self.casing_heat is not None:
            ch = self.casing_heat
            if self.heat_law == "power":
                Pt = friction_impulse
                heat = np.zeros(self.n)
                if Pt is not None:
                    w = self.slip_velocity(X)
                    heat = (1.0 - self.heat_partition) * np.maximum(
                        -np.einsum("ij,ij->i", Pt, w), 0.0
                    )
            else:
                heat = ch.power_per_impulse * impulse
            ch.update(t, heat, h)
        if self.wear is None:
            return
        yielded = impulse >= (1.0 - 1e-9) * self.wear.bound(t, h)
        self.wear.update(t, self.gap(t, X), yielded)  # every step: the next sweep starts here

    def rate_at(self, t) -> np.ndarray | float:
        """``ġ0(t) = dg0/dt`` (m/s); the scalar 0 for a fixed obstacle. With a coating it
        includes the worn surface's rate over a step (:meth:`Abradable.rate_at`), with casing
        heat the wall's expansion rate."""
        rate, ch, wear = self.gap_rate, self.casing_heat, self.wear
        rows = isinstance(t, np.ndarray) and t.ndim
        out = 0.0
        if rate is not None:
            out = _over_times(rate, t, self.n) if rows else np.asarray(rate(t), dtype=float)
        if wear is not None:
            out = out + (wear.rate_at(t[:, None]) if rows else wear.rate_at(t))
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
        if self.heat_law == "power":
            return self.has_friction and bool(np.any(self.heat_partition > 0) and np.any(self.Ht))
        return callable(a) or bool(np.any(np.asarray(a) > 0) and np.any(self.Ht))

    @property
    def carried_state(self) -> list:
        """The history a run carries outside ``X`` (an abradable coating's wear map, the
        casing's heat); a stepper runs its own copy (:meth:`with_fresh_history`)."""
        return [s for s in (self.wear, self.casing_heat) if s is not None]

    def history_snapshot(self) -> tuple:
        """The state of the history this contact carries now (:attr:`carried_state`), copied:
        what :meth:`restore_history` takes back."""
        return tuple(s.snapshot() for s in self.carried_state)

    def restore_history(self, snapshot: tuple) -> None:
        """Put the history this contact carries back to :meth:`history_snapshot`'s state."""
        for s, state in zip(self.carried_state, snapshot, strict=True):
            s.restore(state)

    def with_fresh_history(self, h: float) -> Contact:
        """This contact with a history of its own, started afresh (an unworn coating, a cold
        casing) for a run of step ``h`` (s): the run's state. The contact it is copied from
        keeps its own history untouched (``self`` when there is none)."""
        if not self.carried_state:
            return self
        wear = None if self.wear is None else self.wear.fresh(h)
        heat = None if self.casing_heat is None else self.casing_heat.fresh()
        return replace(self, wear=wear, casing_heat=heat)

    # -- friction --------------------------------------------------------------------------
    @property
    def has_friction(self) -> bool:
        """Tangential forces exist (tangent rows and some μ > 0)."""
        return self.Gvt is not None and bool(np.any(self.friction > 0.0))

    @cached_property
    def GvtT(self) -> np.ndarray:
        """``Gvtᵀ`` (2 n_c, N), C-contiguous: the tangential velocity rows."""
        return np.ascontiguousarray(self.Gvt.T)

    def local(self, normal: np.ndarray, tangential: np.ndarray) -> np.ndarray:
        """Interleave (N, n_c) normal and (N, 2 n_c) tangential columns contact-major:
        (N, 3 n_c) with columns ``3 i + (n, t1, t2)`` (the layout of
        :func:`~femrub.contact.friction.solve_frictional_contact`)."""
        N = normal.shape[0]
        out = np.empty((N, self.n, 3))
        out[:, :, 0] = normal
        out[:, :, 1:] = tangential.reshape(N, self.n, 2)
        return out.reshape(N, 3 * self.n)

    @cached_property
    def H3(self) -> np.ndarray:
        """Force columns of the local impulses ``(P_n, P_t1, P_t2)`` (N, 3 n_c)."""
        return self.local(self.Hm, self.Hmt)

    @cached_property
    def V3T(self) -> np.ndarray:
        """Local velocity rows ``(ġ, w_t + v_c)`` of the structure (3 n_c, N)."""
        return np.ascontiguousarray(self.local(self.Gv, self.Gvt).T)

    def slip_velocity(self, X: np.ndarray) -> np.ndarray:
        """``w_t = Gvtᵀ X − v_c`` (m/s): (n_c, 2) for X (N,), (m, n_c, 2) for X (m, N)."""
        if X.ndim == 1:
            return (self.GvtT @ X).reshape(self.n, 2) - self.casing_velocity
        return (X @ self.Gvt).reshape(X.shape[0], self.n, 2) - self.casing_velocity

    def to_global(self, local: np.ndarray, part: str = "tangent") -> np.ndarray:
        """Vectors given on the tangents ((…, n_c, 2)) in global axes ((…, n_c, 3)):
        ``a₁ t₁ + a₂ t₂`` per contact, as two broadcast products (a third of an ``einsum``'s
        time on a block of a few hundred rows, the same bits)."""
        F = self.frames
        dim = F.shape[2]
        out = local[..., 0:1] * F[:, 1, :] + local[..., 1:2] * F[:, 2, :]
        if dim < 3:
            out = np.concatenate([out, np.zeros((*out.shape[:-1], 3 - dim))], axis=-1)
        return out

    def to_local(self, vectors: np.ndarray) -> np.ndarray:
        """Global vectors in the contacts' tangent planes ((…, n_c, 3)) on the tangents
        ((…, n_c, 2)): the inverse of :meth:`to_global` (least squares on ``t₁``, ``t₂``)."""
        F = self.frames
        T = F[:, 1:3, :]  # (n_c, 2, dim): t₁, t₂
        gram = np.einsum("nid,njd->nij", T, T)
        rhs = np.einsum("nid,...nd->...ni", T, vectors[..., : F.shape[2]])
        return np.linalg.solve(gram, rhs[..., None])[..., 0]

    def project(self, left: np.ndarray, right: np.ndarray) -> Contact:
        """Contact of the model reduced by ``X = right X̄`` and left projection ``leftᵀ``."""
        tang = {}
        if self.Gvt is not None:
            tang = {"Gvt": right.T @ self.Gvt, "Hmt": left.T @ self.Hmt}
        return replace(
            self,
            G=right.T @ self.G,
            Gv=right.T @ self.Gv,
            Hm=left.T @ self.Hm,
            Ht=left.T @ self.Ht,
            **tang,
        )


def _over_times(value: Callable, t: np.ndarray, n: int) -> np.ndarray:
    """``value(t_i)`` (n,) stacked over the times ``t`` (m,): an (m, n) array (in one call
    when ``value`` has a vectorised ``over_times``, e.g. the swept casing gap)."""
    rows = getattr(value, "over_times", None)
    if rows is not None:
        return np.asarray(rows(t), dtype=float).reshape(t.size, n)
    return np.array([value(ti) for ti in t], dtype=float).reshape(t.size, n)
