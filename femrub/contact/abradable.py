"""Abradable coating on the casing: a wear map that deepens where the blade cuts it.

The coating (thickness ``e``) lines the casing. Its current wear depth ``w(ψ, z) ∈ [0, e]``
is stored as one coefficient per cell of a grid of casing angle ``ψ`` (``n_angle`` cells
over a revolution) × axial position ``z`` (``n_axial`` cells over the contacts' axial
extent), and read in ``ψ`` as the periodic quadratic B-spline of the coefficients
(:mod:`femrub.contact.wear_map`): the worn surface a contact slides on is continuous with a
continuous slope, and its rate ``Ω ∂w/∂ψ`` is continuous too, so neither the time step nor
the cell size puts an impact at the centres. Contact ``i`` (angle ``φ_i``, axial position
``z_i``) meets the worn surface, so its gap is::

    g_i(t, X) = g0_i(t) + w(Ω t + φ_i, z_i) − n_i · u(p_i)

A contact that stands for a footprint of the tip (``contact.abradable.footprint``, its
circumferential width) reads the worn surface as its mean over that width
(:mod:`femrub.contact.wear_map`).

Removal law (rigid–perfectly plastic coating, in the spirit of the plastic abradable law
of Batailly & Legrand): the coating carries at most the yield force ``F_y`` per contact; the
impulse of a step is bounded, ``0 <= P_i <= h F_y`` (:func:`femrub.contact.impulses.cap`),
and below that bound contact complementarity holds on the worn surface. When the bound is
reached the coating yields: the blade penetrates the current surface and the material it
penetrates is removed permanently (after each step, :meth:`Abradable.update`). With the
blade's reach into the coating ``r_i = w(ψ_i) − g_i``, the reach linear along the sweep of
the step (from ``ψ_i(t − h)`` to ``ψ_i(t)``), every coefficient whose support meets the
sweep is raised to the largest reach of the sweep over its support::

    c(ψ_k, z_i) <- min(e, max(c(ψ_k, z_i), max_{|ψ − ψ_k| <= 3/2 cell} r_i(ψ)))

so that after the update ``w >= r_i`` all along the sweep (``g_i(t) >= 0`` on the new
surface, and a contact that retraces its own cut does not meet the coating again). A
contact that crosses several cells in a step cuts all of them: the worn volume does not
depend on how the time step compares with the cell size. Once the surface is worn through
(``w = e``) the rigid casing behind it takes any force. Wear is monotone, never negative
and never deeper than ``e``.

The wear map is casing state that evolves during a run: a stepper calls :meth:`reset` when
it starts. ``history`` keeps ``(t, deepest point of the surface)`` at every step that
removed material; ``incursion`` each contact's largest reach ``r_i = w − g_i`` so far (m):
how deep below the unworn surface its tip went, cutting or riding in a groove another
contact (another blade) cut. The cut is :func:`femrub.contact.wear_map.cut_sweeps` (compiled), which
the θ-method's blocks of steps also call (:mod:`femrub.contact.rub_block`).
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ..fem.material import check_finite_positive
from .run_state import RunState
from .wear_map import cut_sweeps, depth_under, entry_bounds, surface_max

__all__ = ["Abradable", "CasingGrid"]


class CasingGrid:
    """Cells of the casing swept by contacts: ``n_angle`` around × ``n_axial`` along the axis.

    Parameters
    ----------
    angles : (n_c,) angular positions ``φ_i`` of the contacts (rad).
    axial : (n_c,) axial positions ``z_i`` of the contacts (m).
    radius : casing radius used for areas and volumes (m).
    rotation_speed : Ω (rad/s).
    n_angle, n_axial : grid cells around the casing and along the axis (over the contacts'
        axial extent, half a cell beyond each end).
    footprint : circumferential width of the tip each contact stands for (m): the contacts
        read values as their mean over it (0: at their point).
    """

    def __init__(
        self, angles, axial, radius, rotation_speed, n_angle=360, n_axial=16, footprint=0.0
    ):
        self.radius = check_finite_positive("casing radius", radius)
        self.omega = float(rotation_speed)
        self.angles = np.asarray(angles, dtype=float).ravel()
        self.axial = np.asarray(axial, dtype=float).ravel()
        if self.angles.shape != self.axial.shape:
            raise ValueError("casing grid: one angle and one axial position per contact")
        if not (int(n_angle) >= 1 and int(n_axial) >= 1):
            raise ValueError("casing grid needs n_angle >= 1 and n_axial >= 1")
        self.n_angle, self.n_axial = int(n_angle), int(n_axial)
        if not (math.isfinite(footprint) and footprint >= 0.0):
            raise ValueError("contact.abradable.footprint must be a length >= 0")
        self.footprint = float(footprint)
        #: the footprint in cells, ``β``
        self.beta = self.footprint * self.n_angle / (2 * math.pi * self.radius)
        z0, z1 = (float(self.axial.min()), float(self.axial.max())) if self.axial.size else (0, 0)
        pad = 0.5 * (z1 - z0) / max(self.n_axial - 1, 1) if z1 > z0 else 0.5e-3
        self.z_edges = np.linspace(z0 - pad, z1 + pad, self.n_axial + 1)
        k = np.searchsorted(self.z_edges, self.axial, side="right") - 1
        self.axial_cell = np.clip(k, 0, self.n_axial - 1)

    def cells(self, t: float) -> np.ndarray:
        """Flat indices of the cells under the contacts at time ``t``."""
        psi = np.mod(self.omega * t + self.angles, 2 * math.pi)
        j = np.minimum((psi * self.n_angle / (2 * math.pi)).astype(int), self.n_angle - 1)
        return j * self.n_axial + self.axial_cell

    def position(self, t: float) -> np.ndarray:
        """Contacts' positions in cell-centre units, ``ψ n_angle / 2π − 1/2`` (unwrapped:
        centre ``k`` is at ``k``, taken modulo ``n_angle``)."""
        return (self.omega * t + self.angles) * (self.n_angle / (2 * math.pi)) - 0.5

    def flat(self, k: np.ndarray, axial_cell: np.ndarray) -> np.ndarray:
        """Flat indices of centres ``k`` (any integers, periodic) in rows ``axial_cell``."""
        return np.mod(k, self.n_angle) * self.n_axial + axial_cell

    def interpolate(self, values: np.ndarray, t: float) -> np.ndarray:
        """``values`` (flat, per cell) at the contacts at ``t``: the periodic quadratic
        B-spline of the values, or its mean over the footprint
        (:func:`femrub.contact.wear_map.depth_under`)."""
        x = self.position(t)
        if self.beta > 0.0:  # x: (n,) or, for several times at once, (m, n)
            v = np.ascontiguousarray(values, dtype=float)
            rows = np.ascontiguousarray(np.broadcast_to(self.axial_cell, x.shape)).reshape(-1)
            xs = np.ascontiguousarray(x, dtype=float).reshape(-1)
            out = depth_under(v, xs, rows, self.n_angle, self.n_axial, self.beta)
            return out.reshape(x.shape)
        kf = np.floor(x + 0.5)
        u = x - kf
        k = kf.astype(np.int64)
        bm = 0.5 * (0.5 - u) * (0.5 - u)
        b0 = 0.75 - u * u
        bp = 0.5 * (0.5 + u) * (0.5 + u)
        a = self.axial_cell
        return (bm * values[self.flat(k - 1, a)] + b0 * values[self.flat(k, a)]) + bp * values[
            self.flat(k + 1, a)
        ]

    @property
    def cell_area(self) -> np.ndarray:
        """(n_axial,) area of a cell of each axial row (m²)."""
        return 2 * math.pi * self.radius / self.n_angle * np.diff(self.z_edges)

    def angle_centres(self) -> np.ndarray:
        return (np.arange(self.n_angle) + 0.5) * 2 * math.pi / self.n_angle

    def axial_centres(self) -> np.ndarray:
        return 0.5 * (self.z_edges[1:] + self.z_edges[:-1])


class Abradable(RunState):
    """Abradable coating on the cells of a :class:`CasingGrid` (module docstring).

    Parameters
    ----------
    thickness : coating thickness ``e`` (m).
    yield_force : force per contact at which the coating yields ``F_y`` (N).
    grid : :class:`CasingGrid` of the contacts.
    """

    def __init__(self, thickness, yield_force, grid: CasingGrid):
        self.thickness = check_finite_positive("contact.abradable.thickness", thickness)
        self.yield_force = check_finite_positive("contact.abradable.yield", yield_force)
        self.grid = grid
        self.n_angle, self.n_axial, self.z_edges = grid.n_angle, grid.n_axial, grid.z_edges
        self.radius = grid.radius
        self.reset()

    # -- state --------------------------------------------------------------------------
    def fresh(self, h: float | None = None) -> Abradable:
        """A copy of this coating, unworn, for a run of step ``h`` (s): its own wear map and
        history (the grid and the material are shared, never changed)."""
        out = copy.copy(self)
        out.reset(h)
        return out

    def reset(self, h: float | None = None) -> None:
        """A fresh coating: no wear, empty history; ``h``: the time step of the stepper that
        runs it (for :meth:`rate_at`; ``None``: no rate)."""
        self.depth = np.zeros((self.n_angle, self.n_axial))
        self.history = [(0.0, 0.0)]
        self.h = h
        self._last = None  # (t, reach) of the previous update: the start of the next sweep
        self._bound = None  # (t, bounds) of the last step's impulse_cap
        self.incursion = np.zeros(self.grid.angles.size)  # each contact's largest reach (m)

    #: what a run changes (wear map, history, where the next sweep starts): RunState
    _STATE = ("depth", "history", "_last", "_bound", "incursion")

    def cells(self, t: float) -> np.ndarray:
        return self.grid.cells(t)

    def depth_at(self, t: float) -> np.ndarray:
        """Wear depth under each contact at ``t`` (m): what the worn surface adds to the gap
        (the quadratic B-spline of the map, :mod:`femrub.contact.wear_map`)."""
        return self.grid.interpolate(self.depth.ravel(), t)

    def rate_at(self, t: float) -> np.ndarray | float:
        """Rate of the worn surface under each contact, ``(w(t) − w(t − h)) / h`` (m/s).

        A contact sliding towards a less worn part of the map meets the coating as a surface
        approaching it. This rate enters ``ġ0``
        (:meth:`~femrub.contact.gap.Contact.rate_at`) so a velocity-level contact law stops
        the blade there and the coating yields (as the casing profile's own rate does on a
        continuous lobe); without it, the blade would cross the unworn coating with no force
        and no wear wherever the profile recedes. The surface has a continuous slope, so the
        rate tends to ``Ω ∂w/∂ψ`` as ``h → 0``.
        """
        if not self.h:
            return 0.0
        return (self.depth_at(t) - self.depth_at(t - self.h)) / self.h

    def impulse_cap(self, t: float, h: float, gap_k=None, gap_p=None) -> np.ndarray:
        """Largest impulse per contact over the step ending at ``t``: ``h F_y``, ``inf`` where
        worn through; with the gaps at ``t_k`` and of the free step at ``t``, less for a
        contact entering the coating within the step (``F_y`` times the part of the step
        after it reaches it, :func:`~femrub.contact.wear_map.entry_bounds`). The bound is
        kept for the step's :meth:`bound` (the yield test after the step)."""
        worn = self.depth_at(t) >= self.thickness
        U = np.where(worn, math.inf, h * self.yield_force)
        if gap_k is not None:
            g_k = np.ascontiguousarray(gap_k, dtype=float)
            entry_bounds(U, g_k, np.ascontiguousarray(gap_p, dtype=float))
        self._bound = (float(t), U.copy())
        return U

    def bound(self, t: float, h: float) -> np.ndarray:
        """The bound of the step ending at ``t`` as :meth:`impulse_cap` last gave it (``h F_y``
        or ``inf`` when it gave none for that step)."""
        b = self._bound
        if b is not None and abs(b[0] - t) <= 1e-9 * h:
            return b[1]
        worn = self.depth_at(t) >= self.thickness
        return np.where(worn, math.inf, h * self.yield_force)

    def update(self, t: float, gap: np.ndarray, yielded: np.ndarray) -> None:
        """Cut the coating swept by contacts that ``yielded`` over the step ending at ``t``
        (module doc); call it after every step.

        ``gap`` is the gap on the current worn surface at ``t`` (m): the contacts' reach into
        the coating is ``r = w − gap``. The sweep starts where the previous call left the
        contacts (at the start of a run: where they are now).
        """
        depth = self.depth_at(t)
        reach = depth - np.asarray(gap, dtype=float)
        last, self._last = self._last, (float(t), reach)
        self.incursion = np.maximum(self.incursion, reach)
        cut = np.asarray(yielded, dtype=bool) & (reach > depth)
        if not np.any(cut):
            return
        g = self.grid
        i = np.flatnonzero(cut)
        r1 = reach[i]
        x1 = g.position(t)[i]
        if last is None or not t > last[0]:
            x0, r0 = x1, r1
        else:
            x0, r0 = g.position(last[0])[i], last[1][i]
        flat = self.depth.ravel()  # a view: cut in place
        deepest = cut_sweeps(
            flat,
            g.axial_cell[i],
            x0,
            x1,
            r0,
            r1,
            self.thickness,
            self.n_angle,
            self.n_axial,
            g.beta,
        )
        self.history.append((float(t), max(self.history[-1][1], float(deepest))))

    # -- results ------------------------------------------------------------------------
    @property
    def surface(self) -> np.ndarray:
        """(n_angle, n_axial) depth of the worn surface at the cell centres (m),
        ``(c[k − 1] + 6 c[k] + c[k + 1]) / 8``: what the wear map shows."""
        c = self.depth
        return (np.roll(c, 1, axis=0) + 6.0 * c + np.roll(c, -1, axis=0)) / 8.0

    @property
    def max_depth(self) -> float:
        """The deepest point of the worn surface (m): the largest of its pieces' maxima
        (:func:`~femrub.contact.wear_map.surface_max`)."""
        return float(surface_max(self.depth.ravel(), self.n_angle, self.n_axial))

    @property
    def cell_area(self) -> np.ndarray:
        return self.grid.cell_area

    @property
    def worn_volume(self) -> float:
        """Removed coating volume ``Σ w A_cell`` (m³)."""
        return float(np.sum(self.depth * self.cell_area[None, :]))

    def angle_centres(self) -> np.ndarray:
        return self.grid.angle_centres()

    def axial_centres(self) -> np.ndarray:
        return self.grid.axial_centres()

    def as_dict(self) -> dict:
        return {
            "thickness": self.thickness,
            "yield": self.yield_force,
            "n_angle": self.n_angle,
            "n_axial": self.n_axial,
            "radius": self.radius,
            "footprint": self.grid.footprint,
        }
