"""Modes of a spinning blade at many speeds, each frequency checked by its residual.

For a list of rotation speeds, :func:`speed_modes` gives the lowest natural frequencies of
``K_T(u(Ω), Ω) x = ω² M x`` (the prestressed tangent of :mod:`femrub.fem.centrifugal`) at
every speed, without a full prestress or a full eigen-solve per speed:

1. **prestress**: the static state ``u(Ω)`` of :mod:`femrub.fem.prestress_rom` (a reduced
   basis built greedily, its full residual measured at every speed: ``η``, at most
   :data:`LISTED_TOLERANCE`, and the correction ``d`` that estimates its error);
2. **Ritz**: the modes of the full tangent at a few *sample* speeds (first at rest, halfway
   in ``Ω²`` and at the largest speed), M-orthonormalised together, span ``W``; at every
   speed the small problem ``Wᵀ K_T(u(Ω)) W y = λ y`` (its matrix evaluated on the
   quadrature points, :mod:`femrub.fem.quadrature`) gives Ritz values ``λ_j ≥`` the exact
   ``λ_j`` (min–max);
3. **certificate**: the residual of each Ritz pair on the full mesh, ``ρ_j = K_T x_j − λ_j M
   x_j`` with ``‖x_j‖_M = 1``, in the norm of the nearest factorised tangent
   ``‖ρ_j‖_{K⁻¹}``, bounds the distance from ``μ_j = 1/λ_j`` to an eigenvalue of the pencil
   ``M x = μ K x`` by ``ε_j = ‖ρ_j‖_{K⁻¹} / λ_j^{3/2}`` (Krylov–Bogoliubov) and, with the gap
   ``δ_j`` to the neighbouring Ritz values (less their ``ε``), by ``ε_j² / δ_j``
   (Kato–Temple); the frequency's relative error bound is ``1 − √(μ_j / (μ_j + δ))``
   (:func:`frequency_bounds`). The prestress is itself approximate: the first-order
   frequency shift of its correction ``d`` (step 1), times :data:`STATIC_MARGIN`, is added:
   an estimate, not a bound (``d`` is one back-substitution with a tangent factorised at
   another speed, and a frequency weighs the prestress's error unlike the energy norm).
   Where a bound exceeds the tolerance, the modes of the full tangent at the worst speed
   become a sample (``W`` grows) and every speed is evaluated again, up to ``max_samples``.

Coriolis terms are left out, as in the rest of femrub (docs/theory.md).
"""

from __future__ import annotations

import contextvars
import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..blas import one_blas_thread
from .eigen import lowest_modes
from .linalg import sparse_lu
from .prestress_rom import enrich, initial_reduced, prestress_problem
from .quadrature import THREADS
from .speed_family import sample_speeds

__all__ = ["SpeedModes", "frequency_bounds", "speed_modes"]

#: relative residual ``η`` of the reduced prestress at its training speeds
STATIC_TOLERANCE = 1e-3
#: largest ``η`` accepted at a listed speed without enriching the basis again (the
#: frequency bounds include the first-order effect of that speed's correction)
LISTED_TOLERANCE = 1e-3
#: ``η`` of the first, coarse basis (on which the tangent at the top speed is factorised).
#: A finer coarse basis (0.03) makes that tangent definite on Rotor 37 and the prestress a
#: quarter cheaper, but trains a different final basis whose frequency errors at mid speeds
#: were up to 1.45 times the bound (0.035 % against 0.024 % at 1400 rad/s): the prestress
#: term of the bound is an estimate (module docstring), so this value stays as validated
COARSE_TOLERANCE = 0.1
#: training speeds of the prestress basis, equally spaced in Ω²
TRAINING = 4
#: factor on the estimated frequency shift of the prestress's residual: ``d`` estimates the
#: error of the reduced prestress only as well as the nearest factorised tangent inverts
#: the exact one, and the shift is taken to first order (on Rotor 37 the error at the
#: sample speeds, where the Ritz part vanishes, was up to 1.07 times the unscaled shift)
STATIC_MARGIN = 2.0
#: most speeds whose residuals are back-substituted together
SPEEDS_PER_SOLVE = 32
#: most bytes of those residuals (a column per Ritz pair checked, ``modes + 1`` per speed,
#: on the free dofs): fewer speeds per solve on a larger mesh
SOLVE_BYTES = 256 * 2**20
#: extra modes per sample in the Ritz basis
EXTRA_MODES = 4
#: relative accuracy asked of the samples' eigenvalues (the samples only span ``W``: the
#: frequencies reported are its Ritz values, checked by their residuals)
SAMPLE_TOLERANCE = 1e-8


