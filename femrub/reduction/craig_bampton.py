"""First-order thermoelastic Craig–Bampton reduction (paper Sec. 2, Eqs. 10–15).

:class:`ThermoelasticCraigBampton` takes a full
:class:`~femrub.model.first_order.FirstOrderModel` of the form of Eq. (9) (1D or 3D, sparse,
any number of contacts) and builds

* the right basis ``R`` of Eq. (13), ``X ≈ R X̄``: the boundary dofs ``u_b, v_b, θ_b``
  (Eq. 10, ``model.boundary``: the dofs the contacts act on) kept as physical dofs with
  their static shapes ``Ψ = −B_ii⁻¹ B_ib`` (Eq. 11), ``n_uv`` first-order mechanical shapes
  (clamped modes ``φ_j`` used as displacement and as velocity shapes) and ``n_θ`` thermal
  modes ``χ_k`` with the coupling correction ``Φ^uθ = −K_ii⁻¹ K^uθ_ii χ`` (after Eq. 11);
* the left basis ``R̃`` of Eq. (14), chosen by ``projection`` (derived and compared in
  ``docs/reduction.md``):

  - ``"petrov-galerkin"``: the boundary equations kept as in the full model (unit left
    vectors on ``u_b, v_b, θ_b``), the interior ones projected on the left eigenvectors of
    the clamped uncoupled problem (``M_ii φ_j``, ``φ_j``, ``χ_k`` with the adjoint correction
    ``C^θu_iiᵀ χ_k``);
  - ``"static-mass"`` (the scenes' default): as ``"petrov-galerkin"``, but the boundary
    velocities move the interior with their displacement static shapes
    (``v_i = Ψ_uu v_b + Φ q_v``) and their momentum rows are projected on them, so the contact
    dofs carry the Craig–Bampton mass ``m_b + Ψ_uuᵀ M_ii Ψ_uu`` (``docs/reduction.md`` §10);
  - ``"galerkin"``: ``R̃ = R``;
  - ``"second-order"``: the classical, symmetric second-order Craig–Bampton model of the
    mechanics (Galerkin, boundary velocity shapes equal to the displacement ones), whose
    impulses converge fastest with the number of modes (``docs/reduction.md`` §8);
  - ``"adjoint"``: the Craig–Bampton basis of the adjoint problem, static shapes
    ``−B_ii⁻ᵀ B_biᵀ`` and the same left modes (two-sided moment matching at s = 0);

* the reduced model ``Ā = R̃ᵀ A R``, ``B̄ = R̃ᵀ B R`` (Eqs. 14–15), a
  :class:`~femrub.model.first_order.FirstOrderModel` that every stepper runs unchanged.

The reductor computes the bases once for the largest sizes it is given; ``reduce(n_uv,
n_theta)`` projects on their leading shapes, so one reductor yields the reduced models of
every smaller size (``reconstruct`` and ``restrict`` take the same sizes).

The reduced state is ordered in the three blocks the steppers expect (the paper's "split
arbitrarily q^uv", after Eq. 15)::

    X̄ = [u_b, q_u | v_b, q_v | θ_b, q_θ],   Layout(n_b + n_qu, n_b + n_qv, n_θb + n_θ)

``n_uv`` counts real first-order mechanical shapes as the paper does (``2 n_i`` for the full
interior): mode ``φ_j`` gives a displacement shape (in ``q_u``) and a velocity shape (in
``q_v``); ``n_qu = ⌊n_uv/2⌋``, ``n_qv = ⌈n_uv/2⌉`` (an odd ``n_uv``: docs/reduction.md).
"""

from __future__ import annotations

import copy
import time
import warnings

import numpy as np
import scipy.sparse as sp

from .. import progress
from ..fem.eigen import lowest_modes, normalise_columns, orient_columns
from ..model.first_order import FirstOrderModel, Layout
from .basis import assemble_basis, left_static_shapes, velocity_static_shapes
from .boundary_coordinates import boundary_coordinates, boundary_dofs
from .interior import InteriorSolver, condensed_solve
from .operators import left_projected, left_sliced, right_projected, sliced
from .thermal_inputs import input_basis, input_distributions
from .truncation import columns_of

__all__ = ["PROJECTIONS", "ThermoelasticCraigBampton", "craig_bampton_thermal"]

