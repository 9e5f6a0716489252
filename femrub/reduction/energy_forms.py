"""Energy forms of a reduced thermoelastic model: the energy its own dynamics conserves.

The reduced model's balance (``docs/reduction.md`` section 8) needs the kinetic and elastic
forms on the displacement the reduced kinematics integrates, the thermal-stress work on
``u̇`` and the damping power along the homogeneous reduced dynamics
(:func:`reduced_energy`); a smaller size cut out of a larger projected model only rebuilds
the forms that rest on ``Ā⁻¹ B̄`` (:func:`energy_rates`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp
from scipy.linalg import eigh

from ..fem.linalg import project

__all__ = ["elastic_basis", "elastic_change", "energy_rates", "reduced_energy"]


def reduced_energy(fom, n_boundary_u: int, R, Ar, Br, layout):
    """Energy forms of the reduced model: the energy its own dynamics conserves.

    * kinetic ``½ (R_v X̄)ᵀ M (R_v X̄)``, as projected;
    * elastic ``½ (R_z X̄)ᵀ K (R_z X̄)`` on the displacement the reduced kinematics
      integrates: ``R_z = R`` except that the displacement part of each boundary-velocity
      static shape, ``Γ = −K_ii⁻¹ C_ib`` (a damped model's quasi-static response to a
      boundary velocity), is replaced by its M-orthogonal projection on the kept modes
      ``Φ (Φᵀ M_ii Φ)⁻¹ Φᵀ M_ii Γ``
      (the interior kinematic rows, projected on ``M_ii Φ``, only integrate that part);
    * damping power: the rate of that energy along the homogeneous reduced dynamics,
      ``P_d = sym(Q Ā⁻¹ B̄)`` on the mechanical coordinates (``Q`` kinetic + elastic);
      with a lumped boundary mass and ``C = a M + b K`` this is negative semi-definite,
      a positive part is energy the reduction creates, reported as the largest relative growth
      rate ``max λ: P_d x = λ Q x`` (``info["energy_growth_rate"]``, 1/s);
    * thermal-stress work on ``u̇``, not ``v``: the full model's power ``vᵀ(−K^uθ θ)``
      equals ``u̇ᵀ(−K^uθ θ)`` because ``u̇ = v``; a reduced model only keeps
      ``u̇_b = v_b`` (its interior ``u̇`` is the rate of ``R_u X̄``, which holds
      thermal-expansion shapes that ``v`` lacks), so the power of the thermal stresses is
      ``(R_u Ā⁻¹ B̄ X̄)ᵀ(−K^uθ)(R_θ X̄)`` (``Pth``) and the work over a step, impulses
      included, ``ΔW_th = (R_u ΔX̄)ᵀ(−K^uθ)(R_θ X̄_m)`` (``Wth``: a heat impulse moves
      the expansion shapes at once; docs/reduction.md section 8).
    """
    m = fom
    L = m.layout
    parts = [0, L.u.stop, L.v.stop, L.n]  # the u, v, θ rows of the bases
    change = elastic_change(fom, n_boundary_u, R, layout)  # R_z = R but on these rows
    # forms rebuilt below are not projected here: the damping power (``energy_rates``, when
    # damped) and the elastic form on ``R_z``
    zero = sp.csr_matrix((L.n, L.n))
    damped = sp.csr_matrix(m.energy.Pd).count_nonzero() > 0
    given = dataclasses.replace(
        m.energy, Pd=zero if damped else m.energy.Pd, Qe=m.energy.Qe if change is None else zero
    )
    forms = given.project(R, parts)
    if change is not None:  # else the projected Qe is already the elastic energy's
        Qe = _projected_on_change(R, m.energy.Qe, parts, L.u, change, right_too=True)
        forms.Qe = sp.csr_matrix(Qe)
    if L.n_t:
        P = sp.csr_matrix(m.energy.Pth)
        P_u = sp.vstack([P[L.v], P[L.u], P[L.t]], format="csr")  # v-rows moved to u-rows
        W = (
            project(R, P_u, R, parts=parts)
            if change is None
            else _projected_on_change(R, P_u, parts, L.u, change, right_too=False)
        )
        forms.Wth = sp.csr_matrix(np.asarray(W))
    return energy_rates(fom, forms, Ar, Br, layout)


def energy_rates(fom, forms, Ar, Br, layout):
    """``(forms, growth rate)``: the forms of :func:`reduced_energy` built on ``Ā⁻¹ B̄`` (``Pth``,
    ``Pd``, the energy growth rate) from the projected ``Qk``, ``Qe`` and ``Wth``."""
    L = fom.layout
    damped = sp.csr_matrix(fom.energy.Pd).count_nonzero() > 0
    if L.n_t or damped:  # Ẋ̄ = Ā⁻¹ B̄ X̄ without loads and impulses
        rate = np.linalg.solve(Ar, Br)
    if L.n_t:
        forms.Pth = sp.csr_matrix(rate.T @ forms.Wth.toarray())
    growth = 0.0
    if damped:
        mech = np.r_[np.arange(layout.n_u), layout.v.start + np.arange(layout.n_v)]
        Q = (forms.Qk + forms.Qe).toarray()[np.ix_(mech, mech)]
        D = Q @ rate[np.ix_(mech, mech)]
        D = 0.5 * (D + D.T)
        Pd = np.zeros((layout.n, layout.n))
        Pd[np.ix_(mech, mech)] = D
        forms.Pd = sp.csr_matrix(Pd)
        # fastest relative growth d ln E / dt the damped reduced dynamics allows (1/s)
        growth = float(eigh(D, Q, eigvals_only=True)[-1])
    return forms, growth


def elastic_basis(fom, n_boundary_u: int, R, layout):
    """``R`` with the boundary-velocity static shapes' displacement projected on the kept
    modes (see :func:`reduced_energy`): ``R`` itself when they have none, else a copy."""
    change = elastic_change(fom, n_boundary_u, R, layout)
    if change is None:
        return R
    cols, new = change
    Rz = R.copy()
    Rz[fom.layout.u, cols] = new
    return Rz


def elastic_change(fom, n_boundary_u: int, R, layout):
    """Where :func:`elastic_basis` differs from ``R``: ``(cols, new)``, the displacement rows
    of the boundary-velocity columns ``cols`` (a slice) of ``R_z`` (``n_u × n_b``:
    ``Φ (Φᵀ M Φ)⁻¹ Φᵀ M Γ``), or ``None`` (``R_z = R``)."""
    L, nb = fom.layout, n_boundary_u
    n_qu = layout.n_u - nb
    cols = slice(layout.v.start, layout.v.start + nb)
    G = R[L.u, cols]
    if not np.any(G):
        return None
    Phi = R[L.u, nb : nb + n_qu]
    MPhi = fom.blocks.M @ Phi
    return cols, Phi @ np.linalg.solve(Phi.T @ MPhi, MPhi.T @ G)


def _projected_on_change(R, Q, parts, rows, change, right_too: bool) -> np.ndarray:
    """``R_zᵀ Q R_z`` (``right_too``) or ``R_zᵀ Q R`` without a copy of ``R``: ``R_z = R + E``
    with ``E`` zero but on the rows ``rows`` of the columns ``cols`` (``change = (cols,
    new)``, ``E[rows, cols] = new − R[rows, cols]``), so the projection on ``R`` plus the
    terms of ``E``: ``Eᵀ Q R`` (rows ``cols``), ``Rᵀ Q E`` and ``Eᵀ Q E`` (columns
    ``cols``)."""
    cols, new = change
    E = np.zeros((R.shape[0], new.shape[1]))
    E[rows] = new - R[rows, cols]
    Q = sp.csr_matrix(Q)
    out = project(R, Q, R, parts=parts)
    out[cols, :] += np.asarray(Q.T @ E).T @ R
    if right_too:
        QE = np.asarray(Q @ E)
        out[:, cols] += R.T @ QE
        out[cols, cols] += E.T @ QE
    return out