@dataclass(frozen=True)
class SpeedModes:
    """Frequencies (Hz) at ``speeds`` (rad/s) and their certificates.

    Attributes
    ----------
    speeds : (n,) rotation speeds (rad/s), as given.
    frequencies : (n, modes) frequencies (Hz), ascending at each speed.
    shapes : list of (m, modes) Ritz coordinates of the modes on the final basis ``W``.
    bounds : (n, modes) relative error bounds of the frequencies (NaN: not checked).
    eta : (n,) certified relative residual of the prestress.
    displacements : (n, N) static displacement (m) on every dof.
    sample_speeds : speeds whose full modes span ``W`` (rad/s).
    rest_frequencies : (modes,) the full eigen-solve's frequencies at rest (Hz).
    static_basis, ritz_basis : sizes of the prestress basis and of ``W``.
    """

    speeds: np.ndarray
    frequencies: np.ndarray
    shapes: list
    bounds: np.ndarray
    eta: np.ndarray
    displacements: np.ndarray
    sample_speeds: list
    rest_frequencies: np.ndarray
    static_basis: int
    ritz_basis: int


def frequency_bounds(lam: np.ndarray, res_k: np.ndarray, modes: int) -> np.ndarray:
    """Relative error bounds of the frequencies of the ``modes`` lowest Ritz values ``lam``
    (ascending, ``λ = ω²``) from ``res_k = ‖ρ_j‖_{K⁻¹}`` (``‖x_j‖_M = 1``; one more entry
    than ``modes`` gives the last mode its upper gap). Module docstring, step 3: in the
    pencil ``M x = μ K x`` (``μ = 1/λ``, ``‖y‖_K = 1``) the residual norm is
    ``ε_j = ‖ρ_j‖_{K⁻¹} / λ_j^{3/2}``, the bound ``δ_j = min(ε_j, ε_j² / gap_j)``, and
    ``λ_j ≥ λ'_j ≥ 1 / (μ_j + δ_j)``."""
    lam = np.asarray(lam, dtype=float)
    mu = 1.0 / np.where(lam > 0, lam, np.nan)
    eps = np.asarray(res_k, dtype=float) / lam[: len(res_k)] ** 1.5
    out = np.empty(modes)
    for j in range(modes):
        below = mu[j] - mu[j + 1] - eps[j + 1] if j + 1 < eps.size else 0.0
        above = mu[j - 1] - mu[j] if j > 0 else np.inf
        gap = min(below, above)
        delta = min(eps[j], eps[j] ** 2 / gap) if gap > 0 else eps[j]
        out[j] = 1.0 - math.sqrt(mu[j] / (mu[j] + delta)) if np.isfinite(mu[j]) else np.inf
    return out