PROJECTIONS = ("petrov-galerkin", "static-mass", "galerkin", "adjoint", "second-order")
#: Relative residual of the clamped modes (``lowest_modes``' ``tol``): a basis, not results;
#: modes within ~1e-11 of those at 1e-12, one restart cycle fewer (docs/performance.md §8).
MODE_TOL = 1e-10
#: Thermal reductions: the paper's boundary temperature dofs, or one input distribution each.
THERMAL = ("inputs", "boundary")


def _check_arguments(fom, projection: str, thermal: str, boundary):
    """Refuse what :class:`ThermoelasticCraigBampton` cannot reduce; the contact boundary
    (``boundary``, else the model's)."""
    if projection not in PROJECTIONS:
        raise ValueError(f"unknown projection {projection!r}; use one of {PROJECTIONS}")
    if thermal not in THERMAL:
        raise ValueError(f"unknown thermal reduction {thermal!r}; use one of {THERMAL}")
    if not isinstance(fom, FirstOrderModel):
        raise TypeError("ThermoelasticCraigBampton needs a femrub.FirstOrderModel")
    if fom.blocks is None:
        raise ValueError(
            "model.blocks is None: the model is already reduced (a full model of Eq. (9) "
            "carries its blocks); reduce the full model"
        )
    if boundary is None and fom.boundary is None:
        raise ValueError("the model has no contact boundary (model.boundary is None)")
    return fom.boundary if boundary is None else boundary


