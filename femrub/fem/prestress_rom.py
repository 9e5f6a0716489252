"""The centrifugal prestress along a list of speeds, on a reduced basis certified by residuals.

The static equilibrium of :mod:`femrub.fem.prestress` at ``s = Ω²``::

    r(u; s) = f_int(u) − s (f_0 + M_P u) = 0          (f_0: ∫ ρ P X · v dX per unit Ω²)

is solved by Galerkin projection on a basis ``V`` (``u = V q``). For the Saint
Venant–Kirchhoff material the strain is a polynomial of degree two in ``q``::

    E(q) = Σ_i q_i L_i + Σ_{i≤j} q_i q_j Q_ij,   L_i = sym(∇V_i),
    Q_ij = sym(∇V_iᵀ ∇V_j) (i < j),  Q_ii = ½ ∇V_iᵀ ∇V_i

so the strain energy ``W(q) = ½ ∫ λ tr(E)² + 2 μ E : E`` is ``½ e(q)ᵀ Γ e(q)`` with the
features ``e = (q_i, q_i q_j)`` and their Gram matrix ``Γ`` in the elasticity inner product
(:class:`EnergyPolynomial`, computed once per basis on the quadrature points of
:mod:`femrub.fem.quadrature`). The reduced force ``Jᵀ Γ e`` and tangent are then exact and
cost microseconds, whatever the mesh.

The basis is built greedily (:func:`enrich`, from :func:`initial_reduced`, the linear static
solution ``K⁻¹ f_0``): at each speed of a list the reduced solution's full residual ``r`` is
measured by its correction ``d ≈ K_T⁻¹ r`` (a back-substitution with the factorised tangent
nearest in ``Ω²``, :class:`PrestressProblem`) in the energy norm, relative to the solution,
``η = √|d · r| / √(u · K u)``; while ``η`` exceeds the tolerance somewhere, the corrections
join the basis (with ``newton``, Newton corrections by conjugate gradients on the tangent,
preconditioned by that factorisation: a Newton–Krylov step whose Krylov space is kept).
Measuring a speed costs one internal-force evaluation and one back-substitution.
"""

from __future__ import annotations

import functools
import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

try:  # numba is a dependency; the fallback keeps a broken install importable
    import numba
except ImportError:  # pragma: no cover
    numba = None

from ..blas import one_blas_thread
from . import centrifugal as cf
from .forms import lame_parameters
from .quadrature import CHUNK, THREADS, gradient_operator

__all__ = [
    "EnergyPolynomial",
    "PrestressProblem",
    "Reduced",
    "energy_polynomial",
    "enrich",
    "initial_reduced",
    "prestress_problem",
]

#: most basis vectors the greedy enrichment may use
MAX_BASIS = 40


@functools.lru_cache(maxsize=64)
def _layout(r: int, linear: bool):
    """Feature indices, stable as the basis grows: vector ``k`` adds ``L_k`` then
    ``Q_0k … Q_kk``. Returns ``(linear_index (r,), pair_i, pair_j, pair_index)``."""
    lin, pi, pj, pidx, n = [], [], [], [], 0
    for k in range(r):
        lin.append(n)
        n += 1
        if not linear:
            for i in range(k + 1):
                pi.append(i), pj.append(k), pidx.append(n)
                n += 1
    return (
        np.array(lin, dtype=int),
        np.array(pi, dtype=int),
        np.array(pj, dtype=int),
        np.array(pidx, dtype=int),
    )


@dataclass(frozen=True)
class EnergyPolynomial:
    """``W(q) = ½ e(q)ᵀ Γ e(q)`` (J) on a basis of ``r`` vectors (module docstring)."""

    gamma: np.ndarray
    r: int
    linear: bool

    def _idx(self):
        return _layout(self.r, self.linear)

    def features(self, q: np.ndarray) -> np.ndarray:
        lin, i, j, pair = self._idx()
        e = np.empty(self.gamma.shape[0])
        e[lin] = q
        e[pair] = q[i] * q[j]
        return e

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """``∂e/∂q`` (n_features × r)."""
        lin, i, j, pair = self._idx()
        eye = np.eye(self.r)
        J = np.empty((self.gamma.shape[0], self.r))
        J[lin] = eye
        J[pair] = eye[i] * q[j][:, None] + eye[j] * q[i][:, None]
        return J

    def force(self, q: np.ndarray) -> np.ndarray:
        """``∂W/∂q = Vᵀ f_int(V q)`` (N·m per unit coordinate)."""
        return self.jacobian(q).T @ (self.gamma @ self.features(q))

    def tangent(self, q: np.ndarray) -> np.ndarray:
        """``∂²W/∂q² = Vᵀ K_T(V q) V`` without spin softening."""
        J = self.jacobian(q)
        K = J.T @ self.gamma @ J
        if not self.linear:
            _, i, j, pair = self._idx()
            stress = (self.gamma @ self.features(q))[pair]
            H = np.zeros((self.r, self.r))
            np.add.at(H, (i, j), stress)
            K += H + H.T
        return K


