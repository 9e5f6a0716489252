"""First-order thermoelastic Craig–Bampton reduction (paper Sec. 2, Eqs. 10–15).

:class:`ThermoelasticCraigBampton` takes a full :class:`~femrub.model.first_order.FirstOrderModel` of the
form of Eq. (9) (1D or 3D, sparse, any number of contacts) and builds

* the right basis ``R`` of Eq. (13), ``X ≈ R X̄``: the boundary dofs ``u_b, v_b, θ_b``
  (Eq. 10, found from the contact data) kept as physical dofs with their static shapes
  ``Ψ = −B_ii⁻¹ B_ib`` (Eq. 11), ``n_uv`` first-order mechanical shapes (clamped modes
  ``φ_j`` used as displacement and as velocity shapes) and ``n_θ`` thermal modes ``χ_k``
  with the coupling correction ``Φ^uθ = −K_ii⁻¹ K^uθ_ii χ`` (after Eq. 11);
* the left basis ``R̃`` of Eq. (14), chosen by ``projection``:

  - ``"petrov-galerkin"`` (default): the boundary equations are kept as in the full model
    (unit left vectors on ``u_b, v_b, θ_b``: mass and heat capacity stay lumped on the
    contact dofs) and the interior equations are projected on the left eigenvectors of the
    clamped uncoupled problem (``M_ii φ_j`` for the kinematic rows, ``φ_j`` for the momentum
    rows, ``χ_k`` with the adjoint correction ``C^θu_iiᵀ χ_k`` for the heat rows);
  - ``"galerkin"``: ``R̃ = R``;
  - ``"adjoint"``: the Craig–Bampton basis of the adjoint problem, static shapes
    ``−B_ii⁻ᵀ B_biᵀ`` and the same left modes (two-sided moment matching at s = 0);

  ``docs/reduction.md`` derives them and compares them on the paper case;
* the reduced model ``Ā = R̃ᵀ A R``, ``B̄ = R̃ᵀ B R`` (Eqs. 14–15), a
  :class:`~femrub.model.first_order.FirstOrderModel` that every stepper runs unchanged.

The reduced state is ordered in the three blocks the steppers expect (the paper's "split
arbitrarily q^uv", after Eq. 15)::

    X̄ = [u_b, q_u | v_b, q_v | θ_b, q_θ],   Layout(n_b + n_qu, n_b + n_qv, n_θb + n_θ)

``n_uv`` counts real first-order mechanical shapes as the paper does (``2 n_i`` for the full
interior): mode ``φ_j`` gives a displacement shape (in ``q_u``) and a velocity shape (in
``q_v``). ``n_qu = ⌊n_uv/2⌋`` and ``n_qv = ⌈n_uv/2⌉``: an odd ``n_uv`` adds mode
``(n_uv + 1)/2`` as a velocity shape only. With no displacement partner that coordinate is
inert for every projection (its momentum row sees no force), so an odd ``n_uv`` behaves as
``n_uv − 1``; as a displacement shape only it would instead stiffen the boundary row of the
Petrov–Galerkin model (a frozen interior displacement with no inertia).
"""

from __future__ import annotations

import time
import warnings

import numpy as np
import scipy.sparse as sp

from ..fem.eigen import lowest_modes, normalise_columns
from ..model.first_order import FirstOrderModel, Layout, LoadTerm
from .blocks import InteriorSolver, contact_boundary, split_blocks

__all__ = ["PROJECTIONS", "ThermoelasticCraigBampton", "craig_bampton_thermal"]

PROJECTIONS = ("petrov-galerkin", "galerkin", "adjoint")