class ThermoelasticCraigBampton:
    """Reductor of a full first-order thermoelastic model (paper Sec. 2).

    The expensive work is done once, in the constructor, for the largest sizes: the LU
    factorisations of ``K_ii`` and ``K^θθ_ii``, the static shapes (Eq. 11), the clamped modes
    and the right and left bases (Eqs. 13–14). :meth:`reduce` then builds a reduced model of
    any sizes up to those from the leading columns of each block of the bases (pyMOR's
    ``reduce(dims)``): the truncated bases are those a reductor built with the smaller sizes
    computes (to round-off; to ARPACK's tolerance above ``DENSE_EIGEN_BELOW`` interior dofs),
    so nothing is factorised or solved again.

    Parameters
    ----------
    fom : full :class:`~femrub.model.first_order.FirstOrderModel` of the form of Eq. (9),
        carrying its Eq. (2) matrices (``fom.blocks``) and contact boundary
        (``fom.boundary``), as :func:`~femrub.model.build.first_order_model` builds it.
    max_n_uv : largest number of first-order mechanical shapes (``None``: all, ``2 n_i``).
    max_n_theta : largest number of thermal modes (``None``: all interior temperature dofs).
    projection : ``"petrov-galerkin"``, ``"static-mass"``, ``"galerkin"``, ``"adjoint"`` or
        ``"second-order"``
        (module docstring).
    boundary : optional ``{"u": positions in the u-block, "theta": positions in the θ-block}``
        overriding ``fom.boundary``.
    thermal : ``"boundary"`` (the paper's Eq. 10: every heated temperature dof is a boundary
        dof with its static shape, interior on clamped thermal modes, projected like the
        mechanics) or ``"inputs"`` (no temperature dof is kept: the thermal basis of
        :func:`~femrub.reduction.thermal_inputs.input_basis`, ``2 m + 1`` input shapes for
        ``m`` heat distributions plus ``max_n_theta`` modes of the whole blade, Galerkin
        projection of the heat equation; docs/reduction.md §8).
    keep_solver : keep the interior factorisations for later solves (``solver``); ``False``
        releases them before the dense bases are allocated (lower peak memory).
    stiffness : an :class:`~femrub.reduction.interior.InteriorStiffness` of this model's ``K_ii``
        (its modal damping's), used instead of a new factorisation (checked entry for entry).

    Attributes
    ----------
    n_uv, n_theta : the largest sizes (``max_n_uv``, ``max_n_theta`` resolved).
    n_qu, n_qv : displacement and velocity shapes of ``n_uv`` (``⌊n_uv/2⌋``, ``⌈n_uv/2⌉``).
    R, left : (N, r) right and left bases (dense) of the largest sizes, rows in the full state
        order, columns in the order of ``layout``.
    layout : reduced :class:`~femrub.model.first_order.Layout` of the largest sizes.
    boundary : ``{"u": ..., "theta": ...}`` boundary dofs used (Eq. 10).
    omega2 : (n_qv,) clamped mechanical eigenvalues ω² (rad²/s²) of the shapes kept.
    mu : (n_theta,) clamped thermal eigenvalues (1/s) of ``K^θθ χ = μ C^θθ χ``.
    solver : the :class:`~femrub.reduction.interior.InteriorSolver` (factorisations of ``K_ii``,
        ``K^θθ_ii``), kept for further solves (the full model's modes, ``condensed_solve``);
        :func:`~femrub.reduction.sizes.reduce_model` releases it once the sizes are chosen.
    timings : seconds of the static shapes, modes, bases (projection: the model's ``info``).
    """

    def __init__(
        self,
        fom,
        max_n_uv=None,
        max_n_theta=None,
        *,
        projection="petrov-galerkin",
        boundary=None,
        thermal="boundary",
        keep_solver=True,
        stiffness=None,
    ):
        given = _check_arguments(fom, projection, thermal, boundary)
        self.thermal = thermal
        self.fom, self.projection = fom, projection
        self._signature = (fom.layout, fom.A.shape, fom.B.shape)  # what for_model checks
        blocks, L = fom.blocks, fom.layout
        nu, nt = L.n_u, L.n_t
        mb, tb = boundary_dofs(given, nu, nt)
        # contacts on patch means: reduce in the coordinates where they are dofs
        self.coordinates = coords = boundary_coordinates(given, nu)
        if coords is not None:
            blocks, B = coords.blocks(blocks), coords.operator(fom.B, L)
        else:
            B = fom.B  # CSC (the model's): its boundary columns are cut out cheaply
        if thermal == "inputs":
            tb = np.zeros(0, dtype=int)  # heat enters through its distributions, not dofs
        mi, ti = np.setdiff1d(np.arange(nu), mb), np.setdiff1d(np.arange(nt), tb)
        self.n_uv = 2 * mi.size if max_n_uv is None else _count("n_uv", max_n_uv, 2 * mi.size)
        self.n_theta = ti.size if max_n_theta is None else _count("n_theta", max_n_theta, ti.size)
        self.n_qu, self.n_qv = self.n_uv // 2, (self.n_uv + 1) // 2
        self.boundary = {"u": mb, "theta": tb}
        if coords is None and sp.csr_matrix(blocks.M)[mb][:, mi].count_nonzero():
            warnings.warn(
                "the mass matrix couples the contact dofs to the interior; the paper's "
                "reduction assumes it lumped on the contacting dofs",
                stacklevel=2,
            )
        self.timings = {}
        self._largest = None  # the largest reduced operators, projected on first use
        self._models = {}  # the reduced models made, by sizes: each made once
        #: the energy forms of each size, shared with :meth:`for_model`'s reductors (same
        #: matrices: the forms do not depend on what a speed changes)
        self._energy_forms = {}
        t0 = time.perf_counter()
        self.solver = solver = InteriorSolver(blocks, mi, ti, stiffness)
        self._bnd = np.r_[mb, nu + mb, 2 * nu + tb].astype(int)
        self._int = np.r_[mi, nu + mi, 2 * nu + ti].astype(int)
        psi = solver.solve(-sp.csc_matrix(B)[:, self._bnd][self._int])  # Eq. 11, columns first
        n_i = mi.size
        velocity_static_shapes(psi, projection, n_i, mb.size)
        self.timings["static_shapes"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        self.omega2, phi = lowest_modes(solver.K, solver.M, self.n_qv, solver.solve_K, tol=MODE_TOL)
        if thermal == "inputs":
            Q = input_distributions(fom)
            chi, self.n_theta_b, self.mu = input_basis(
                solver.Ctt, solver.Ktt, solver.solve_T, Q, self.n_theta
            )
            self.n_theta, self.n_inputs = self.mu.size, Q.shape[1]
        else:
            self.mu, chi = lowest_modes(
                solver.Ktt, solver.Ctt, self.n_theta, solver.solve_T, tol=MODE_TOL
            )
            chi, self.n_theta_b, self.n_inputs = orient_columns(chi), tb.size, tb.size
        phi = orient_columns(phi)
        phi_ut = -solver.solve_K(solver.Kut @ chi)  # K_ii Φ^uθ = −K^uθ_ii Φ^θθ
        self.timings["modes"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        self._idx = (mb, mi, tb, ti)
        self.layout = self._layout(self.n_uv, self.n_theta)
        left = None  # (left) adjoint modes; boundary columns: adjoint static shapes or unit vectors
        if projection not in ("galerkin", "second-order"):
            psi_l = left_static_shapes(
                psi,
                projection,
                n_i,
                mb.size,
                lambda: solver.solve_transposed(-sp.csr_matrix(B)[self._bnd][:, self._int].T),
            )
            mphi = orient_columns(normalise_columns(solver.M @ phi[:, : self.n_qu]))
            left = (psi_l, mphi, phi, chi, solver.Ctu.T @ chi)
            del psi_l, mphi
        B = None  # the shapes are solved: the operator in the boundary coordinates goes
        if not keep_solver:  # no more solves: the factorisations' memory before the bases'
            solver.free()
        at = (self._idx, self._int, nu, fom.n_dofs, self.layout)  # where each shape goes
        self.R = assemble_basis(*at, psi, phi[:, : self.n_qu], phi, chi, phi_ut)
        del psi, phi, phi_ut  # each shape is in R (or in ``left``) before the left basis
        self.left = self.R if left is None else assemble_basis(*at, *left)
        del left
        if coords is not None:  # back to the physical coordinates: R = T̃ R', R̃ = L̃ R̃'
            self.left = self.R if self.left is self.R else coords.left(self.left, L)
            self.R = coords.right(self.R, L)
        self.timings["bases"] = time.perf_counter() - t0

    # -- bases -----------------------------------------------------------------------------
    def _layout(self, n_uv: int, n_theta: int) -> Layout:
        """Reduced layout ``(n_b + n_qu, n_b + n_qv, n_θb + n_θ)`` of the sizes given."""
        nb = self.boundary["u"].size
        return Layout(nb + n_uv // 2, nb + (n_uv + 1) // 2, self.n_theta_b + n_theta)

    def _columns(self, n_uv, n_theta) -> tuple[int, int, np.ndarray, Layout]:
        """Sizes (``None``: the largest), columns of ``R`` they keep and their layout.

        Each block of ``R`` is ``[boundary dofs, shapes in increasing eigenvalue order]``, so
        smaller sizes keep the leading columns of the ``u``, ``v`` and ``θ`` blocks.
        """
        n_uv = self.n_uv if n_uv is None else _count("n_uv", n_uv, self.n_uv)
        n_theta = self.n_theta if n_theta is None else _count("n_theta", n_theta, self.n_theta)
        Lr, Lm = self._layout(n_uv, n_theta), self.layout
        cols = np.r_[
            np.arange(Lr.n_u), Lm.v.start + np.arange(Lr.n_v), Lm.t.start + np.arange(Lr.n_t)
        ]
        return n_uv, n_theta, cols, Lr

    def stiffness_solver(self):
        """``f ↦ K⁻¹ f`` for the full model's whole stiffness (contacts free), by static
        condensation on the interior factorisation (:func:`.interior.condensed_solve`)."""
        K, coords = self.fom.blocks.K, self.coordinates
        if coords is None:
            return condensed_solve(K, self.boundary["u"], self.solver)
        K_prime = coords.blocks(self.fom.blocks).K
        return coords.solve(condensed_solve(K_prime, self.boundary["u"], self.solver))

    def mechanical_basis(self) -> np.ndarray:
        """Second-order Craig–Bampton basis of the displacements: ``[[I, 0], [Ψ_uu, Φ]]``."""
        L, Lr = self.fom.layout, self.layout
        return self.R[L.u, Lr.u]

    def thermal_basis(self) -> np.ndarray:
        """Craig–Bampton basis of the temperatures: ``[[I, 0], [Ψ_θθ, Φ^θθ]]``."""
        L, Lr = self.fom.layout, self.layout
        return self.R[L.t, Lr.t]

    # -- reduction -------------------------------------------------------------------------
    def reduce(self, n_uv=None, n_theta=None) -> FirstOrderModel:
        """The reduced model of Eqs. (14)–(15) with ``n_uv`` shapes and ``n_theta`` modes.

        ``None`` gives the largest sizes of the reductor; smaller sizes truncate its bases
        (class docstring), so this only projects: ``Ā = R̃ᵀ A R``, ``B̄ = R̃ᵀ B R``. The
        largest model is projected once (on the first call) and every size is then a block
        of it (:mod:`femrub.reduction.truncation`), unless its elastic-energy basis depends
        on the size (then that size is projected). A size asked again is the model made the
        first time (a model is immutable; a stepper runs its own copy of its contact's
        history).
        """
        key = (n_uv, n_theta)
        if key not in self._models:
            self._models[key] = self._reduced(n_uv, n_theta)
        return self._models[key]

    def _reduced(self, n_uv, n_theta) -> FirstOrderModel:
        """The reduced model of ``n_uv``, ``n_theta`` (:meth:`reduce`), made."""
        n_uv, n_theta, cols, layout = self._columns(n_uv, n_theta)
        t0 = time.perf_counter()
        m = self.fom
        if cols.size == self.R.shape[1] or self._nested():
            t0 -= self.project()  # this call's projection time includes the largest's
        if self._largest is not None and (cols.size == self.R.shape[1] or self._nested()):
            parts = self._slice(cols, layout)
        else:
            parts = self._project(cols, layout)
        x0 = self.restrict(m.x0, n_uv, n_theta)
        info = {
            "reduction": "thermoelastic Craig-Bampton (paper Sec. 2)",
            "projection": self.projection,
            "n_uv": n_uv,
            "n_theta": n_theta,
            "n_qu": n_uv // 2,
            "n_qv": (n_uv + 1) // 2,
            "n_boundary_u": int(self.boundary["u"].size),
            "n_boundary_theta": int(self.n_theta_b),
            "thermal": self.thermal,
            "energy_growth_rate": parts.pop("growth"),
            "n_full": m.n_dofs,
            "n_reduced": layout.n,
            "timings": dict(self.timings, projection=time.perf_counter() - t0),
            "full_info": dict(m.info),
        }
        A, B = parts.pop("A"), parts.pop("B")
        return FirstOrderModel(
            A=sp.csc_matrix(A),
            B=sp.csc_matrix(B),
            layout=layout,
            x0=x0,
            info=info,
            length_scale=m.length_scale,
            parameters=m.parameters,
            sweep=m.sweep,
            **parts,
        )

    def project(self) -> float:
        """Project the largest reduced operators (once); return the seconds it took (0 when
        already done). :meth:`reduce` calls it; a caller may call it first to time it."""
        if self._largest is not None:
            return 0.0
        t0 = time.perf_counter()
        n, r = self.R.shape
        with progress.phase(f"projecting the operators on the bases ({n} -> {r} dofs)"):
            self._largest = self._project(np.arange(r), self.layout)
        self.timings["projection"] = time.perf_counter() - t0
        return self.timings["projection"]

    def _nested(self) -> bool:
        """Whether every size's elastic-energy basis is ``R`` itself (no displacement part in
        the boundary velocity shapes, :func:`.energy_forms.elastic_basis`): then a size is a
        block."""
        L, Lr, nb = self.fom.layout, self.layout, self.boundary["u"].size
        return not np.any(self.R[L.u, Lr.v.start : Lr.v.start + nb])

    def _project(self, cols, layout) -> dict:
        """The operators of the sizes of ``cols`` projected over the full state; once the
        largest model is projected, those that are projections are blocks of its
        (:func:`~femrub.reduction.operators.left_sliced`: no columns of the left basis taken)
        and only what the right basis alone projects (the observations, and the energy
        forms, which rest on the size's own modes) is projected on ``R``'s columns."""
        every = cols.size == self.R.shape[1]  # the largest sizes: the bases, no copies
        R = self.R if every else np.take(self.R, cols, axis=1)  # C-ordered, as self.R
        largest = None if every else self._largest
        if largest is None:
            parts = left_projected(self.fom, R, self._left_columns(cols, R, every, layout))
        else:  # blocks of the largest model's: no columns of the left basis taken
            parts = left_sliced(largest, self.fom, cols)
        shared = None if largest is None else columns_of(largest["to_full"], cols)
        nb = self.boundary["u"].size
        return {**parts, **right_projected(self.fom, R, parts, layout, nb, to_full=shared)}

    def _left_columns(self, cols, R, every, layout) -> np.ndarray:
        """The left basis on ``cols`` (``R`` itself for a Galerkin projection)."""
        if self.projection in ("galerkin", "second-order"):
            return R
        if self.left is None:
            raise ValueError(
                f"sizes {layout.n_u + layout.n_v} + {layout.n_t} were not made before this "
                "reductor was released (released(): it lifts and reconstructs, it no longer "
                "projects); reduce them with the reductor of the build"
            )
        return self.left if every else np.take(self.left, cols, axis=1)

    def _slice(self, cols, layout) -> dict:
        """The operators of the sizes of ``cols`` as blocks of the largest projected ones,
        with the full model's gap, heat and load functions (:meth:`for_model`)."""
        key = cols.tobytes()
        parts = sliced(self._largest, self.fom, cols, layout, self._energy_forms.get(key))
        self._energy_forms[key] = (parts["energy"], parts["growth"])
        return parts

    def reconstruct(self, Xr: np.ndarray, n_uv=None, n_theta=None) -> np.ndarray:
        """Full state ``R X̄`` of a reduced state (r,) or of the rows of an (m, r) array.

        ``n_uv``, ``n_theta``: the sizes the reduced model was built with (``reduce``'s
        arguments, also in its ``info``); ``None``: the largest sizes.
        """
        Xr = self.lift(Xr, n_uv, n_theta)  # zero on the columns left out: no copy of R
        return self.R @ Xr if Xr.ndim == 1 else Xr @ self.R.T

    def lift(self, Xr: np.ndarray, n_uv=None, n_theta=None) -> np.ndarray:
        """The largest model's state equal to a state of the model of sizes ``n_uv``,
        ``n_theta`` (its sub-basis: zero on the columns it leaves out)."""
        *_, cols, layout = self._columns(n_uv, n_theta)
        Xr = np.asarray(Xr, dtype=float)
        if Xr.shape[-1] != layout.n:
            raise ValueError(f"a reduced state has {layout.n} entries, got {Xr.shape}")
        if cols.size == self.layout.n:
            return Xr
        out = np.zeros(Xr.shape[:-1] + (self.layout.n,))
        out[..., cols] = Xr
        return out

    def restrict(self, X: np.ndarray, n_uv=None, n_theta=None) -> np.ndarray:
        """Least-squares reduced state of a full state (exact when ``X`` is in span R).

        ``n_uv``, ``n_theta``: sizes of the reduced model, as in :meth:`reconstruct`.
        """
        *_, cols, layout = self._columns(n_uv, n_theta)
        X = np.asarray(X, dtype=float)
        if not np.any(X):
            return np.zeros(X.shape[:-1] + (layout.n,))
        sol = np.linalg.lstsq(self.R[:, cols], X.T if X.ndim == 2 else X, rcond=None)[0]
        return sol.T if X.ndim == 2 else sol

    def for_model(self, fom) -> ThermoelasticCraigBampton:
        """This reductor's bases on ``fom``: a full model with the same matrices.

        What a rotation speed changes without changing a matrix (the casing's gap functions,
        heat coefficients, load signals) is taken from ``fom`` by :meth:`reduce`; the bases
        are shared, not copied. The caller vouches for the matrices (the model cache keys
        them, :mod:`femrub.app.cached`); the layout and the operators' shapes are checked.
        """
        if (fom.layout, fom.A.shape, fom.B.shape) != self._signature:
            raise ValueError("for_model: the model's layout or operators differ from the bases'")
        new = copy.copy(self)
        new.fom, new.timings = fom, {}  # nothing built: the reduced model's info says so
        new._models = {}  # the models of ``fom``
        return new

    def released(self) -> ThermoelasticCraigBampton:
        """This reductor once the build has made its models: it lifts, reconstructs and
        restricts states and gives the models it made (:meth:`reduce` of those sizes), and
        holds no left basis (a Petrov–Galerkin projection's: ``n × r``, 0.6 GB for a
        Rotor 37 blade): another size is a block of the largest model's when that one is
        projected, and refused otherwise."""
        new = copy.copy(self)
        new.left, new._models = None, dict(self._models)
        return new

    def detached(self) -> ThermoelasticCraigBampton:
        """This reductor without its full model (``fom = None``), to keep for
        :meth:`for_model` without holding the model it was built for (about 1 GB for a
        Rotor 37 blade); its factorisations must be released (:meth:`InteriorSolver.free`)."""
        new = copy.copy(self)
        new.fom, new._models = None, {}
        return new


def craig_bampton_thermal(model, n_uv=None, n_theta=None, **kw):
    """Reduce ``model``; return ``(reduced model, reductor)`` (``reductor.reconstruct``).

    The reductor is built with ``n_uv``, ``n_theta`` as its largest sizes, so
    ``reductor.reduce(smaller sizes)`` gives smaller models from the same bases.
    """
    red = ThermoelasticCraigBampton(model, n_uv, n_theta, **kw)
    return red.reduce(), red


def _count(name, value, most) -> int:
    if not (isinstance(value, (int, np.integer)) and 0 <= value <= most):
        raise ValueError(f"{name} must be an integer in [0, {most}], got {value!r}")
    return int(value)