def _strain_features(Gt, lin, pi, pj, pair, phi):  # pragma: no cover (compiled)
    """Fill ``phi`` (c, 6, n_features) with the Voigt components (shear × √2) of ``L_k``
    and ``Q_ij`` from the gradients ``Gt`` (c, r, 3, 3); compiled by numba."""
    r2 = np.sqrt(2.0)
    for q in range(Gt.shape[0]):
        for k in range(lin.size):
            g = Gt[q, k]
            f = lin[k]
            phi[q, 0, f] = g[0, 0]
            phi[q, 1, f] = g[1, 1]
            phi[q, 2, f] = g[2, 2]
            phi[q, 3, f] = r2 * 0.5 * (g[1, 2] + g[2, 1])
            phi[q, 4, f] = r2 * 0.5 * (g[0, 2] + g[2, 0])
            phi[q, 5, f] = r2 * 0.5 * (g[0, 1] + g[1, 0])
        for p in range(pi.size):
            a = Gt[q, pi[p]]
            b = Gt[q, pj[p]]
            scale = 0.5 if pi[p] == pj[p] else 1.0
            f = pair[p]
            for c in range(6):
                x = (0, 1, 2, 1, 0, 0)[c]
                y = (0, 1, 2, 2, 2, 1)[c]
                v = 0.0
                for m in range(3):
                    v += a[m, x] * b[m, y] + a[m, y] * b[m, x]
                phi[q, c, f] = scale * 0.5 * v * (1.0 if c < 3 else r2)


if numba is not None:
    _strain_features = numba.njit(cache=True, nogil=True)(_strain_features)


def _features(G: np.ndarray, r: int, linear: bool) -> np.ndarray:
    """Voigt strain features ``(c, 6, n_features)`` in the :func:`_layout` order from the
    gradients ``G`` (c, 3, 3, r) of the basis vectors."""
    lin, pi, pj, pair = _layout(r, linear)
    phi = np.empty((G.shape[0], 6, lin.size + pair.size))
    _strain_features(np.ascontiguousarray(np.moveaxis(G, 3, 1)), lin, pi, pj, pair, phi)
    return phi


def _gamma_rows(op, BV, lo, r, n_old, rows) -> None:
    """Add the quadrature points ``lo … lo + CHUNK`` to the new rows of ``Γ``."""
    n_feat = rows.shape[1]
    hi = min(lo + CHUNK, op.n_points)
    G = BV[9 * lo : 9 * hi].reshape(hi - lo, 3, 3, r)
    phi = _features(G, r, op.linear)  # (c, 6, n_feat)
    new = phi[..., n_old:] * op.w[lo:hi, None, None]
    trace = phi[:, :3].sum(axis=1)
    rows += 2.0 * op.mu * (new.reshape(-1, n_feat - n_old).T @ phi.reshape(-1, n_feat))
    rows += op.lam * (new[:, :3].sum(axis=1).T @ trace)


def energy_polynomial(op, BV: np.ndarray, previous: EnergyPolynomial | None = None):
    """:class:`EnergyPolynomial` of the basis whose gradients at the quadrature points are
    ``BV = B V`` (``op``: a :class:`~femrub.fem.quadrature.GradientOperator`); given the
    ``previous`` polynomial of the first columns, only the new rows of ``Γ`` are computed."""
    r = BV.shape[1]
    lin, _, _, pair = _layout(r, op.linear)
    n_feat = lin.size + pair.size
    n_old = 0 if previous is None else previous.gamma.shape[0]
    starts = range(0, op.n_points, CHUNK)

    def part(k):
        rows = np.zeros((n_feat - n_old, n_feat))
        for lo in starts[k::THREADS]:
            _gamma_rows(op, BV, lo, r, n_old, rows)
        return rows

    # the chunks shared between the cores, each on one BLAS thread (tall-skinny products)
    with one_blas_thread, ThreadPoolExecutor(THREADS) as pool:
        rows = sum(pool.map(part, range(THREADS)))
    gamma = np.zeros((n_feat, n_feat))
    if n_old:
        gamma[:n_old, :n_old] = previous.gamma
    gamma[n_old:] = rows
    gamma[:, n_old:] = rows.T
    return EnergyPolynomial(gamma, r, op.linear)


