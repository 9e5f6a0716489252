"""Frictional heat into the casing and the clearance its expansion takes (lumped model).

The casing wall (coating + shell) of thickness ``b`` is cut into cells on a grid of casing
angle × axial position (as the wear map, :mod:`femrub.contact.abradable`). Each cell is one
lumped temperature rise ``T`` above ambient (documented lumped model, no conduction between
cells): heat capacity ``C = ρ c b A`` and conductance through the wall to the ambient outer
shell ``G = k A / b``, so with the power ``q`` it receives::

    C dT/dt = q − G T,        τ = C / G = ρ c b² / k

integrated exactly for a power constant over a step (``T ← T e^{−h/τ} + q/G (1 − e^{−h/τ})``)
and lazily (a cell cools as ``e^{−Δt/τ}`` since its last update, evaluated when a contact
meets it). The step being solved sees the wall as the last step's power, continued, left
it (explicit in the power, exact in the cooling): so a held contact follows the wall
instead of finding itself inside it after the update. The contact ``i`` over the step puts
the casing's share of the frictional power into the cell under it::

    q_i = (1 − η) P_i α_i / (η h)     (α_i = η μ |Ω| r_i: heat law of the blade, P_i impulse)

i.e. ``(1 − η) μ |Ω| r_i λ_i`` (heat law ``"alpha"``), or with Coulomb friction (heat law
``"power"``) ``q_i = (1 − η) (−P_t,i · w_t,i) / h``, the casing's share of the friction
power (:meth:`~femrub.contact.gap.Contact.after_step`). The wall expands through its
thickness towards the blade (the outer shell holds it), closing the gap by ``δ = α_c b T``:

    g_i(t, X) = ... − α_c b T(Ω t + φ_i, z_i)

Heat partition from the effusivities ``e = √(k ρ c)`` of blade and casing when not given:
``η = e_blade / (e_blade + e_casing)`` (:func:`effusivity_partition`).
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ..fem.material import check_finite_positive
from .run_state import RunState

__all__ = ["CasingHeat", "effusivity_partition"]


def effusivity_partition(blade: tuple, casing: tuple) -> float:
    """Share ``η`` of the frictional power entering the blade from ``(k, ρ, c)`` of each."""
    eb = math.sqrt(blade[0] * blade[1] * blade[2])
    ec = math.sqrt(casing[0] * casing[1] * casing[2])
    return eb / (eb + ec)


class CasingHeat(RunState):
    """Lumped casing-wall temperatures on the cells of ``grid`` (module docstring).

    Parameters
    ----------
    grid : :class:`~femrub.contact.abradable.CasingGrid` of the contacts.
    thickness : wall thickness ``b`` (m).
    density, specific_heat, conductivity, expansion : wall material (SI).
    partition : ``η``, share of the frictional power that enters the blade (< 1).
    alpha : (n_c,) blade heat coefficients ``α_i = η μ |Ω| r_i`` (m/s).
    """

    def __init__(
        self, grid, thickness, density, specific_heat, conductivity, expansion, partition, alpha
    ):
        self.grid = grid
        self.b = check_finite_positive("contact.casing_heat.thickness", thickness)
        rho_c = check_finite_positive("contact.casing_heat.density", density)
        rho_c *= check_finite_positive("contact.casing_heat.specific_heat", specific_heat)
        k = check_finite_positive("contact.casing_heat.conductivity", conductivity)
        self.expansion = float(expansion)
        self.tau = rho_c * self.b**2 / k
        self.conductance = k * grid.cell_area / self.b  # (n_axial,) W/K per cell
        eta = float(partition)
        if not 0.0 < eta <= 1.0:
            raise ValueError(f"heat partition must be in (0, 1] with casing heat, got {eta!r}")
        self.power_per_impulse = (1.0 - eta) / eta * np.asarray(alpha, dtype=float)  # m/s
        self.reset()

    def fresh(self) -> CasingHeat:
        """A copy of this casing, cold, for a run: its own cell temperatures and history
        (the grid and the wall's properties are shared, never changed)."""
        out = copy.copy(self)
        out.reset()
        return out

    def reset(self) -> None:
        """Cold: no temperature rise, no heat received."""
        shape = (self.grid.n_angle * self.grid.n_axial,)
        self.T = np.zeros(shape)
        self.t_last = np.zeros(shape)
        self.q = np.zeros(shape)  # W of the last update
        self.h = math.inf  # step of the last update
        self.heat_in = 0.0  # J
        self.history = [(0.0, 0.0)]

    #: what a run changes (cell temperatures, heat received, history): RunState
    _STATE = ("T", "t_last", "q", "h", "heat_in", "history")

    def _cool_to(self, cells, t) -> np.ndarray:
        dt = t - self.t_last[cells]
        return self.T[cells] * np.exp(-np.maximum(dt, 0.0) / self.tau)

    def _predict(self, cells, t) -> np.ndarray:
        """``T`` at ``t``: a cell heated over the last step keeps that power up to one step
        on (the step being solved sees the wall the heat of the last one expands), else
        it cools. The update after the step then puts the step's own power in."""
        dt = np.maximum(t - self.t_last[cells], 0.0)
        decay = np.exp(-dt / self.tau)
        G = self.conductance[cells % self.grid.n_axial]
        q = np.where(dt <= 1.01 * self.h, self.q[cells], 0.0)
        return self.T[cells] * decay + q / G * (1.0 - decay)

    def temperature_at(self, t: float) -> np.ndarray:
        """Wall temperature rise under each contact at ``t`` (K)."""
        return self._predict(self.grid.cells(t), t)

    def closure_at(self, t: float) -> np.ndarray:
        """How much the wall's expansion closes each contact's gap at ``t`` (m)."""
        return self.expansion * self.b * self.temperature_at(t)

    def closure_rate_at(self, t: float) -> np.ndarray:
        """``d/dt`` of :meth:`closure_at` (m/s): ``α_c b (q − G T) / C`` with the power ``q``
        of the step just done (zero in cells no contact heated then). It enters the gap rate
        ``ġ0`` so the velocity-level contact law follows the wall as it expands."""
        cells = self.grid.cells(t)
        T = self._predict(cells, t)
        G = self.conductance[cells % self.grid.n_axial]
        q = np.where(t - self.t_last[cells] <= 1.01 * self.h, self.q[cells], 0.0)
        return self.expansion * self.b * (q - G * T) / (G * self.tau)

    def update(self, t: float, heat: np.ndarray, h: float) -> None:
        """Add the step's casing heat ``heat`` (n_c,) (J over the step ending at ``t``) to
        the cells under the contacts (:meth:`~femrub.contact.gap.Contact.after_step`)."""
        Q = np.asarray(heat, dtype=float)
        self.h = h
        # every cell under a contact is updated (with zero power where no heat came)
        c, inv = np.unique(self.grid.cells(t), return_inverse=True)
        q = np.bincount(inv, weights=Q / h, minlength=c.size)  # W per cell
        decay = math.exp(-h / self.tau)
        G = self.conductance[c % self.grid.n_axial]
        self.T[c] = self._cool_to(c, t - h) * decay + q / G * (1.0 - decay)
        self.t_last[c] = t
        self.q[c] = q
        if np.any(Q > 0.0):
            self.heat_in += float(Q.sum())
            self.history.append((float(t), float(self.T[c].max())))

    def map_at(self, t: float) -> np.ndarray:
        """(n_angle, n_axial) wall temperature rise at ``t`` (K)."""
        T = self.T * np.exp(-np.maximum(t - self.t_last, 0.0) / self.tau)
        return T.reshape(self.grid.n_angle, self.grid.n_axial)
