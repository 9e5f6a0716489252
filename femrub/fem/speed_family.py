"""Stiffness of a spinning blade at any speed from a few prestress solves.

The prestressed tangent ``K_T(Ω)`` (:mod:`femrub.fem.prestress`) is a smooth function of
``s = Ω²``: exactly affine for the linear prestress (``K + Ω² (K_σ1 − M_P)``), nearly so
for the nonlinear one. :class:`SpeedFamily` holds ``K_T`` at sample speeds ``Ω_j`` and
interpolates in ``s`` with Lagrange polynomials::

    K_T(Ω) ≈ Σ_j L_j(Ω²) K_T(Ω_j),    L_j(s) = Π_{m≠j} (s − s_m) / (s_j − s_m)

and likewise the static displacement ``u(Ω)``. :meth:`SpeedFamily.project` gives the
same family on a reduced basis (``Vᵀ K_j V``), so a Campbell diagram or a speed sweep
evaluates small matrices only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .prestress import centrifugal_prestress

__all__ = ["SpeedFamily", "lagrange_weights", "sample_speeds", "speed_family"]


def lagrange_weights(nodes, x: float) -> np.ndarray:
    """Weights ``L_j(x)`` of the Lagrange polynomial through ``nodes`` (distinct)."""
    nodes = np.asarray(nodes, dtype=float)
    w = np.ones(nodes.size)
    for j in range(nodes.size):
        for m in range(nodes.size):
            if m != j:
                w[j] *= (x - nodes[m]) / (nodes[j] - nodes[m])
    return w


def sample_speeds(max_speed: float, n: int) -> np.ndarray:
    """``n`` sample speeds equally spaced in ``Ω²`` from 0 to ``max_speed`` (rad/s)."""
    if n < 2:
        raise ValueError(f"a speed family needs at least 2 sample speeds, got {n}")
    return max_speed * np.sqrt(np.linspace(0.0, 1.0, n))


@dataclass(frozen=True)
class SpeedFamily:
    """``K_T`` (and ``u``) at sample speeds, interpolated in ``Ω²`` (module docstring).

    Attributes
    ----------
    speeds : (n_s,) sample speeds (rad/s).
    stiffness : list of the ``K_T(Ω_j)`` (sparse on the free dofs, or dense reduced).
    displacement : (n_s, n_u_all) static displacements (empty when projected).
    method : prestress method.
    """

    speeds: np.ndarray
    stiffness: list
    displacement: np.ndarray
    method: str

    def weights(self, omega: float) -> np.ndarray:
        return lagrange_weights(self.speeds**2, float(omega) ** 2)

    def stiffness_at(self, omega: float):
        """Interpolated ``K_T(Ω)``."""
        w = self.weights(omega)
        return sum(wj * Kj for wj, Kj in zip(w, self.stiffness))

    def displacement_at(self, omega: float) -> np.ndarray:
        """Interpolated static displacement ``u(Ω)`` (all dofs)."""
        return self.weights(omega) @ self.displacement

    def project(self, V: np.ndarray) -> SpeedFamily:
        """The family on the reduced basis ``V`` (n_free, k): dense ``Vᵀ K_j V``."""
        Ks = [V.T @ (K @ V) for K in self.stiffness]
        return SpeedFamily(self.speeds, Ks, np.zeros((self.speeds.size, 0)), self.method)


def speed_family(disc, material, speeds, method: str = "nonlinear", *, log=None) -> SpeedFamily:
    """Prestress ``disc`` at each of ``speeds`` (rad/s) and collect :class:`SpeedFamily`."""
    speeds = np.asarray(speeds, dtype=float)
    if np.unique(speeds**2).size != speeds.size:
        raise ValueError("the sample speeds of a speed family must be distinct")
    states = []
    for omega in speeds:
        if log:
            log(f"prestress ({method}) at {omega:g} rad/s ...")
        states.append(centrifugal_prestress(disc, material, omega, method, log=log))
    return SpeedFamily(speeds, [p.K for p in states], np.array([p.u for p in states]), method)