class PrestressProblem:
    """The full problem's pieces: ``B`` (:mod:`femrub.fem.quadrature`), ``f_0``, ``M_P``
    and the stiffness at rest ``K0`` on the free dofs ``free``, with the factorisations
    that precondition the corrections: ``(s, solve)`` pairs, the first at rest (``solve``;
    ``None``: added later with :meth:`add_factor`, before any correction)."""

    def __init__(self, op, f0, MP, free, K0, solve):
        self.op, self.f0, self.MP, self.free = op, f0, MP, free
        self.MP_free = MP[free][:, free].tocsr()
        self.K0 = K0
        self.factors = [] if solve is None else [(0.0, solve)]

    def add_factor(self, s: float, solve) -> None:
        """A factorisation of the tangent at ``s = Ω²`` (preconditions nearby speeds)."""
        self.factors.append((float(s), solve))

    def drop_factor(self, s: float) -> None:
        """Forget the factorisation at ``s`` (its memory is released with its last user;
        the one at rest stays)."""
        self.factors = [f for f in self.factors if f[0] != float(s) or f[0] == 0.0]

    def nearest(self, s: float) -> int:
        """Index in :attr:`factors` of the factorisation nearest in ``s = Ω²``."""
        return min(range(len(self.factors)), key=lambda i: abs(self.factors[i][0] - s))

    def by_factor(self, s_list) -> list:
        """``[(solve, indices), ...]``: for each factorisation nearest to some ``s`` of
        ``s_list`` (``Ω²``), its solve and the indices of those ``s`` (in the order of
        :attr:`factors`)."""
        near = np.array([self.nearest(s) for s in s_list], dtype=int)
        return [(self.factors[f][1], np.flatnonzero(near == f)) for f in np.unique(near)]

    def residual(self, u: np.ndarray, s: float) -> np.ndarray:
        """``r(u; s)`` on the free dofs (N)."""
        r = self.op.internal_force(u) - s * (self.f0 + self.MP @ u)
        return r[self.free]

    def tangent(self, u: np.ndarray, s: float):
        """``x ↦ K_T(u) x − s M_P x`` on the free dofs (one evaluation of the moduli)."""
        op, free = self.op, self.free
        D = op.moduli(op.gradients(u))

        def apply(x):
            full = np.zeros(op.B.shape[1])
            full[free] = x
            return op.apply(D, full)[free] - s * (self.MP_free @ x)

        return apply

    def corrections(self, us, s_list, *, newton: bool):
        """``(η (n,), d (n, N))`` at every pair of ``us`` (n, all dofs) and ``s_list``: the
        correction ``d ≈ K_T⁻¹ r`` of the residual ``r(u; s)`` (``newton``: preconditioned
        conjugate gradients on the tangent to 1e-2, else the nearest factorisation alone)
        and its relative energy norm ``η = √|d · r| / √(u · K0 u)``.

        The residuals are computed on :data:`~femrub.fem.quadrature.THREADS` threads, and
        the speeds that share their nearest factorisation are corrected together: one
        back-substitution with a right-hand side per speed reads the factor once for all
        of them (on Rotor 37, 37 right-hand sides at once cost what 7 cost one by one)."""
        s_list = np.asarray(s_list, dtype=float)

        def measure(k):
            uf = us[k][self.free]
            return self.residual(us[k], s_list[k]), float(uf @ (self.K0 @ uf))

        with ThreadPoolExecutor(THREADS) as pool:
            measured = list(pool.map(measure, range(s_list.size)))
            r = np.array([m[0] for m in measured]).reshape(s_list.size, -1)
            energy = np.array([m[1] for m in measured])
            d = np.empty_like(r)
            for solve, idx in self.by_factor(s_list):
                if newton:
                    applies = list(pool.map(lambda k: self.tangent(us[k], s_list[k]), idx))
                    d[idx] = _pcg(applies, r[idx].T, solve).T
                else:
                    d[idx] = np.asarray(solve(r[idx].T)).reshape(-1, idx.size).T
        work = np.abs(np.einsum("kn,kn->k", d, r))
        eta = np.sqrt(np.divide(work, energy, out=np.zeros_like(work), where=energy > 0))
        return eta, d