class ThermoelasticCraigBampton:
    """Reductor of a full first-order thermoelastic model (paper Sec. 2).

    Parameters
    ----------
    model : full :class:`~femrub.model.first_order.FirstOrderModel` of the form of Eq. (9).
    n_uv : number of first-order mechanical shapes (``None``: all, ``2 n_i``).
    n_theta : number of thermal modes (``None``: all interior temperature dofs).
    projection : ``"petrov-galerkin"``, ``"galerkin"`` or ``"adjoint"`` (module docstring).
    boundary : optional ``{"u": positions in the u-block, "theta": positions in the θ-block}``;
        default: the contact dofs (:func:`~femrub.reduction.blocks.contact_boundary`).

    Attributes
    ----------
    R, left : (N, r) right and left bases (dense), rows in the full state order.
    layout : reduced :class:`~femrub.model.first_order.Layout`.
    omega2 : (n_qv,) clamped mechanical eigenvalues ω² (rad²/s²) of the shapes kept.
    mu : (n_θ,) clamped thermal eigenvalues (1/s) of ``K^θθ χ = μ C^θθ χ``.
    timings : seconds spent in the static shapes, the modes and the bases.
    """

    def __init__(
        self, model, n_uv=None, n_theta=None, *, projection="petrov-galerkin", boundary=None
    ):
        if projection not in PROJECTIONS:
            raise ValueError(f"unknown projection {projection!r}; use one of {PROJECTIONS}")
        if not isinstance(model, FirstOrderModel):
            raise TypeError("ThermoelasticCraigBampton needs a femrub.FirstOrderModel")
        self.fom, self.projection = model, projection
        blocks = split_blocks(model)
        L = model.layout
        nu, nt = L.n_u, L.n_t
        mb, tb = contact_boundary(model) if boundary is None else _given(boundary, nu, nt)
        mi, ti = np.setdiff1d(np.arange(nu), mb), np.setdiff1d(np.arange(nt), tb)
        n_uv = 2 * mi.size if n_uv is None else _count("n_uv", n_uv, 2 * mi.size)
        n_theta = ti.size if n_theta is None else _count("n_theta", n_theta, ti.size)
        self.n_uv, self.n_theta = n_uv, n_theta
        self.n_qu, self.n_qv = n_uv // 2, (n_uv + 1) // 2
        self.boundary = {"u": mb, "theta": tb}
        if sp.csr_matrix(blocks.M)[mb][:, mi].count_nonzero():
            warnings.warn(
                "the mass matrix couples the contact dofs to the interior; the paper's "
                "reduction assumes it lumped on the contacting dofs",
                stacklevel=2,
            )
        self.timings = {}
        t0 = time.perf_counter()
        solver = InteriorSolver(blocks, mi, ti)
        self._bnd = np.r_[mb, nu + mb, 2 * nu + tb].astype(int)
        self._int = np.r_[mi, nu + mi, 2 * nu + ti].astype(int)
        B = model.B.tocsr()
        B_ib = B[self._int][:, self._bnd].toarray()
        psi = solver.solve(-B_ib)  # Eq. (11)
        self.timings["static_shapes"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        self.omega2, phi = lowest_modes(solver.K, solver.M, self.n_qv, solver.solve_K)
        self.mu, chi = lowest_modes(solver.Ktt, solver.Ctt, n_theta, solver.solve_T)
        phi_ut = -solver.solve_K(solver.Kut @ chi)  # K_ii Φ^uθ = −K^uθ_ii Φ^θθ
        self.timings["modes"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        self._idx = (mb, mi, tb, ti)
        self.layout = Layout(mb.size + self.n_qu, mb.size + self.n_qv, tb.size + n_theta)
        self.R = self._assemble(psi, phi[:, : self.n_qu], phi, chi, phi_ut)
        if projection == "galerkin":
            self.left = self.R
        else:  # left (adjoint) modes; boundary columns: adjoint static shapes or unit vectors
            if projection == "adjoint":
                psi_l = solver.solve_transposed(-B[self._bnd][:, self._int].T.toarray())
            else:  # boundary equations kept as in the full model
                psi_l = np.zeros_like(psi)
            mphi = normalise_columns(solver.M @ phi[:, : self.n_qu])
            self.left = self._assemble(psi_l, mphi, phi, chi, solver.Ctu.T @ chi)
        self.timings["bases"] = time.perf_counter() - t0
        self._rom = None

    # -- bases -----------------------------------------------------------------------------
    def _assemble(self, psi, u_shapes, v_shapes, chi, chi_u) -> np.ndarray:
        """A basis in the full state order with the reduced column order of the layout."""
        mb, mi, tb, ti = self._idx
        nu, N, Lr = self.fom.layout.n_u, self.fom.n_dofs, self.layout
        nb = mb.size
        V = np.zeros((N, Lr.n))
        cu_b = np.arange(0, nb)
        cv_b = Lr.v.start + np.arange(nb)
        ct_b = Lr.t.start + np.arange(tb.size)
        for k, (rows, cols) in enumerate(
            [(mb, cu_b), (nu + mb, cv_b), (2 * nu + tb, ct_b)]
        ):  # boundary dofs kept (Eq. 12) with their static shapes (Eq. 11)
            V[rows, cols] = 1.0
            first = [0, nb, 2 * nb][k]
            V[self._int[:, None], cols[None, :]] = psi[:, first : first + cols.size]
        V[mi[:, None], np.arange(nb, nb + self.n_qu)[None, :]] = u_shapes
        V[(nu + mi)[:, None], (Lr.v.start + nb + np.arange(self.n_qv))[None, :]] = v_shapes
        cq_t = Lr.t.start + tb.size + np.arange(self.n_theta)
        V[(2 * nu + ti)[:, None], cq_t[None, :]] = chi
        V[mi[:, None], cq_t[None, :]] = chi_u
        return V

    def mechanical_basis(self) -> np.ndarray:
        """Second-order Craig–Bampton basis of the displacements: ``[[I, 0], [Ψ_uu, Φ]]``."""
        L, Lr = self.fom.layout, self.layout
        return self.R[L.u, Lr.u]

    def thermal_basis(self) -> np.ndarray:
        """Craig–Bampton basis of the temperatures: ``[[I, 0], [Ψ_θθ, Φ^θθ]]``."""
        L, Lr = self.fom.layout, self.layout
        return self.R[L.t, Lr.t]

    # -- reduction -------------------------------------------------------------------------
    def reduce(self) -> FirstOrderModel:
        """The reduced model of Eqs. (14)–(15) (built once, then cached)."""
        if self._rom is not None:
            return self._rom
        t0 = time.perf_counter()
        m, R, Lt = self.fom, self.R, self.left
        Ar = Lt.T @ np.asarray(m.A @ R)
        Br = Lt.T @ np.asarray(m.B @ R)
        loads = [
            LoadTerm(Lt.T @ t.vector, t.signal, power=R.T @ t.power, heat=t.heat, name=t.name)
            for t in m.loads
        ]
        contact = None if m.contact is None else m.contact.project(Lt, R)
        obs = {k: np.asarray(O @ R) for k, O in m.observations.items()}
        energy = None if m.energy is None else self._energy(Ar, Br)
        to_full = None if m.to_full is None else np.asarray(m.to_full @ R)
        self.timings["projection"] = time.perf_counter() - t0
        info = {
            "reduction": "thermoelastic Craig-Bampton (paper Sec. 2)",
            "projection": self.projection,
            "n_uv": self.n_uv,
            "n_theta": self.n_theta,
            "n_qu": self.n_qu,
            "n_qv": self.n_qv,
            "n_boundary_u": int(self.boundary["u"].size),
            "n_boundary_theta": int(self.boundary["theta"].size),
            "n_full": m.n_dofs,
            "n_reduced": self.layout.n,
            "timings": dict(self.timings),
            "full_info": dict(m.info),
        }
        self._rom = FirstOrderModel(
            A=sp.csc_matrix(Ar),
            B=sp.csc_matrix(Br),
            layout=self.layout,
            loads=loads,
            contact=contact,
            observations=obs,
            energy=energy,
            to_full=to_full,
            x0=self.restrict(m.x0),
            info=info,
        )
        return self._rom

    def _energy(self, Ar, Br):
        """Energy forms projected on ``R``; the thermal-stress power uses ``u̇``, not ``v``.

        The full model's thermal power ``vᵀ(−K^uθ θ)`` equals ``u̇ᵀ(−K^uθ θ)`` because
        ``u̇ = v``; a reduced model only keeps ``u̇_b = v_b`` (its interior ``u̇`` is the rate of
        ``R_u X̄``, which holds thermal-expansion shapes that ``v`` lacks), so the power of the
        thermal stresses on the reduced displacement is ``(R_u Ā⁻¹ B̄ X̄)ᵀ(−K^uθ)(R_θ X̄)``.
        """
        m, R = self.fom, self.R
        forms = m.energy.project(R)
        L = m.layout
        if L.n_t:
            P = sp.csr_matrix(m.energy.Pth)
            P_u = sp.vstack([P[L.v], P[L.u], P[L.t]], format="csr")  # v-rows moved to u-rows
            rate = np.linalg.solve(Ar, Br)  # Ẋ̄ = Ā⁻¹ B̄ X̄ without loads and impulses
            forms.Pth = sp.csr_matrix(rate.T @ (R.T @ np.asarray(P_u @ R)))
        return forms

    def reconstruct(self, Xr: np.ndarray) -> np.ndarray:
        """Full state ``R X̄`` of a reduced state (r,) or of the rows of an (m, r) array."""
        Xr = np.asarray(Xr, dtype=float)
        if Xr.shape[-1] != self.layout.n:
            raise ValueError(f"a reduced state has {self.layout.n} entries, got {Xr.shape}")
        return self.R @ Xr if Xr.ndim == 1 else Xr @ self.R.T

    def restrict(self, X: np.ndarray) -> np.ndarray:
        """Least-squares reduced state of a full state (exact when ``X`` is in span R)."""
        X = np.asarray(X, dtype=float)
        if not np.any(X):
            return np.zeros(X.shape[:-1] + (self.layout.n,))
        sol = np.linalg.lstsq(self.R, X.T if X.ndim == 2 else X, rcond=None)[0]
        return sol.T if X.ndim == 2 else sol


def craig_bampton_thermal(model, n_uv=None, n_theta=None, **kw):
    """Reduce ``model``; return ``(reduced model, reductor)`` (``reductor.reconstruct``)."""
    red = ThermoelasticCraigBampton(model, n_uv, n_theta, **kw)
    return red.reduce(), red


def _count(name, value, most) -> int:
    if not (isinstance(value, (int, np.integer)) and 0 <= value <= most):
        raise ValueError(f"{name} must be an integer in [0, {most}], got {value!r}")
    return int(value)


def _given(boundary, nu, nt):
    mb = np.unique(np.asarray(boundary.get("u", []), dtype=int))
    tb = np.unique(np.asarray(boundary.get("theta", []), dtype=int))
    if mb.size and (mb.min() < 0 or mb.max() >= nu) or tb.size and (tb.min() < 0 or tb.max() >= nt):
        raise ValueError("boundary dofs out of range of the u- or θ-block")
    return mb, tb