class _Setting:
    """The full problem at every speed: prestress basis, mass, the tangent's pieces."""

    def __init__(self, disc, material, mats, method, log):
        self.disc, self.material, self.mats, self.method, self.log = (
            disc,
            material,
            mats,
            method,
            log,
        )
        with ThreadPoolExecutor(1) as beside:  # the stiffness factorised beside the forms
            lu0 = beside.submit(
                contextvars.copy_context().run, sparse_lu, mats.K, symmetric=True, what="stiffness"
            )
            self.problem = prestress_problem(disc, material, method, mats.K, None)
            self.solve0 = lu0.result().solve
        self.problem.add_factor(0.0, self.solve0)
        self.free = self.problem.free
        self.MPf = self.problem.MP_free

    def full_tangent(self, u, s):
        """The assembled tangent ``K_T(u) − s M_P`` on the free dofs."""
        op = self.problem.op
        K = op.assemble(op.moduli(op.gradients(u)))
        return (K[self.free][:, self.free] - s * self.MPf).tocsr()

    def sample(self, u, s, k):
        """Lowest ``k`` modes of the full tangent at ``(u, s)`` (free dofs), and its solve."""
        if s == 0.0:
            solve, K = self.solve0, self.mats.K
        else:
            K = self.full_tangent(u, s)
            solve = sparse_lu(K, symmetric=True, what="prestressed tangent").solve
        return lowest_modes(K, self.mats.M, k, solve, tol=SAMPLE_TOLERANCE)[1], solve

    def prestress(self, speeds, sample_speeds, static_tol):
        """``(u (n, N), η (n,), corrections (n, N), basis size, samples)`` at ``speeds``
        (sorted, > 0); the corrections ``d ≈ u_exact − u`` feed the frequency bounds. The
        tangent at the top speed, factorised on the first, coarse prestress, preconditions
        the Newton corrections; the modal samples at ``sample_speeds`` (sorted, > 0) are
        taken on the trained one, and their factorisations measure every listed speed."""
        s_all = np.asarray(speeds) ** 2
        s_train = np.linspace(0.0, s_all[-1], TRAINING + 1)[1:]
        s_samples = np.asarray(sample_speeds, dtype=float) ** 2
        reduced = initial_reduced(self.problem)
        reduced = enrich(reduced, s_train, COARSE_TOLERANCE, newton=False, log=self.log)[0]
        top = s_samples[-1:]
        K = self.full_tangent(reduced.displacement(reduced.path(top)[0]), top[0])
        # on the coarse state and with spin softening, often indefinite (so on Rotor 37)
        lu = sparse_lu(K, symmetric=True, what="tangent", definite=False)
        self.problem.add_factor(top[0], lu.solve)
        reduced = enrich(reduced, s_train, static_tol, log=self.log)[0]
        self.problem.drop_factor(top[0])  # the coarse state's, released before the samples
        states = [reduced.displacement(x) for x in reduced.path(s_samples)]
        # the samples side by side, each its tangent's assembly, factorisation and
        # eigen-solve (their messages in this thread's log)
        with ThreadPoolExecutor(min(THREADS, len(states))) as pool:
            jobs = [
                pool.submit(contextvars.copy_context().run, self.sample, u, s, self.k)
                for u, s in zip(states, s_samples, strict=True)
            ]
            taken = [job.result() for job in jobs]
        samples = []
        for s, (shapes, solve) in zip(s_samples, taken, strict=True):
            self.problem.add_factor(s, solve)
            samples.append((float(np.sqrt(s)), shapes))
        # every listed speed, with the final factorisations: measured, and enriched only
        # above LISTED_TOLERANCE (the bounds carry the effect of each speed's correction d,
        # which estimates the error of u)
        reduced, q, eta, d = enrich(reduced, s_all, LISTED_TOLERANCE, newton=False, log=self.log)
        u = np.array([reduced.displacement(x) for x in q])
        corrections = np.zeros((len(d), self.problem.op.B.shape[1]))
        corrections[:, self.free] = d
        return u, eta, corrections, reduced.V.shape[1], samples


