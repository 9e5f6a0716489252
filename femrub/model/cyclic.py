"""Cyclic-symmetry modes of a structure made of N identical sectors (bladed disk, casing ring).

A structure of ``N`` sectors turned by ``α = 2π/N`` about the axis ``x``
(:mod:`femrub.geometry.cyclic_sector`) vibrates in travelling or standing waves of a
whole number of nodal diameters ``k``. On the sector, a wave of ``k`` nodal diameters
satisfies the cyclic condition on its right face, the left face turned by ``R(α)``::

    u_right = e^{i k α} R(α) u_left,        k = 0, 1, ..., ⌊N/2⌋           (1)

(``R`` turns the displacement's components: a vector field repeats sector after sector in
the rotating components). With ``q`` the sector's independent dofs (interior and left
face) and ``u = T_k q`` (1), the sector's free dofs obey the Hermitian generalised
eigenproblem::

    T_kᴴ K T_k q = ω² T_kᴴ M T_k q                                            (2)

each eigenvalue of which is, for ``0 < k < N/2``, a double mode of the whole structure (the
two waves travelling forwards and backwards, or the ``cos`` and ``sin`` standing waves),
and a single one for ``k = 0`` and ``k = N/2``; the whole structure's spectrum is the union
over ``k`` of (2). Family ``j`` is the ``j``-th lowest mode of each ``k``.

At a rotation speed Ω the rotor's stiffness is the tangent about its spinning equilibrium
(:mod:`femrub.fem.centrifugal`: material + geometric stiffness − spin softening ``Ω² M_P``).
The centrifugal load is cyclic-symmetric, so the static displacement is the ``k = 0``
solution of the sector: ``T_0ᵀ r(T_0 q) = 0``, solved once (``"linear"``: one solve;
``"nonlinear"``: Newton from the linear solution); its stress field, and hence the
geometric stiffness assembled on the sector, repeats in every sector. Coriolis terms are
left out, as for the single blade. Over a list of speeds (:func:`mode_tables_over_speeds`)
the sector is assembled once and the static state at each speed is solved from the previous
speed's, scaled by ``(Ω_i / Ω_{i−1})²`` (the centrifugal load grows as ``Ω²``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..fem import centrifugal as cf
from ..fem.discretisation import assemble, discretise
from ..fem.eigen import lowest_hermitian_modes
from ..fem.linalg import sparse_lu
from ..fem.prestress import PrestressForms
from ..geometry.cyclic_sector import SectorMesh, cyclic_plane_distance, face_pairs

__all__ = [
    "CyclicStructure",
    "ModeTable",
    "cyclic_projection",
    "cyclic_structure",
    "face_dof_map",
    "harmonic_modes",
    "mode_table",
    "mode_tables_over_speeds",
    "nodal_diameter_content",
    "spinning",
]

AXIS = (1.0, 0.0, 0.0)  # the machine axis x
PRESTRESS_METHODS = ("off", "linear", "nonlinear")


@dataclass(frozen=True)
class CyclicStructure:
    """A sector's free-dof matrices and the dof map of its cyclic faces.

    Attributes
    ----------
    sector : SectorMesh
        The sector mesh (``N``, the turn ``R(α)``).
    K, M : scipy.sparse.csr_matrix
        Stiffness (N/m; the tangent at the spinning equilibrium when ``omega > 0`` with a
        prestress) and HRZ-lumped mass (kg) on the free dofs.
    free : numpy.ndarray
        Free displacement dofs (the basis's numbering).
    left, right : numpy.ndarray
        ``(n_face_nodes, 3)``: positions in ``free`` of the three components of each free
        node of the left face and of its image on the right face (``(n, 1)`` for a scalar
        field: :mod:`femrub.model.cyclic_thermal`).
    omega : float
        Rotation speed Ω (rad/s) of the prestress (0: none).
    prestress : str
        ``"off"``, ``"linear"`` or ``"nonlinear"``.
    static : numpy.ndarray
        Static displacement at Ω on every dof (m; zeros without prestress).
    basis : skfem.Basis
        The sector's P2 vector basis.
    disc : Discretisation
        The sector's discretisation (its ``basis_u`` is ``basis``), or ``None``.
    """

    sector: SectorMesh
    K: sp.csr_matrix
    M: sp.csr_matrix
    free: np.ndarray
    left: np.ndarray
    right: np.ndarray
    omega: float
    prestress: str
    static: np.ndarray
    basis: object = field(repr=False)
    disc: object = field(default=None, repr=False)

    @property
    def n_sectors(self) -> int:
        return self.sector.n_sectors

    @property
    def nodal_diameters(self) -> np.ndarray:
        """The nodal diameters k from 0 to ⌊N/2⌋."""
        return np.arange(self.n_sectors // 2 + 1)


def _dof_components(basis, n_components: int = 3) -> np.ndarray:
    """Component (0 .. ``n_components − 1``) of every dof of a basis (``ElementVector``
    order; all 0 for a scalar field)."""
    comp = np.empty(basis.N, dtype=np.int64)
    dofs = np.asarray(basis.element_dofs)
    comp[dofs] = (np.arange(dofs.shape[0]) % n_components)[:, None]
    return comp


def _face_nodes(basis, on_face, comp, tol, n_components: int) -> np.ndarray:
    """``(n, n_components)`` dofs of the components at each dof location on a face."""
    locs = basis.doflocs
    dofs = np.flatnonzero(np.abs(on_face(locs)) <= tol)
    first = dofs[comp[dofs] == 0]
    out = [first]
    for c in range(1, n_components):
        cand = dofs[comp[dofs] == c]
        dist, idx = cKDTree(locs[:, cand].T).query(locs[:, first].T)
        if dist.size and dist.max() > tol:
            raise ValueError("a face node lacks a displacement component")
        out.append(cand[idx])
    return np.column_stack(out)


def face_dof_map(basis, sector: SectorMesh, free: np.ndarray, n_components: int = 3):
    """Left-face dofs and their right images as positions in ``free`` (free nodes only),
    ``(n, n_components)`` each: the three components of a displacement, or the one of a
    scalar field (the temperature, :mod:`femrub.model.cyclic_thermal`)."""
    scale = float(np.ptp(basis.mesh.p, axis=1).max())
    tol = 1e-8 * scale
    comp = _dof_components(basis, n_components)
    on_left, on_right = cyclic_plane_distance(sector.angle / 2)
    left = _face_nodes(basis, on_left, comp, tol, n_components)
    right_all = _face_nodes(basis, on_right, comp, tol, n_components)
    locs = basis.doflocs
    right0 = face_pairs(locs, left[:, 0], right_all[:, 0], sector.rotation, tol)
    row = {d: i for i, d in enumerate(right_all[:, 0])}
    right = right_all[[row[d] for d in right0]]
    position = -np.ones(basis.N, dtype=np.int64)
    position[free] = np.arange(free.size)
    keep = np.all(position[left] >= 0, axis=1)
    if np.any(position[right[keep]] < 0) or np.any(position[right[~keep]] >= 0):
        raise ValueError(
            "the held (clamped or ambient) dofs of the sector are not cyclic-symmetric"
        )
    return position[left[keep]], position[right[keep]]


def cyclic_projection(structure: CyclicStructure, k: int) -> sp.csr_matrix:
    """``T_k`` of Eq. (1): free dofs from the independent ones (all but the right face's).

    Returns
    -------
    scipy.sparse.csr_matrix
        ``(n_free, n_free − n_right)``, complex unless ``e^{i k α}`` is real (``k = 0``,
        ``k = N/2``), then real.
    """
    n = structure.free.size
    right = structure.right.ravel()
    independent = np.setdiff1d(np.arange(n), right)
    column = -np.ones(n, dtype=np.int64)
    column[independent] = np.arange(independent.size)
    phase = np.exp(1j * k * structure.sector.angle)
    if abs(phase.imag) < 1e-12:
        phase = phase.real
    c = structure.left.shape[1]  # 3: a displacement, turned by R(α); 1: a scalar field
    R = structure.sector.rotation if c == 3 else np.eye(c)
    # row right[j, c] = phase Σ_c' R[c, c'] q[left[j, c']]
    rows = np.repeat(structure.right, c, axis=1).ravel()
    cols = column[np.tile(structure.left, (1, c))].ravel()
    vals = np.tile((phase * R).ravel(), structure.left.shape[0])
    rows = np.concatenate([independent, rows])
    cols = np.concatenate([np.arange(independent.size), cols])
    vals = np.concatenate([np.ones(independent.size), vals])
    T = sp.csr_matrix((vals, (rows, cols)), shape=(n, independent.size))
    T.eliminate_zeros()
    return T


def _prestress_state(basis, material, free, T0, omega, method, start=None):
    """Static displacement at Ω (k = 0 on the sector) and the tangent on the free dofs.

    Newton from ``start`` (m, every dof; zeros when ``None``); ``"linear"`` takes one step,
    exact from any start since its residual is affine in ``u``. The internal force and the
    tangent are those of the blade's prestress
    (:class:`~femrub.fem.prestress.PrestressForms`: compiled products with the gradient at
    the quadrature points)."""
    linear = method == "linear"
    forms = PrestressForms(basis, material, AXIS, linear)
    w2 = omega * omega
    MP = sp.csr_matrix(cf.spin_mass(basis, forms.rho, AXIS))[free][:, free]
    u = np.zeros(basis.N) if start is None else np.array(start, dtype=float)

    def tangent(u):
        return sp.csr_matrix(forms.tangent(u, None, 0.0))[free][:, free] - w2 * MP

    def residual(u):
        return T0.T @ (forms.internal(u) - forms.force(u, w2))[free]

    zero = np.zeros(basis.N)
    scale = float(np.linalg.norm(T0.T @ forms.force(zero, w2)[free]))
    for _ in range(1 if linear else 30):
        r = residual(u)
        if np.linalg.norm(r) <= 1e-10 * scale:
            break
        KT = (T0.T @ tangent(u) @ T0).tocsc()
        u[free] -= T0 @ sparse_lu(KT, symmetric=True, what="cyclic tangent").solve(r)
    else:
        if not linear and np.linalg.norm(residual(u)) > 1e-6 * scale:
            raise ValueError(
                f"Newton on the rotor's centrifugal prestress at Ω = {omega:g} rad/s did not "
                "converge; use loads.centrifugal = 'linear' or a lower rotation speed"
            )
    return u, tangent(u).tocsr()


def cyclic_structure(
    sector: SectorMesh, material, *, omega: float = 0.0, prestress: str = "off"
) -> CyclicStructure:
    """Assemble a sector (P2 tetrahedra, HRZ mass, ``root`` clamped) for the eigenproblem (2).

    Parameters
    ----------
    sector : SectorMesh
        The meshed sector.
    material : Material
        Its material (``young`` Pa, ``poisson``, ``rho`` kg/m³).
    omega : float
        Rotation speed Ω (rad/s) of the centrifugal prestress.
    prestress : str
        ``"off"`` (no prestress, whatever Ω: the casing), ``"linear"`` or ``"nonlinear"``.
    """
    if prestress not in PRESTRESS_METHODS:
        raise ValueError(f"unknown prestress {prestress!r}; use one of {PRESTRESS_METHODS}")
    disc = discretise(sector.mesh, order=2)
    mats = assemble(disc, material)
    free = np.asarray(mats.free_u)
    left, right = face_dof_map(disc.basis_u, sector, free)
    static = np.zeros(disc.basis_u.N)
    rest = CyclicStructure(
        sector, mats.K, mats.M, free, left, right, 0.0, prestress, static, disc.basis_u, disc
    )
    return spinning(rest, material, omega)


def spinning(rest: CyclicStructure, material, omega: float, start=None) -> CyclicStructure:
    """The sector ``rest`` (assembled at rest) about its spinning equilibrium at Ω.

    Solves ``T_0ᵀ r(T_0 q) = 0`` for the static state (module docstring) with the method
    ``rest.prestress`` and replaces the stiffness by the tangent
    ``K_T = K(u) + K_σ − Ω² M_P`` (N/m).

    Parameters
    ----------
    rest : CyclicStructure
        The sector at Ω = 0 (from :func:`cyclic_structure`).
    material : Material
        Its material.
    omega : float
        Ω (rad/s); ``rest`` itself when 0 or when ``rest.prestress`` is ``"off"``.
    start : numpy.ndarray, optional
        Static displacement (m, every dof) Newton starts from; zeros when ``None``.

    Returns
    -------
    CyclicStructure
        ``rest`` with ``K`` the tangent, ``omega`` Ω and ``static`` the static state (m).
    """
    omega = float(omega) if rest.prestress != "off" else 0.0
    if omega == 0.0:
        return rest
    T0 = cyclic_projection(rest, 0)
    static, K = _prestress_state(rest.basis, material, rest.free, T0, omega, rest.prestress, start)
    return replace(rest, K=K, omega=omega, static=static)


def harmonic_modes(structure: CyclicStructure, k: int, n_modes: int):
    """The ``n_modes`` lowest modes of nodal diameter ``k`` (eigenproblem 2).

    Returns
    -------
    frequencies : numpy.ndarray
        ``(n_modes,)`` natural frequencies (Hz), increasing.
    shapes : numpy.ndarray
        ``(n_free, n_modes)`` complex sector shapes on the free dofs (``T_k q``).
    """
    if not 0 <= k <= structure.n_sectors // 2:
        raise ValueError(f"nodal diameter {k} outside 0..{structure.n_sectors // 2}")
    T = cyclic_projection(structure, k)
    Th = T.conj().T
    Kk, Mk = (Th @ structure.K @ T).tocsr(), (Th @ structure.M @ T).tocsr()
    Kk, Mk = 0.5 * (Kk + Kk.conj().T), 0.5 * (Mk + Mk.conj().T)  # Hermitian to round-off
    lam, q = lowest_hermitian_modes(Kk, Mk, min(n_modes, Kk.shape[0]))
    return np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * math.pi), T @ q


@dataclass(frozen=True)
class ModeTable:
    """Natural frequencies by nodal diameter and family.

    Attributes
    ----------
    nodal_diameter, family : numpy.ndarray of int
        ``k`` and the family ``j`` (1: the lowest mode of each ``k``).
    frequency_hz : numpy.ndarray
        Natural frequency (Hz).
    rotation_speed : float
        Ω (rad/s) of the prestress the frequencies are at.
    """

    nodal_diameter: np.ndarray
    family: np.ndarray
    frequency_hz: np.ndarray
    rotation_speed: float

    def frequency(self, k: int, family: int) -> float:
        """The frequency (Hz) of family ``family`` at nodal diameter ``k``."""
        hit = (self.nodal_diameter == k) & (self.family == family)
        return float(self.frequency_hz[hit][0])


def mode_table(structure: CyclicStructure, n_families: int) -> ModeTable:
    """The ``n_families`` lowest modes of every nodal diameter k from 0 to ⌊N/2⌋."""
    nd, fam, freq = [], [], []
    for k in structure.nodal_diameters:
        f, _ = harmonic_modes(structure, int(k), n_families)
        nd.append(np.full(f.size, k))
        fam.append(np.arange(1, f.size + 1))
        freq.append(f)
    return ModeTable(np.concatenate(nd), np.concatenate(fam), np.concatenate(freq), structure.omega)


def mode_tables_over_speeds(
    rest: CyclicStructure, material, speeds, n_families: int, *, done=None
) -> list[ModeTable]:
    """:func:`mode_table` of the sector ``rest`` at every speed of ``speeds`` (rad/s).

    The sector is assembled once (``rest``); the static state at ``Ω_i`` is solved by
    :func:`spinning` from ``(Ω_i / Ω_{i−1})² u_{i−1}``, the previous speed's state scaled as
    the centrifugal load ``∝ Ω²``.

    Parameters
    ----------
    rest : CyclicStructure
        The sector at rest, with its prestress method.
    material : Material
        Its material.
    speeds : array_like
        Rotation speeds Ω (rad/s), in the order solved.
    n_families : int
        Modes per nodal diameter.
    done : list, optional
        Each table is appended to it as soon as it is computed (what an interrupted sweep
        finished stays there); the returned list is ``done`` when given.

    Returns
    -------
    list of ModeTable
        One per speed, its ``rotation_speed`` the listed Ω (also without prestress).
    """
    tables = [] if done is None else done
    state, previous = None, 0.0
    for omega in np.asarray(speeds, dtype=float):
        start = None if state is None or previous == 0.0 else (omega / previous) ** 2 * state
        structure = spinning(rest, material, omega, start)
        tables.append(replace(mode_table(structure, n_families), rotation_speed=float(omega)))
        state, previous = structure.static, structure.omega
    return tables


def nodal_diameter_content(vertex_displacement: np.ndarray, copies: np.ndarray, angle: float):
    """Share of a whole-structure shape in each nodal diameter (spatial DFT over sectors).

    The displacement of copy ``s`` is turned back into the sector's frame,
    ``v_s = R(−s α) u_s``, and ``V_k = Σ_s v_s e^{−2πi k s / N}``; harmonics ``k`` and
    ``N − k`` are one nodal diameter.

    Parameters
    ----------
    vertex_displacement : numpy.ndarray
        ``(3, n_vertices)`` of the whole structure (real or complex).
    copies : numpy.ndarray
        ``(N, n_sector_vertices)`` from :func:`~femrub.geometry.cyclic_sector.full_wheel`.
    angle : float
        ``α`` (rad).

    Returns
    -------
    numpy.ndarray
        ``(⌊N/2⌋ + 1,)`` shares summing to 1.
    """
    from ..geometry.cyclic_sector import axis_rotation

    N = copies.shape[0]
    v = np.stack([axis_rotation(-s * angle) @ vertex_displacement[:, copies[s]] for s in range(N)])
    power = np.sum(np.abs(np.fft.fft(v, axis=0)) ** 2, axis=(1, 2))  # (N,)
    k = np.arange(N // 2 + 1)
    share = power[k] + np.where((k > 0) & (2 * k != N), power[(N - k) % N], 0.0)
    return share / share.sum()
