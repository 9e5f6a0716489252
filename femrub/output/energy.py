"""Discrete energy and heat balance of a run, for any first-order model.

Over a step ``(t_k, t_{k+1}]`` with midpoint state ``X_m = (X_k + X_{k+1}) / 2``::

    ΔW_ext = h Σ_j s̄_j (p_jᵀ X_m)          s̄_j = (s_j(t_k) + s_j(t_{k+1})) / 2
    ΔW_th  = h X_mᵀ P_th X_m               work of the thermal stresses −K^uθ θ
             (or (X_{k+1} − X_k)ᵀ W_th X_m when the model carries W_th: a reduced model)
    ΔW_d   = h X_mᵀ P_d X_m                 damping (<= 0)
    ΔW_c   = Pᵀ Gvᵀ X_m                     impulse times the structure's mean gap velocity

For the θ-method with γ = 1/2 (trapezoidal rule) these increments make the balance
``E_{k+1} − E_k = ΔW_ext + ΔW_th + ΔW_d + ΔW_c`` exact up to round-off, so
``energy_error`` measures the scheme's own energy error; ``ΔW_c <= 0`` checks that no
energy is created at impacts (with Newton's law and e <= 1 the impulse satisfies
``P (ġ_{k+1} + e ġ_k) = 0``, hence ``ΔW_c = −P ġ_k (1 − e) / 2 <= 0`` for a fixed casing;
a moving casing, ``ġ = ġ0(t) + Gvᵀ X``, can also do work on the structure). The frictional
heat of a step is ``Σ_i α_i(t_{k+1}) P_i``.

With Coulomb friction the tangential impulses ``P_t`` add their work ``P_t · Gvtᵀ X_m`` to
``ΔW_c``; it splits exactly into the work of the moving casing surface and the friction
dissipation::

    ΔW_c,t = ΔW_casing − ΔW_friction,   ΔW_casing = P_t · v_c,   ΔW_friction = −P_t · w_t,m

(``w_t,m = Gvtᵀ X_m − v_c``, the mid-step slip velocity; a scheme that integrates the
tangential work ``∫ λ_t · Gvtᵀ X dt`` itself hands it as ``tangential_work``).
``friction_heat`` is then the heat the stepper put into the blade and
``heat_to_casing = friction_work − friction_heat``; on a model without blade temperatures
(a bladed disk, a blade run with ``physics.thermal = "off"``) nothing enters the blade and
``heat_to_casing`` is the casing's share ``Σ_i (1 − η_i)`` of each contact's friction work.
"""

from __future__ import annotations

import numpy as np

from ..fem.linalg import compact
from ..model.first_order import EnergyForms, FirstOrderModel
from ..steppers.record import WORK_KEYS
from .results import ENERGY_KEYS

__all__ = ["BLOWUP_FACTOR", "EnergyMeter"]

# a balance residual this many times the energy exchanged so far is created from nothing
# (a physical runaway keeps the balance closed): numerical blow-up
BLOWUP_FACTOR = 1e3

_WORKS = ("external_work", "thermal_work", "damping_work", "contact_work")
_HEATS = ("friction_heat", "heat_load", "heat_outflow")


def _heat_to_casing(contact, inc: dict, Pt: np.ndarray, Xm: np.ndarray) -> np.ndarray:
    """The casing's share of each step's friction work under the ``"power"`` law: what the
    blade did not take (``friction_work − friction_heat``), or, on a model without blade
    temperatures (no heat enters a blade dof), ``Σ_i (1 − η_i) (−P_t,i · w_t,m,i)``: the
    blade's share ``η`` then leaves the model's bookkeeping instead of being counted as the
    casing's."""
    if contact.has_heat or not Pt.shape[1]:
        return inc.get("friction_work", 0.0) - inc["friction_heat"]
    slip = (Xm @ contact.Gvt).reshape(Pt.shape) - contact.casing_velocity
    per_contact = -np.einsum("kij,kij->ki", Pt, slip)
    return per_contact @ (1.0 - contact.heat_partition)