def speed_modes(
    disc,
    material,
    mats,
    method: str,
    speeds,
    *,
    modes: int = 6,
    samples: int = 3,
    tolerance: float = 0.005,
    static_tol: float = STATIC_TOLERANCE,
    max_samples: int = 12,
    check: bool = True,
    log=None,
) -> SpeedModes:
    """Certified frequencies at ``speeds`` (rad/s) of ``disc`` with prestress ``method``
    (``"linear"`` or ``"nonlinear"``); ``mats``: its mechanical matrices on the free dofs
    (``K`` at rest, ``M``). ``tolerance``: the largest relative frequency error bound
    accepted before a sample is added; ``samples``: the first samples, equally spaced in
    ``Ω²`` from rest to the largest speed (at least 2). Module docstring."""
    speeds = np.asarray(speeds, dtype=float)
    setting = _Setting(disc, material, mats, method, log)
    setting.k = min(modes + EXTRA_MODES, mats.n_u - 1)
    top = float(speeds.max())
    sampled = sample_speeds(top, max(int(samples), 2))[1:]
    moving = np.unique(speeds[speeds > 0])
    u_all, eta_all = np.zeros((speeds.size, disc.basis_u.N)), np.zeros(speeds.size)
    d_all = np.zeros_like(u_all)
    static_basis, taken = 0, []
    with ThreadPoolExecutor(1) as beside:  # the modes at rest, beside the prestress
        at_rest = beside.submit(
            contextvars.copy_context().run,
            lowest_modes,
            *(mats.K, mats.M, setting.k, setting.solve0),
            tol=SAMPLE_TOLERANCE,
        )
        if moving.size:
            u_m, eta_m, d_m, static_basis, taken = setting.prestress(moving, sampled, static_tol)
            where = np.searchsorted(moving, speeds)
            moving_mask = speeds > 0
            u_all[moving_mask] = u_m[where[moving_mask]]
            eta_all[moving_mask] = eta_m[where[moving_mask]]
            d_all[moving_mask] = d_m[where[moving_mask]]
        lam0, shapes0 = at_rest.result()
    first = [(0.0, shapes0), *taken]
    ritz = _Ritz(setting, first)
    while True:
        lam, Y, bounds = ritz.evaluate(speeds, u_all, d_all, modes, check)
        worst = int(np.nanargmax(bounds.max(axis=1))) if check else 0
        if not check or bounds[worst].max() <= tolerance or len(ritz.samples) >= max_samples:
            break
        if log:
            log(
                f"Ritz bound {100 * bounds[worst].max():.3g} % at {speeds[worst]:.6g} rad/s: "
                "its full modes join the basis"
            )
        shapes, solve = setting.sample(u_all[worst], speeds[worst] ** 2, setting.k)
        setting.problem.add_factor(speeds[worst] ** 2, solve)
        ritz = _Ritz(setting, ritz.samples + [(float(speeds[worst]), shapes)])
    return SpeedModes(
        speeds=speeds,
        frequencies=np.sqrt(np.clip(lam[:, :modes], 0.0, None)) / (2 * np.pi),
        shapes=[y[:, :modes] for y in Y],
        bounds=bounds,
        eta=eta_all,
        displacements=u_all,
        sample_speeds=[w for w, _ in ritz.samples],
        rest_frequencies=np.sqrt(np.clip(lam0[:modes], 0.0, None)) / (2 * np.pi),
        static_basis=int(static_basis),
        ritz_basis=int(ritz.W.shape[1]),
    )


