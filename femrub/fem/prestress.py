"""Static centrifugal prestress of a spinning blade and its prestressed stiffness.

:func:`centrifugal_prestress` solves the static equilibrium of :mod:`femrub.fem.centrifugal`
at the rotation speed Ω on the free (unclamped) displacement dofs of a
:class:`~femrub.fem.discretisation.Discretisation`::

    r(u) = f_int(u) − f_Ω(u) = 0,   f_Ω(u) = ∫ ρ Ω² P (X + u) · v dX

* ``"nonlinear"`` (default): Newton on the total-Lagrangian form, ``K_T(u_k) Δu = −r(u_k)``,
  with the load on the deformed geometry, converged in the energy norm ``|Δu · r|``; when
  a full step does not converge the load ``Ω²`` is applied in increments (continuation,
  doubled after a success, each increment starting from the extrapolated previous one). An
  increment whose Newton correction grows in energy (``Θ₀ = (e₁ / e₀)^½ > 1``: it
  diverges) is rejected after those two iterations, and the next one is that increment
  halved as many times as it takes to bring ``Θ₀``, taken proportional to the increment,
  below 1: one rejection instead of one per halving.
* ``"linear"``: one solve of ``(K − Ω² M_P) u = f_Ω(0)`` (small displacements; the first
  Newton iterate of the nonlinear problem).

The returned :class:`Prestress` holds ``u`` and the tangent ``K_T(u)`` (material +
geometric stiffness − spin softening) that replaces ``K^uu`` in the Eq. (2) blocks of the
spinning blade (:func:`femrub.fem.discretisation.assemble`, ``prestress=``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from . import centrifugal as cf
from .forms import lame_parameters
from .linalg import sparse_lu
from .quadrature import gradient_operator

__all__ = ["METHODS", "Prestress", "PrestressForms", "centrifugal_prestress"]

METHODS = ("linear", "nonlinear")


@dataclass(frozen=True)
class Prestress:
    """Static state of a blade spinning at ``omega`` (rad/s).

    Attributes
    ----------
    omega : rotation speed Ω (rad/s).
    method : ``"linear"`` or ``"nonlinear"``.
    u : (n_u_all,) static displacement on every dof of the basis (m).
    K : (n_free, n_free) prestressed tangent stiffness on the free dofs ``free_u``.
    free_u : free displacement dofs (full numbering).
    iterations : Newton iterations spent (1 for linear).
    residual : final ``‖r(u)‖ / ‖f_Ω(0)‖`` on the free dofs.
    increments : load increments used by the continuation.
    rejected : load increments rejected.
    """

    omega: float
    method: str
    u: np.ndarray
    K: sp.csr_matrix
    free_u: np.ndarray
    iterations: int
    residual: float
    increments: int = 1
    rejected: int = 0

    def displacement_at(self, dofs) -> np.ndarray:
        """Static displacement at the full-numbering ``dofs`` (any shape)."""
        return self.u[np.asarray(dofs, dtype=int)]

    def growth(self, points) -> np.ndarray:
        """Outward radial growth ``n_i · ū_i`` (m) of :class:`ContactPoints` ``points`` (at
        each contact's node or the mean over its patch, as the contacts act)."""
        return points.normal_displacement(self.u)


class PrestressForms:
    """The forms of :mod:`femrub.fem.centrifugal` on one basis, with fixed parameters: the
    load by its scikit-fem form, the internal force and the tangent through the compiled
    kernels of :class:`~femrub.fem.quadrature.GradientOperator` (equal to the forms of
    :mod:`femrub.fem.centrifugal` to round-off, several times cheaper on a blade mesh).

    Parameters
    ----------
    basis : the vector scikit-fem basis of the displacement (3D).
    material : :class:`~femrub.fem.material.Material` (``rho``, ``young``, ``poisson``).
    axis : the rotation axis (:func:`femrub.fem.centrifugal.axis_params`).
    linear : small-displacement kinematics (``E = ε(u)``) instead of Green–Lagrange.
    """

    def __init__(self, basis, material, axis, linear: bool):
        self.lam, self.mu = lame_parameters(material.young, material.poisson, 3)
        self.basis, self.axis, self.linear = basis, axis, linear
        self.rho = float(material.rho)
        self._op = None

    @property
    def op(self):
        """The :class:`~femrub.fem.quadrature.GradientOperator` of the basis (built once)."""
        if self._op is None:
            self._op = gradient_operator(self.basis, self.lam, self.mu, linear=self.linear)
        return self._op

    def force(self, u, omega2):
        return cf.centrifugal_force(self.basis, u, self.rho * omega2, self.axis)

    def internal(self, u):
        return self.op.internal_force(u)

    def tangent(self, u, MP, omega2):
        K = self.op.assemble(self.op.moduli(self.op.gradients(u)))
        return K if MP is None else K - omega2 * MP


def _free(basis, fixed) -> np.ndarray:
    mask = np.ones(basis.N, dtype=bool)
    mask[np.asarray(fixed, dtype=int)] = False
    return np.flatnonzero(mask)


def _sub(A, free):
    return sp.csr_matrix(A)[free][:, free].tocsr()


def centrifugal_prestress(
    disc,
    material,
    omega: float,
    method: str = "nonlinear",
    *,
    tol: float = 1e-10,
    max_iter: int = 25,
    max_increments: int = 16,
    start: Prestress | None = None,
    log=None,
) -> Prestress:
    """Static prestress of ``disc`` spinning at ``omega`` about its blade's axis.

    Parameters
    ----------
    disc : 3D :class:`~femrub.fem.discretisation.Discretisation` (clamped root).
    material : :class:`~femrub.fem.material.Material` (``rho``, ``young``, ``poisson``).
    omega : rotation speed Ω (rad/s).
    method : ``"nonlinear"`` (Newton, total Lagrangian) or ``"linear"``.
    tol : Newton tolerance on ``‖r‖ / ‖f_Ω(0)‖``.
    max_iter : Newton iterations per load increment.
    max_increments : most load increments the continuation may use.
    start : a nonlinear prestress of the same ``disc`` at another speed Ω₀: the continuation
        in Ω² starts from its state (a warm start along a list of speeds) instead of from
        rest; the equilibrium reached is the same to ``tol``.
    log : optional callable for progress messages.

    Raises
    ------
    ValueError
        Unknown method, a 1D discretisation, or Newton failing with ``max_increments``.
    """
    if method not in METHODS:
        raise ValueError(f"unknown prestress method {method!r}; use one of {', '.join(METHODS)}")
    if disc.dim != 3:
        raise ValueError("centrifugal prestress needs a 3D blade (the bar has no rotation axis)")
    omega = float(omega)
    if not math.isfinite(omega):
        raise ValueError(f"rotation speed must be finite, got {omega!r}")
    basis = disc.basis_u
    free = _free(basis, disc.fixed_u)
    forms = PrestressForms(basis, material, disc.blade.axis, method == "linear")
    w2 = omega * omega
    u = np.zeros(basis.N)
    if w2 == 0.0:
        return Prestress(0.0, method, u, _sub(forms.tangent(u, None, 0.0), free), free, 0, 0.0, 0)
    MP = cf.spin_mass(basis, forms.rho, disc.blade.axis)
    scale = float(np.linalg.norm(forms.force(u, w2)[free])) or 1.0
    if method == "linear":
        K0 = _sub(forms.tangent(u, MP, w2), free)
        u[free] = sparse_lu(K0, symmetric=True, what="K − Ω² M_P").solve(forms.force(u, w2)[free])
        res = _residual(forms, u, w2, free) / scale
        return Prestress(omega, method, u, _sub(forms.tangent(u, MP, w2), free), free, 1, res)
    w2_0 = 0.0
    if start is not None and start.method == method and start.u.shape == u.shape:
        w2_0, u = float(start.omega) ** 2, start.u.copy()
    smallest = 0.5 ** math.floor(math.log2(max_increments))
    done, step, iters, n_inc, rejected = 0.0, 1.0, 0, 0, 0
    rate = np.zeros_like(u)  # du / d(load fraction) of the last increment: the predictor
    while done < 1.0:
        step = min(step, 1.0 - done)
        load = w2_0 + (w2 - w2_0) * (done + step)
        trial, k, ok, theta = _newton(
            forms, u + step * rate, MP, load, free, scale, tol, max_iter, log
        )
        iters += k
        if ok:
            rate = (trial - u) / step
            u, done, n_inc = trial, done + step, n_inc + 1
            if log:
                since = f" from {math.sqrt(w2_0):g} rad/s" if w2_0 else ""
                log(f"prestress: {100 * done:.0f} % of Ω²{since} in {k} Newton iterations")
            step *= 2.0
            continue
        if step <= smallest:
            raise ValueError(
                f"Newton on the centrifugal prestress at Ω = {omega:g} rad/s did not "
                f"converge with {max_increments} load increments; use "
                "loads.centrifugal = 'off' or 'linear', or a lower rotation speed"
            )
        rejected += 1
        step = max(step * 0.5 ** _halvings(theta), smallest)
        if log:
            why = f"first contraction {theta:.3g}" if theta is not None else "diverging"
            log(f"prestress: load increment rejected ({why}); next {step:.4g} of Ω²")
    res = _residual(forms, u, w2, free) / scale
    KT = _sub(forms.tangent(u, MP, w2), free)
    return Prestress(omega, method, u, KT, free, iters, res, n_inc, rejected)


def _residual(forms, u, w2, free) -> float:
    return float(np.linalg.norm((forms.internal(u) - forms.force(u, w2))[free]))


def _halvings(theta: float | None) -> int:
    """How many times to halve a rejected load fraction whose first Newton contraction was
    ``theta``: until ``theta``, taken proportional to the fraction (as the Kantorovich
    quantity ``ω ‖Δu₀‖ / 2`` of a start from rest is), falls below 1, where Newton contracts;
    once when ``theta`` is unknown (a later iteration diverged).

    The contraction grows faster than the fraction where it is large (Rotor 37 at
    1344 rad/s from rest: 0.25, 0.49, 1.0, 2.2 and 5.2 at 1/16 ... 1 of Ω²), so the
    increment chosen contracts with a margin.
    """
    if theta is None or not math.isfinite(theta):
        return 1
    return max(1, math.ceil(math.log2(theta)))


def _newton(forms, u, MP, w2, free, scale, tol, max_iter, log=None):
    """Newton iterations at load ``w2``; returns ``(u, iterations, converged, growth)``.

    Converged when ``‖r‖ <= tol ‖f_Ω(0)‖`` or when the energy norm of the correction
    ``e_k = |Δu_k · r_k|`` has fallen below ``1e-18`` of the first one (the residual of a
    thin blade stiffened by its membrane stress has a round-off floor well above ``tol``,
    and grows in the first iterations of a converging Newton, so it is no merit function).
    Gives up when ``e_k`` grows above ``e_0`` (the continuation then takes a smaller load
    increment); ``growth`` is then the first contraction ``Θ₀ = (e_1 / e_0)^½`` when the
    second iteration gave up (a diverging increment stops there), else ``None``.
    """
    e0 = None
    for k in range(max_iter):
        r = (forms.internal(u) - forms.force(u, w2))[free]
        norm = float(np.linalg.norm(r)) / scale
        if log:
            log(f"prestress: Newton iteration {k}, relative residual {norm:.2e}")
        if not math.isfinite(norm):
            return u, k + 1, False, None
        if norm <= tol:
            return u, k, True, None
        KT = _sub(forms.tangent(u, MP, w2), free)
        du = sparse_lu(KT, symmetric=True, what="prestressed tangent").solve(r)
        e = abs(float(du @ r))
        if e0 is None:
            e0 = e
        elif not e <= e0:
            return u, k + 1, False, math.sqrt(e / e0) if k == 1 else None
        u[free] -= du
        if e <= 1e-18 * e0:
            return u, k + 1, True, None
    return u, max_iter, False, None