def _pcg(applies, b, precondition, rtol: float = 1e-2, max_iter: int = 15) -> np.ndarray:
    """Preconditioned conjugate gradients for ``A_j x_j = b_j`` on the columns of ``b``
    (``A_j`` symmetric positive, applied by ``applies[j]``), side by side: one
    ``precondition`` solve for all the columns still iterating, the ``A_j`` applied on
    :data:`~femrub.fem.quadrature.THREADS` threads; each column follows (and stops as) the
    iteration of its own system alone."""
    x = np.zeros_like(b)
    r = b.copy()
    z = np.asarray(precondition(r)).reshape(r.shape)
    p = z.copy()
    rz = np.einsum("ij,ij->j", r, z)
    rz0 = rz.copy()
    going = np.ones(b.shape[1], dtype=bool)
    with ThreadPoolExecutor(THREADS) as pool:  # the preconditioner keeps MKL's threads
        for _ in range(max_iter):
            cols = np.flatnonzero(going)
            for j, Ap in zip(cols, pool.map(lambda j: applies[j](p[:, j]), cols)):
                curvature = float(p[:, j] @ Ap)
                if curvature <= 0.0:
                    going[j] = False
                    continue
                alpha = rz[j] / curvature
                x[:, j] += alpha * p[:, j]
                r[:, j] -= alpha * Ap
            cols = np.flatnonzero(going)
            if not cols.size:
                break
            z = np.asarray(precondition(r[:, cols])).reshape(-1, cols.size)
            for j, zj in zip(cols, z.T):
                rz_new = float(r[:, j] @ zj)
                if rz_new <= rtol**2 * rz0[j]:
                    going[j] = False
                    continue
                p[:, j] = zj + (rz_new / rz[j]) * p[:, j]
                rz[j] = rz_new
    return x


def prestress_problem(disc, material, method: str, K0, solve) -> PrestressProblem:
    """The :class:`PrestressProblem` of ``disc`` (3D, clamped) for ``method`` = ``"linear"``
    or ``"nonlinear"``; ``K0`` the stiffness at rest on its free dofs, ``solve`` its
    factorisation's solve (``None``: :class:`PrestressProblem`)."""
    basis = disc.basis_u
    lam, mu = lame_parameters(material.young, material.poisson, 3)
    op = gradient_operator(basis, lam, mu, linear=method == "linear")
    rho, axis = float(material.rho), disc.blade.axis
    f0 = cf.centrifugal_force(basis, np.zeros(basis.N), rho, axis)
    MP = cf.spin_mass(basis, rho, axis).tocsr()
    free = np.setdiff1d(np.arange(basis.N), np.asarray(disc.fixed_u, dtype=int))
    return PrestressProblem(op, f0, MP, free, K0, solve)