class EnergyMeter:
    """Accumulates the energy balance over blocks of steps (see module docstring).

    ``update(i0, X, impulse, t, h)`` takes the states ``X[0..m]`` at times ``t[0..m]``
    (``X[0]`` already recorded as row ``i0``) and the impulses of the ``m`` steps, and fills
    rows ``i0 + 1 .. i0 + m`` with vectorised increments.
    """

    def __init__(self, model: FirstOrderModel, capacity: int):
        self.model = model
        f = model.energy
        self.forms = EnergyForms(
            *(compact(q) for q in (f.Qk, f.Qe, f.Pth, f.Pd)),
            f.heat_content,
            f.heat_outflow,
            None if f.Wth is None else compact(f.Wth),
        )
        self._signals = [term.signal for term in model.loads]
        self._powers = (
            np.column_stack([term.power for term in model.loads]) if model.loads else None
        )
        self._heats = np.array([term.heat for term in model.loads])
        self.contact = model.contact
        self.data = {k: np.zeros(capacity) for k in ENERGY_KEYS}
        self._support: dict[int, tuple] = {}
        self._E0 = self._Q0 = 0.0
        self.scale = 0.0
        self.heat_scale = 0.0

    def _quad(self, Q, X):
        """Row-wise ``x_iᵀ Q x_i`` for the rows ``x_i`` of ``X``; a dense ``Q`` on the rows and
        columns where it is nonzero (an energy form acts on one block of the state)."""
        if not isinstance(Q, np.ndarray):
            return np.einsum("ij,ij->i", X, np.asarray((Q @ X.T).T))
        sub = self._support.get(id(Q))
        if sub is None:
            sub = self._support[id(Q)] = _support(Q)
        Qs, r, c = sub
        return np.einsum("ij,ij->i", X[:, r], X[:, c] @ Qs.T)  # X @ Q.T: fast BLAS path

    def start(self, X0: np.ndarray) -> None:
        f, d = self.forms, self.data
        X = X0[None, :]
        d["kinetic"][0] = 0.5 * self._quad(f.Qk, X)[0]
        d["elastic"][0] = 0.5 * self._quad(f.Qe, X)[0]
        d["heat_content"][0] = float(f.heat_content @ X0)
        self._E0 = d["kinetic"][0] + d["elastic"][0]
        self._Q0 = d["heat_content"][0]
        self.scale, self.heat_scale = abs(self._E0), abs(self._Q0)

    def update(self, i0, X, impulse, t, h, work=None, friction=None) -> None:
        """Fill rows ``i0 + 1 .. i0 + m`` from a block of states (see class docstring).

        ``work``: ``{key: (m,)}``, the works and heats of each step that the stepper computed
        itself (the step records' ``works``, keys in
        :data:`~femrub.steppers.record.WORK_KEYS`; e.g. impulses given inside the step, an
        exact flight); the others by the quadratures above (contact: ``Pᵀ Gvᵀ X_m``).
        ``friction``: ``(P_t (m, n_c, 2), blade heat (m, n_c))`` of the steps, or ``None``.
        """
        f, d = self.forms, self.data
        m = X.shape[0] - 1
        rows = slice(i0 + 1, i0 + 1 + m)
        Xm = 0.5 * (X[1:] + X[:-1])
        inc = {}
        if self._powers is not None:
            S = np.array([[float(sig(tt)) for sig in self._signals] for tt in t])
            Sbar = 0.5 * (S[1:] + S[:-1])
            inc["external_work"] = h * np.einsum("ij,ij->i", Sbar, Xm @ self._powers)
            inc["heat_load"] = h * (Sbar @ self._heats)
        if f.Wth is None:
            inc["thermal_work"] = h * self._quad(f.Pth, Xm)
        else:  # work on the state increment (a reduced model's expansion shapes jump)
            dX = X[1:] - X[:-1]
            WX = Xm @ f.Wth.T if isinstance(f.Wth, np.ndarray) else (f.Wth @ Xm.T).T
            inc["thermal_work"] = np.einsum("ij,ij->i", dX, np.asarray(WX))
        inc["damping_work"] = h * self._quad(f.Pd, Xm)
        own = work or {}
        c = self.contact
        if c is not None:
            dwc = own.get("contact_work")
            if dwc is None:
                dwc = np.einsum("ij,ij->i", impulse, c.structure_velocity(Xm))
            inc["contact_work"] = dwc
            inc["impact_dissipation"] = -dwc
            alpha = np.broadcast_to(c.alpha_at(t[1:]), impulse.shape)
            inc["friction_heat"] = np.einsum("ij,ij->i", alpha, impulse)
            if friction is not None:
                Pt, heat = friction
                if Pt.shape[1]:
                    wt = own.get("tangential_work")
                    if wt is None:  # P_t · Gvtᵀ X_m
                        vt = (Xm @ c.Gvt).reshape(Pt.shape)
                        wt = np.einsum("kij,kij->k", Pt, vt)
                    inc["contact_work"] = dwc + wt
                    inc["casing_work"] = np.einsum("kij,ij->k", Pt, c.casing_velocity)
                    inc["friction_work"] = inc["casing_work"] - wt
                    inc["impact_dissipation"] = -dwc
                inc["friction_heat"] = heat.sum(axis=1)
                if c.heat_law == "power":
                    inc["heat_to_casing"] = _heat_to_casing(c, inc, Pt, Xm)
        inc["heat_outflow"] = h * (Xm @ f.heat_outflow)
        for k in WORK_KEYS[1:6]:  # the stepper's own, where it gave them
            if k in own:
                inc[k] = own[k]
        for k, v in inc.items():
            d[k][rows] = d[k][i0] + np.cumsum(v)
        d["kinetic"][rows] = 0.5 * self._quad(f.Qk, X[1:])
        d["elastic"][rows] = 0.5 * self._quad(f.Qe, X[1:])
        d["heat_content"][rows] = X[1:] @ f.heat_content
        works = sum(d[k][rows] for k in _WORKS)
        d["energy_error"][rows] = d["kinetic"][rows] + d["elastic"][rows] - self._E0 - works
        heats = d["friction_heat"][rows] + d["heat_load"][rows] - d["heat_outflow"][rows]
        d["heat_error"][rows] = d["heat_content"][rows] - self._Q0 - heats
        mech = np.max([np.abs(d[k][rows]) for k in _WORKS], axis=0)
        heat = np.max([np.abs(d[k][rows]) for k in _HEATS], axis=0)
        self._scale_rows = np.maximum.accumulate(np.maximum(mech, self.scale))
        self._heat_rows = np.maximum.accumulate(np.maximum(heat, self.heat_scale))
        self.scale, self.heat_scale = self._scale_rows[-1], self._heat_rows[-1]

    def blown_up(self, rows: slice, factor: float = BLOWUP_FACTOR) -> int | None:
        """First row in ``rows`` where a balance residual dwarfs the energy put in or taken out.

        A physical runaway is fed by the thermal work and keeps the balance closed; a
        numerical instability creates energy from nothing and opens it.
        """
        d = self.data
        # compared only once something has entered: round-off before that is not a blow-up
        mech = (self._scale_rows > 0) & (
            np.abs(d["energy_error"][rows]) > factor * self._scale_rows
        )
        heat = (self._heat_rows > 0) & (np.abs(d["heat_error"][rows]) > factor * self._heat_rows)
        bad = mech | heat
        return rows.start + int(np.argmax(bad)) if bad.any() else None

    def arrays(self, n: int) -> dict[str, np.ndarray]:
        return {k: v[:n].copy() for k, v in self.data.items()}


def _support(Q: np.ndarray) -> tuple:
    """``(Q[r][:, c], r, c)``: the rows ``r`` and columns ``c`` where ``Q`` is nonzero, as
    slices when they are ranges (no copy of the states' columns)."""

    def part(mask):
        idx = np.flatnonzero(mask)
        if idx.size == 0:
            return slice(0, 0)
        if idx[-1] - idx[0] + 1 == idx.size:
            return slice(int(idx[0]), int(idx[-1]) + 1)
        return idx

    r, c = part(np.any(Q != 0.0, axis=1)), part(np.any(Q != 0.0, axis=0))
    return np.ascontiguousarray(Q[r][:, c]), r, c