class _Ritz:
    """The Ritz basis ``W`` of the samples' modes (M-orthonormal, full numbering) and
    its products with ``B`` and ``M_P``."""

    def __init__(self, setting: _Setting, samples: list):
        self.setting, self.samples = setting, samples
        M = setting.mats.M
        V = np.hstack([shapes for _, shapes in samples])
        G = V.T @ (M @ V)
        lam, Q = sla.eigh(0.5 * (G + G.T))
        keep = lam > 1e-10 * lam.max()
        Wf = V @ (Q[:, keep] / np.sqrt(lam[keep]))
        op, free = setting.problem.op, setting.free
        self.Wf = Wf
        self.W = np.zeros((op.B.shape[1], Wf.shape[1]))
        self.W[free] = Wf
        self.BW = op.B @ self.W
        self.MPr = Wf.T @ (setting.MPf @ Wf)

    def evaluate(self, speeds, u_all, d_all, modes, check):
        """Ritz values (n, m), coordinates and frequency bounds (n, modes) at every speed
        (``d_all``: the prestress corrections, whose effect joins the bounds).

        The speeds are taken by groups that share their nearest factorisation, at most
        :data:`SPEEDS_PER_SOLVE` at a time (fewer when their residuals would take more
        than :data:`SOLVE_BYTES`): their Ritz pairs and residuals on
        :data:`~femrub.fem.quadrature.THREADS` threads (one BLAS thread each), and the
        residuals' back-substitution as one solve with all their columns, in this thread
        while the others go on with the next group."""
        n = len(speeds)
        lam, Y, bounds = [None] * n, [None] * n, np.full((n, modes), np.nan)
        problem = self.setting.problem
        column = 8 * problem.free.size * min(modes + 1, self.W.shape[1])
        per_solve = max(1, min(SPEEDS_PER_SOLVE, SOLVE_BYTES // column))
        groups = [
            (solve, group[i : i + per_solve])
            for solve, group in problem.by_factor(np.asarray(speeds, dtype=float) ** 2)
            for i in range(0, group.size, per_solve)
        ]

        def one(k):
            with one_blas_thread:
                return self._at(float(speeds[k]) ** 2, u_all[k], d_all[k], modes, check)

        with ThreadPoolExecutor(THREADS) as pool:
            jobs = {k: pool.submit(one, k) for _, idx in groups for k in idx}
            for solve, idx in groups:
                out = [jobs.pop(k).result() for k in idx]
                for k, (lam_k, Y_k, _, _) in zip(idx, out, strict=True):
                    lam[k], Y[k] = lam_k, Y_k
                if check:
                    bounds[idx] = self._bounds(out, solve, modes)
        return np.array(lam), Y, bounds

    def _at(self, s, u, d, modes, check):
        """At ``s = Ω²``: the Ritz values and coordinates, and (``check``) the residuals
        ``R`` of the first Ritz pairs on the free dofs and the prestress term of the
        bounds (:meth:`_static`; 0 without a correction ``d``)."""
        op, setting = self.setting.problem.op, self.setting
        g = op.gradients(u)
        Kr = op.project(g, self.BW)
        lam, Y = sla.eigh(Kr - s * self.MPr)
        if not check:
            return lam, Y, None, 0.0
        n_res = min(modes + 1, self.W.shape[1])
        corrected = op.gradients(u + d) if np.any(d) else None
        KX, at_corrected = self._tangent_applied(g, Y[:, :n_res], corrected, modes)
        X = self.Wf @ Y[:, :n_res]
        R = KX[setting.free] - s * (setting.MPf @ X) - (setting.mats.M @ X) * lam[:n_res]
        if corrected is None:
            return lam, Y, R, 0.0
        y = Y[:, :modes]
        at_u = np.einsum("im,ij,jm->m", y, Kr, y)  # xᵀ K_T(u) x
        return lam, Y, R, self._static(at_u, at_corrected, lam[:modes])

    def _tangent_applied(self, g, Y, corrected, modes):
        """``K_T(u) W Y`` on all dofs at the state of the gradients ``g`` and, when the
        gradients ``corrected`` of ``u + d`` are given, ``xᵀ K_T(u + d) x`` for the first
        ``modes`` columns ``x`` of ``W Y``: chunk by chunk of quadrature points (the chunk's
        ``B W Y``, moduli and their product in buffers written again by every chunk)."""
        op = self.setting.problem.op
        m = Y.shape[1]
        KX = np.zeros((op.B.shape[1], m))
        forms = np.zeros(modes)
        chunks = op.chunks()
        size = max(hi - lo for lo, hi in chunks)
        D, DG = np.empty((size, 9, 9)), np.empty((size, 9, m))
        for lo, hi in chunks:
            GX = (self.BW[9 * lo : 9 * hi] @ Y).reshape(-1, 9, m)
            Dc = op.moduli(g[lo:hi], op.w[lo:hi], out=D[: hi - lo])
            np.matmul(Dc, GX, out=DG[: hi - lo])
            op.add_transposed(lo, DG[: hi - lo].reshape(-1, m), KX)
            if corrected is not None:
                forms += op.quadratic_forms(corrected[lo:hi], GX[..., :modes], w=op.w[lo:hi])
        return KX, forms

    @staticmethod
    def _bounds(out, solve, modes):
        """The frequency bounds of the speeds whose :meth:`_at` gave ``out``, their
        residuals' ``K⁻¹`` norms from one back-substitution with ``solve``."""
        R = np.hstack([R for _, _, R, _ in out])
        KR = np.asarray(solve(R)).reshape(R.shape)
        res = np.sqrt(np.maximum(np.einsum("ij,ij->j", R, KR), 0.0))
        bounds, col = [], 0
        for lam, _, R_k, static in out:
            n_res = R_k.shape[1]
            bounds.append(frequency_bounds(lam[:n_res], res[col : col + n_res], modes) + static)
            col += n_res
        return np.array(bounds)

    @staticmethod
    def _static(at_u, at_corrected, lam):
        """Relative frequency shift of the prestress correction ``d``, to first order:
        ``|xᵀ (K_T(u + d) − K_T(u)) x| / 2λ`` per Ritz vector ``x`` (``at_u``: ``xᵀ K_T(u)
        x``, ``at_corrected``: ``xᵀ K_T(u + d) x``), times :data:`STATIC_MARGIN`."""
        return STATIC_MARGIN * np.abs(at_corrected - at_u) / (2.0 * lam)