class Reduced:
    """The Galerkin problem on a ``K0``-orthonormal basis ``V`` (free dofs); built from
    ``previous`` (a basis of its first columns) only the new rows of ``Γ`` are computed."""

    def __init__(self, problem: PrestressProblem, V: np.ndarray, previous=None):
        self.problem, self.V = problem, V
        full = np.zeros((problem.op.B.shape[1], V.shape[1]))
        full[problem.free] = V
        self.full = full
        r0 = 0 if previous is None else previous.V.shape[1]
        BV = problem.op.B @ full[:, r0:]
        self.BV = BV if previous is None else np.hstack([previous.BV, BV])
        prior = None if previous is None else previous.energy
        self.energy = energy_polynomial(problem.op, self.BV, prior)
        self.b = full.T @ problem.f0
        self.Mr = full.T @ (problem.MP @ full)

    def solve(self, s: float, q0: np.ndarray, max_iter: int = 40):
        """Newton on ``Vᵀ r(V q; s) = 0`` from ``q0``: ``(q, converged)``."""
        q = q0.copy()
        for _ in range(max_iter):
            R = self.energy.force(q) - s * (self.b + self.Mr @ q)
            T = self.energy.tangent(q) - s * self.Mr
            try:
                dq = np.linalg.solve(T, R)
            except np.linalg.LinAlgError:
                return q, False
            q -= dq
            if not np.all(np.isfinite(q)):
                return q, False
            if np.linalg.norm(dq) <= 1e-13 * max(np.linalg.norm(q), 1e-300):
                return q, True
        return q, False

    def path(self, s_list: np.ndarray) -> np.ndarray:
        """``q`` at every ``s`` (ascending), by continuation from rest with halving."""
        q, s_done, rate, out = np.zeros(self.V.shape[1]), 0.0, None, []
        for s in s_list:
            while s_done < s:
                step = s - s_done
                for _ in range(30):
                    guess = q if rate is None else q + step * rate
                    trial, ok = self.solve(s_done + step, guess)
                    if ok:
                        break
                    step *= 0.5
                else:
                    raise ValueError(
                        f"the reduced prestress did not converge at Ω = {math.sqrt(s):g} rad/s"
                    )
                rate = (trial - q) / step
                q, s_done = trial, s_done + step
            out.append(q.copy())
        return np.array(out)

    def displacement(self, q: np.ndarray) -> np.ndarray:
        return self.full @ q

    def enriched(self, d: np.ndarray):
        """This problem with the columns of ``d`` (or the vector ``d``) added to the basis,
        ``Γ`` grown once for all of them (``None`` when they all lie in its span)."""
        V = _orthonormal_add(self.V, d, self.problem.K0)
        return None if V is None else Reduced(self.problem, V, self)


def _orthonormal_add(V: np.ndarray, d: np.ndarray, K0) -> np.ndarray | None:
    """``V`` with the columns of ``d`` added in turn, ``K0``-orthonormal (twice
    Gram–Schmidt), each skipped when it lies in the span; ``None`` when none is added."""
    added = V
    for x in np.asarray(d, dtype=float).reshape(V.shape[0], -1).T:
        norm0 = math.sqrt(abs(float(x @ (K0 @ x))))
        for _ in range(2):
            x = x - added @ (added.T @ (K0 @ x))
        norm = math.sqrt(abs(float(x @ (K0 @ x))))
        if norm > 1e-12 * norm0:
            added = np.column_stack([added, x / norm])
    return None if added.shape[1] == V.shape[1] else added


def initial_reduced(problem: PrestressProblem) -> Reduced:
    """The basis of the linear static solution ``K0⁻¹ f_0``."""
    u_lin = problem.factors[0][1](problem.f0[problem.free])
    return Reduced(problem, _orthonormal_add(np.zeros((u_lin.size, 0)), u_lin, problem.K0))


def enrich(reduced: Reduced, s_set, tol: float, *, newton=True, max_basis=MAX_BASIS, log=None):
    """Enrich ``reduced`` until ``η ≤ tol`` at every ``s`` of ``s_set`` (ascending):
    ``(reduced, q, η, d)`` (``d``: each speed's correction, free dofs). ``η`` is measured
    with the nearest factorisation; each round the corrections of every speed above
    ``tol`` join the basis (``newton``: the Newton corrections, by preconditioned
    conjugate gradients on the tangent). Raises ``ValueError`` when ``max_basis``
    vectors do not suffice."""
    s_set = np.asarray(s_set, dtype=float)
    while True:
        q = reduced.path(s_set)
        u = np.array([reduced.displacement(x) for x in q])
        eta, d = reduced.problem.corrections(u, s_set, newton=False)
        worst = int(np.argmax(eta))
        if log:
            log(
                f"reduced prestress: basis {reduced.V.shape[1]}, largest η = {eta[worst]:.2e} "
                f"at {math.sqrt(s_set[worst]):.6g} rad/s"
            )
        if eta[worst] <= tol:
            return reduced, q, eta, d
        order = np.argsort(-eta)[: max(max_basis - reduced.V.shape[1], 0)]
        grow = order[eta[order] > tol]
        if newton and grow.size:
            d[grow] = reduced.problem.corrections(u[grow], s_set[grow], newton=True)[1]
        grown = reduced.enriched(d[grow].T) if grow.size else None
        if grown is None:
            raise ValueError(
                f"the reduced prestress did not reach η = {tol:g} with "
                f"{reduced.V.shape[1]} basis vectors (η = {eta[worst]:.2e} at "
                f"{math.sqrt(s_set[worst]):.6g} rad/s)"
            )
        reduced = grown
