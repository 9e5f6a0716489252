"""Floquet multipliers of a periodic orbit and the bifurcations between branch points.

A perturbation ``δX0`` of the orbit's start returns after one period as ``M δX0``, with
``M = ∂Φ_T/∂X0`` the monodromy matrix (:mod:`femrub.periodic.shooting`). Its eigenvalues,
the Floquet multipliers ``μ_i``, say how perturbations grow per period (Floquet theory; for
a linear system ``A Ẋ = B X + F(t)``, ``μ_i = e^{λ_i T}`` with ``λ_i`` the eigenvalues of
``A⁻¹ B``). The orbit is asymptotically stable when every multiplier lies inside the unit
circle::

    max_i |μ_i| < 1                                                   (1)

Along a branch ``(X0(s), p(s))`` of pseudo-arclength ``s`` the orbit loses or gains
stability where multipliers cross the unit circle:

* **fold** (saddle-node, limit point): a real multiplier crosses +1 and the branch turns
  back in the parameter: ``dp/ds`` and ``det(M − I)`` both change sign (a turn without the
  crossing is the map's jumps, not a fold, and is not flagged);
* **period doubling** (flip): a real multiplier crosses −1;
* **Neimark–Sacker** (secondary Hopf, torus): a complex pair crosses ``|μ| = 1``;
* **branch point**: a real multiplier crosses +1 without a fold; the determinant of the
  bordered Jacobian ``[R_X, R_p; τᵀ]`` changes sign (Seydel, *Practical Bifurcation and
  Stability Analysis*, 2010, Sec. 5.4);
* **stability change**: Eq. (1) changes between the two points and none of the above
  explains it: a multiplier jumped across the unit circle, as at a nonsmooth transition
  (an impact appearing at grazing, a contact set changing).

:func:`special_point` names the one a step of the branch passed (between two points).
"""

from __future__ import annotations

import numpy as np

__all__ = ["SPECIAL", "multipliers", "special_point", "stable"]

#: the names of the special points in ``branch.csv`` (column ``special``)
SPECIAL = ("fold", "period-doubling", "neimark-sacker", "branch-point", "stability-change")
#: relative imaginary part below which a multiplier counts as real
REAL = 1e-8


def multipliers(M: np.ndarray) -> np.ndarray:
    """The Floquet multipliers (eigenvalues of ``M``), largest modulus first."""
    mu = np.linalg.eigvals(M)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def stable(mu: np.ndarray) -> bool:
    """Eq. (1)."""
    return bool(mu.size == 0 or np.max(np.abs(mu)) < 1.0)


def _counts(mu: np.ndarray) -> tuple[int, int]:
    """Real multipliers below −1, complex multipliers outside the unit circle."""
    real = np.abs(mu.imag) <= REAL * np.maximum(np.abs(mu), 1e-300)
    flip = int(np.sum(real & (mu.real < -1.0)))
    torus = int(np.sum(~real & (np.abs(mu) > 1.0)))
    return flip, torus


def _real_crossing(before: dict, after: dict) -> bool:
    """An odd number of real multipliers crossed +1: ``det(M − I) = Π (μ_i − 1)`` changed
    sign (Seydel 2010, Sec. 5.4)."""
    sign = [np.sign(np.prod(d["mu"] - 1.0).real) for d in (before, after)]
    return bool(sign[0] * sign[1] < 0)


def special_point(before: dict, after: dict) -> str:
    """What the branch passed between two points (``""``: nothing).

    ``before``/``after`` hold ``mu`` (multipliers), ``dp`` (the tangent's parameter
    component ``dp/ds``) and ``det_sign`` (the sign of the bordered Jacobian's
    determinant).
    """
    if np.sign(before["dp"]) * np.sign(after["dp"]) < 0 and _real_crossing(before, after):
        return "fold"
    (f0, t0), (f1, t1) = _counts(before["mu"]), _counts(after["mu"])
    if f0 != f1:
        return "period-doubling"
    if t0 != t1:
        return "neimark-sacker"
    if before["det_sign"] * after["det_sign"] < 0:
        return "branch-point"
    if stable(before["mu"]) != stable(after["mu"]):
        return "stability-change"
    return ""
