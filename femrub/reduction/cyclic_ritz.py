"""Reduced models of a whole cyclic structure from one sector, harmonic by harmonic.

A structure of ``N`` identical sectors (:mod:`femrub.model.cyclic`) moves, in sector ``s``
and in the sector's own axes, as a sum of waves of ``k`` nodal diameters::

    u_s = Σ_k Re(e^{i k s α} W_k ξ_k),        α = 2π/N                     (1)

with ``W_k`` shapes on the sector's free dofs that satisfy the cyclic condition of ``k``
(``W_k = T_k Q_k``, :func:`~femrub.model.cyclic.cyclic_projection`). For each ``k`` the
basis holds the ``n_modes`` lowest modes of Eq. (2) of :mod:`femrub.model.cyclic` and,
when loads act at given rows (the blade tips' contacts), their *residual attachment
shapes*: the static responses ``K_k⁻¹ T_kᴴ Rᵀ`` to unit loads at those rows, less their
modal part ``Q Λ⁻¹ Qᴴ T_kᴴ Rᵀ`` (MacNeal's residual flexibility). Modes and residual shapes
together reproduce the static response to any load at the rows exactly; the Rayleigh–Ritz
problem on them gives ``M``-orthonormal Ritz vectors ``W_k`` and frequencies ``ω̂_k``, so
that the harmonic's reduced mass is ``I`` and its stiffness ``diag(ω̂_k²)`` (the lowest
``ω̂`` are the modes' own frequencies to round-off).

Real coordinates of the whole structure: for ``0 < k < N/2`` a vector of ``W_k`` is a
double mode of the structure, with two coordinates ``(a, b)`` (``ξ = a + i b``) and the field
``√(2/N) (a Re(e^{iksα} W) − b Im(e^{iksα} W))`` in sector ``s``; for ``k = 0`` and
``k = N/2`` (``W`` real) one coordinate ``a`` and the field ``a e^{iksα} W / √N``. With
these scalings every coordinate has unit modal mass over the whole structure
(``Σ_s |u_s|²_M``) and the harmonics are mass- and stiffness-orthogonal, so the whole
structure's reduced mass is ``I`` and its stiffness ``diag(ω̂²)`` (:class:`CyclicBasis`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..fem.eigen import hermitian_solver, lowest_hermitian_modes
from ..model.cyclic import CyclicStructure, cyclic_projection

__all__ = [
    "CyclicBasis",
    "HarmonicBasis",
    "cyclic_bases",
    "cross_matrix",
    "cyclic_basis",
    "harmonic_basis",
]

#: Residual shapes whose mass-norm share is below this (relative) are dropped as dependent.
DEPENDENT_BELOW = 1e-10


@dataclass(frozen=True)
class HarmonicBasis:
    """The Ritz vectors of one nodal diameter on the sector.

    Attributes
    ----------
    k : int
        Nodal diameter.
    omega : numpy.ndarray
        ``(m,)`` Ritz angular frequencies ``ω̂`` (rad/s), increasing.
    shapes : numpy.ndarray
        ``(n_free, m)`` complex sector shapes ``W`` (``Wᴴ M W = I``, ``Wᴴ K W = diag(ω̂²)``).
    n_modes : int
        How many of the vectors came from modes (the rest from residual shapes).
    """

    k: int
    omega: np.ndarray
    shapes: np.ndarray
    n_modes: int


def _hermitian(A):
    return 0.5 * (A + A.conj().T)


def _residual_shapes(Mk, Q, lam, static, loads):
    """Residual attachment shapes ``K⁻¹F − Q Λ⁻¹ Qᴴ F`` (``static`` = ``K⁻¹F``),
    ``M``-orthonormal and ``M``-orthogonal to ``Q`` (dependent ones dropped)."""
    X = static - Q @ ((Q.conj().T @ loads) / lam[:, None])
    X -= Q @ (Q.conj().T @ (Mk @ X))
    return _orthonormal(X, Mk)


@dataclass(frozen=True)
class _Harmonic:
    """What the Ritz bases of one nodal diameter share: the projected matrices, the most
    modes asked for and the static responses to the loads."""

    k: int
    real: bool
    T: object
    Kk: object
    Mk: object
    lam: np.ndarray
    Q: np.ndarray
    loads: np.ndarray | None
    static: np.ndarray | None


def _harmonic(structure: CyclicStructure, k: int, n_modes: int, load_rows) -> _Harmonic:
    T = cyclic_projection(structure, k)
    Th = T.conj().T
    Kk = _hermitian((Th @ structure.K @ T).tocsr())
    Mk = _hermitian((Th @ structure.M @ T).tocsr())
    solve = hermitian_solver(Kk)
    lam, Q = lowest_hermitian_modes(Kk, Mk, min(n_modes, Kk.shape[0]), solve=solve)
    loads = static = None
    if callable(load_rows):
        load_rows = load_rows(k)
    if load_rows is not None and load_rows.shape[0]:
        loads = np.asarray((Th @ sp.csr_matrix(load_rows).T).toarray(), dtype=complex)
        static = np.column_stack([solve(loads[:, j]) for j in range(loads.shape[1])])
    real = _is_real_harmonic(k, structure.n_sectors)
    return _Harmonic(int(k), real, T, Kk, Mk, lam, Q, loads, static)


def _ritz(h: _Harmonic, n_modes: int) -> HarmonicBasis:
    """The Ritz basis of ``h`` with its ``n_modes`` lowest modes (and the residual shapes)."""
    lam, Q = h.lam[:n_modes], h.Q[:, :n_modes]
    basis = Q
    if h.loads is not None:
        basis = np.column_stack([Q, _residual_shapes(h.Mk, Q, lam, h.static, h.loads)])
    if h.real:  # real shapes: a real span of the same size
        basis = _real_span(basis, h.Mk)
    w2, V = sla.eigh(_hermitian(basis.conj().T @ (h.Kk @ basis)))
    omega = np.sqrt(np.clip(w2, 0.0, None))
    return HarmonicBasis(h.k, omega, h.T @ (basis @ V), Q.shape[1])


def _real_span(B, Mk):
    """A real ``M``-orthonormal basis of the span of ``B`` when that span is real (a real
    harmonic's shapes, each some complex multiple of a real one): the principal
    ``B.shape[1]`` directions of ``[Re B, Im B]``."""
    Y = np.column_stack([B.real, B.imag])
    d, V = sla.eigh(np.real(Y.T @ (Mk @ Y)))
    top = slice(d.size - B.shape[1], d.size)
    return Y @ (V[:, top] / np.sqrt(d[top]))


def _orthonormal(X, Mk):
    """An ``M``-orthonormal basis of the span of ``X``'s columns (dependent ones dropped),
    the columns' order kept (Gram–Schmidt twice, column by column)."""
    out = []
    scale = max(float(np.real(np.vdot(x, Mk @ x))) for x in X.T)
    for x in X.T:
        for _ in range(2):
            for q in out:
                x = x - q * np.vdot(q, Mk @ x)
        norm2 = float(np.real(np.vdot(x, Mk @ x)))
        if norm2 > DEPENDENT_BELOW * scale:
            out.append(x / np.sqrt(norm2))
    return np.column_stack(out)


def harmonic_basis(
    structure: CyclicStructure, k: int, n_modes: int, load_rows=None
) -> HarmonicBasis:
    """The Ritz basis of nodal diameter ``k`` (module docstring).

    Parameters
    ----------
    structure : CyclicStructure
        The sector (its ``K`` the tangent at its speed when prestressed).
    k : int
        Nodal diameter, ``0 <= k <= N/2``.
    n_modes : int
        Modes kept (families).
    load_rows : scipy.sparse matrix or callable, optional
        ``(r, n_free)`` rows of the loads on the sector (e.g. contact patch means), or a
        function of ``k`` returning them (complex rows: loads ``f_0`` on sector 0 of a load
        ``f_s = e^{iksα} f_0``, e.g. a line load ``e^{ikψ}``); their residual shapes join the
        basis.
    """
    return _ritz(_harmonic(structure, k, n_modes, load_rows), n_modes)


def _is_real_harmonic(k: int, n_sectors: int) -> bool:
    return k == 0 or 2 * k == n_sectors


@dataclass(frozen=True)
class CyclicBasis:
    """The whole structure's real coordinates over harmonic bases (module docstring).

    Attributes
    ----------
    n_sectors : int
        ``N``.
    harmonics : tuple of HarmonicBasis
        One per nodal diameter kept, in increasing ``k``.
    """

    n_sectors: int
    harmonics: tuple

    @property
    def angle(self) -> float:
        return 2.0 * math.pi / self.n_sectors

    def blocks(self):
        """``(harmonic, start, m, pair)`` of each harmonic's coordinates: the first coordinate,
        the vectors and whether each vector has two coordinates."""
        start = 0
        for h in self.harmonics:
            m = h.omega.size
            pair = not _is_real_harmonic(h.k, self.n_sectors)
            yield h, start, m, pair
            start += m * (2 if pair else 1)

    @property
    def size(self) -> int:
        return sum(m * (2 if pair else 1) for _, _, m, pair in self.blocks())

    @property
    def omega(self) -> np.ndarray:
        """``(size,)`` angular frequency (rad/s) of every coordinate."""
        parts = [np.tile(h.omega, 2 if pair else 1) for h, _, _, pair in self.blocks()]
        return np.concatenate(parts)

    @property
    def nodal_diameter(self) -> np.ndarray:
        """``(size,)`` nodal diameter of every coordinate."""
        parts = [np.full(m * (2 if pair else 1), h.k) for h, _, m, pair in self.blocks()]
        return np.concatenate(parts)

    def sector_rows(self, rows) -> np.ndarray:
        """Rows on the coordinates of a sector quantity in every sector.

        Parameters
        ----------
        rows : array_like or sparse
            ``(r, n_free)`` rows of a sector quantity in the sector's axes (e.g. the normal
            displacement of a contact).

        Returns
        -------
        numpy.ndarray
            ``(N, r, size)``: ``[s] @ x`` is the quantity in sector ``s`` (Eq. 1).
        """
        R = sp.csr_matrix(rows)
        N = self.n_sectors
        out = np.zeros((N, R.shape[0], self.size))
        phase = np.exp(1j * self.angle * np.arange(N))
        for h, start, m, pair in self.blocks():
            P = np.asarray(R @ h.shapes)  # (r, m) complex
            Ps = phase[:, None, None] ** h.k * P[None]  # (N, r, m)
            if pair:
                scale = math.sqrt(2.0 / N)
                out[:, :, start : start + m] = scale * Ps.real
                out[:, :, start + m : start + 2 * m] = -scale * Ps.imag
            else:
                out[:, :, start : start + m] = Ps.real / math.sqrt(N)
        return out

    def sector_field(self, x: np.ndarray, s: int) -> np.ndarray:
        """The sector's free-dof displacement (its own axes) in sector ``s`` for coordinates
        ``x`` (``(size,)`` or ``(size, n_times)``)."""
        x = np.asarray(x, dtype=float)
        N = self.n_sectors
        out = 0.0
        for h, start, m, pair in self.blocks():
            field = np.exp(1j * h.k * self.angle * s) * h.shapes
            if pair:
                xi = x[start : start + m] + 1j * x[start + m : start + 2 * m]
                out = out + math.sqrt(2.0 / N) * (field @ xi).real
            else:
                out = out + (field @ x[start : start + m]).real / math.sqrt(N)
        return out


def cyclic_bases(structure: CyclicStructure, sizes, load_rows=None, harmonics=None) -> list:
    """:class:`CyclicBasis` of every nodal diameter in ``harmonics`` (default all,
    ``0 .. ⌊N/2⌋``) with each number of modes of ``sizes``, one factorisation and one
    eigen-solve per nodal diameter for them all (the larger sizes' spans hold the smaller's)."""
    ks = structure.nodal_diameters if harmonics is None else sorted(set(harmonics))
    parts = [_harmonic(structure, int(k), max(sizes), load_rows) for k in ks]
    return [CyclicBasis(structure.n_sectors, tuple(_ritz(h, n) for h in parts)) for n in sizes]


def cyclic_basis(
    structure: CyclicStructure, n_modes: int, load_rows=None, harmonics=None
) -> CyclicBasis:
    """:func:`harmonic_basis` of every nodal diameter in ``harmonics`` (default all,
    ``0 .. ⌊N/2⌋``), as one :class:`CyclicBasis`."""
    return cyclic_bases(structure, [n_modes], load_rows, harmonics)[0]


def cross_matrix(rows: CyclicBasis, cols: CyclicBasis, operator) -> np.ndarray:
    """``(rows.size, cols.size)``: the whole structure's bilinear form of a sector
    ``operator`` between the real coordinates of two bases of the same sectors.

    For a sector operator ``A`` (``(n_rows_free, n_cols_free)``, real, the same in every
    sector, e.g. a mass, a coupling ``K^uθ``) and fields of coordinates ``x`` (``rows``) and
    ``y`` (``cols``), ``Σ_s u_sᵀ A w_s = xᵀ B y`` (Eq. 1): harmonics of different ``k`` do
    not couple, and with ``P = W_kᴴ A V_k`` a pair's block is
    ``[[Re P, −Im P], [Im P, Re P]]`` (``ξ = a + i b``), a real harmonic's ``Re P``. With
    ``A = M`` and ``cols`` spanned by ``rows`` it carries ``cols``' coordinates into
    ``rows``' exactly.
    """
    out = np.zeros((rows.size, cols.size))
    blocks = {h.k: (h, start, m) for h, start, m, _ in rows.blocks()}
    for h, start, m, pair in cols.blocks():
        if h.k not in blocks:
            continue
        hr, rs, mr = blocks[h.k]
        P = hr.shapes.conj().T @ (operator @ h.shapes)  # (mr, m)
        out[rs : rs + mr, start : start + m] = P.real
        if pair:
            out[rs : rs + mr, start + m : start + 2 * m] = -P.imag
            out[rs + mr : rs + 2 * mr, start : start + m] = P.imag
            out[rs + mr : rs + 2 * mr, start + m : start + 2 * m] = P.real
    return out
