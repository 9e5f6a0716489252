"""Discrete energy and heat balance of a run, for any first-order model.

Over a step ``(t_k, t_{k+1}]`` with midpoint state ``X_m = (X_k + X_{k+1}) / 2``::

    ΔW_ext = h Σ_j s̄_j (p_jᵀ X_m)          s̄_j = (s_j(t_k) + s_j(t_{k+1})) / 2
    ΔW_th  = h X_mᵀ P_th X_m               work of the thermal stresses −K^uθ θ
    ΔW_d   = h X_mᵀ P_d X_m                 damping (<= 0)
    ΔW_c   = Pᵀ ġ(X_m)                      contact impulse times mean gap velocity (<= 0)

For the θ-method with γ = 1/2 (trapezoidal rule) these increments make the balance
``E_{k+1} − E_k = ΔW_ext + ΔW_th + ΔW_d + ΔW_c`` exact up to round-off, so
``energy_error`` measures the scheme's own energy error; ``ΔW_c <= 0`` checks that no
energy is created at impacts (with Newton's law and e <= 1 the impulse satisfies
``P (ġ_{k+1} + e ġ_k) = 0``, hence ``ΔW_c = −P ġ_k (1 − e) / 2 <= 0``).
"""

from __future__ import annotations

import numpy as np

from .model import FirstOrderModel
from .results import ENERGY_KEYS

__all__ = ["EnergyMeter"]


class EnergyMeter:
    """Accumulates the energy balance step by step (see module docstring)."""

    def __init__(self, model: FirstOrderModel, capacity: int):
        self.model = model
        self.forms = model.energy
        self.data = {k: np.zeros(capacity) for k in ENERGY_KEYS}
        self._acc = dict.fromkeys(ENERGY_KEYS, 0.0)
        self._powers = [term.power for term in model.loads]
        self._heats = np.array([term.heat for term in model.loads])
        self._E0 = self._Q0 = 0.0
        self.scale = 0.0
        self.heat_scale = 0.0

    def _mech(self, X):
        f = self.forms
        return 0.5 * X @ (f.Qk @ X), 0.5 * X @ (f.Qe @ X)

    def start(self, X0: np.ndarray) -> None:
        kin, ela = self._mech(X0)
        self._E0 = kin + ela
        self._Q0 = float(self.forms.heat_content @ X0)
        self._acc.update(kinetic=kin, elastic=ela, heat_content=self._Q0)
        self.scale = abs(self._E0)
        self.heat_scale = abs(self._Q0)
        self.record(0)

    def record(self, i: int) -> None:
        for k, v in self._acc.items():
            self.data[k][i] = v

    def update(self, i, Xk, Xk1, impulse, tk, tk1, h, alpha, gap_velocity_mid) -> None:
        """Add the increments of step ``i − 1 → i`` and store row ``i``."""
        f, a = self.forms, self._acc
        Xm = 0.5 * (Xk + Xk1)
        if self._powers:
            s = np.array([0.5 * (t.signal(tk) + t.signal(tk1)) for t in self.model.loads])
            a["external_work"] += h * float(sum(si * (p @ Xm) for si, p in zip(s, self._powers)))
            a["heat_load"] += h * float(s @ self._heats)
        a["thermal_work"] += h * float(Xm @ (f.Pth @ Xm))
        a["damping_work"] += h * float(Xm @ (f.Pd @ Xm))
        if impulse.size:
            dwc = float(impulse @ gap_velocity_mid)
            a["contact_work"] += dwc
            a["impact_dissipation"] -= dwc
            a["friction_heat"] += float(alpha @ impulse)
        a["heat_outflow"] += h * float(f.heat_outflow @ Xm)
        kin, ela = self._mech(Xk1)
        a["kinetic"], a["elastic"] = kin, ela
        a["heat_content"] = float(f.heat_content @ Xk1)
        works = a["external_work"] + a["thermal_work"] + a["damping_work"] + a["contact_work"]
        a["energy_error"] = kin + ela - self._E0 - works
        heats = a["friction_heat"] + a["heat_load"] - a["heat_outflow"]
        a["heat_error"] = a["heat_content"] - self._Q0 - heats
        self.scale = max(
            self.scale,
            abs(a["external_work"]),
            abs(a["thermal_work"]),
            abs(a["damping_work"]),
            abs(a["contact_work"]),
        )
        self.heat_scale = max(
            self.heat_scale, abs(a["friction_heat"]), abs(a["heat_load"]), abs(a["heat_outflow"])
        )
        self.record(i)

    def blown_up(self, factor: float = 1e3) -> bool:
        """True when a balance residual dwarfs the energy put in or taken out (numerics).

        A physical runaway is fed by the thermal work and keeps the balance closed; a
        numerical instability creates energy from nothing and opens it.
        """
        a = self._acc
        mech = abs(a["energy_error"]) > factor * max(self.scale, 1e-30)
        heat = abs(a["heat_error"]) > factor * max(self.heat_scale, 1e-30)
        return bool(mech or heat)

    def arrays(self, n: int) -> dict[str, np.ndarray]:
        return {k: v[:n].copy() for k, v in self.data.items()}
