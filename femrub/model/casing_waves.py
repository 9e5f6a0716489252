"""A flexible casing ring seen from the rotor: its modes as waves in the rotating frame.

The casing does not turn. Its modes of ``k`` nodal diameters (:mod:`femrub.model.cyclic`,
:mod:`femrub.reduction.cyclic_ritz`), as fields of the angle ``ψ`` on its inner surface, are
waves ``Re(ξ A(x) e^{i k ψ})`` with ``A(x)`` the cylindrical components (radial,
circumferential, axial) of the mode's Fourier amplitude at the axial position ``x``,
computed from the sector's shape (:func:`ring_amplitudes`; the harmonics ``k + jN`` the
sector's mesh adds are left out). A point of the rotor at the angle ``φ`` of the rotor's
frame is at ``ψ = φ + σ Ω t`` (σ the direction of rotation). In the rotating coordinates
``ζ = ξ e^{iβt}``, ``β = k σ Ω``, the casing's displacement at a rotor point is
``Re(ζ A(x) e^{ikφ})``: rows that do not depend on time, so the contacts between blades
and casing keep the gap form ``g = g0(t) + Gᵀ X``. The modal equation
``ξ̈ + 2ζ_c ω ξ̇ + ω² ξ = F_ξ`` becomes, with ``ζ = c + i d``::

    [c̈]   [2ζ_c ω    2β  ] [ċ]   [ω² − β²    2ζ_c ω β] [c]   [F_c]
    [d̈] + [−2β     2ζ_c ω] [ḋ] + [−2ζ_c ω β  ω² − β² ] [d] = [F_d]        (1)

(gyroscopic ``2β`` and circulatory ``2ζ_c ω β`` terms; ``k = 0`` keeps ``β = 0`` and one
coordinate). The energy these coordinates carry, ``½|ẋ|² + ½(ω² − β²)|x|²``, changes by the
work of the forces, the damping ``−2ζ_c ω |ẋ|²`` and the circulatory power
``−ẋᵀ K_a x`` (``K_a`` the skew part of the stiffness in (1)): :func:`rotating_blocks`
returns that power's form with the blocks, so the energy balance closes.

The rows neglect the casing's convective velocity ``σΩ ∂u/∂φ`` in the relative sliding
velocity (its size against the casing's sliding ``σΩr`` is ``k|u|/r``, below 1e-3 here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..reduction.cyclic_ritz import CyclicBasis

__all__ = [
    "CasingWaves",
    "casing_harmonics",
    "casing_waves",
    "cylindrical_components",
    "ring_amplitudes",
    "ring_line_loads",
    "rotating_blocks",
    "waves_of",
]

#: Gauss points over the sector's angle for the Fourier amplitude of a mode.
ANGLE_POINTS = 16


def cylindrical_components(values: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """``(3, ...)`` Cartesian components at angles ``phi`` (broadcast against ``values[0]``) as
    (radial, circumferential, axial)."""
    s, c = np.sin(phi), np.cos(phi)
    radial = -s * values[1] + c * values[2]
    circumferential = -c * values[1] - s * values[2]
    return np.stack([radial, circumferential, values[0]])


def ring_amplitudes(structure, basis, axial: np.ndarray, radius: float) -> np.ndarray:
    """Fourier amplitudes ``A(x)`` of every Ritz vector of ``basis`` on the ring's surface.

    Parameters
    ----------
    structure : CyclicStructure
        The ring's sector.
    basis : HarmonicBasis
        Its shapes of nodal diameter ``k``.
    axial : numpy.ndarray
        ``(n,)`` axial positions ``x`` (m).
    radius : float
        Radius (m) the shapes are read at (just inside the ring's bore).

    Returns
    -------
    numpy.ndarray
        ``(m, n, 3)`` complex: ``A_j(x_p)`` in (radial, circumferential, axial) components,
        ``(1/α) ∫ W_j(φ) e^{−ikφ} dφ`` over the sector.
    """
    probe, phi, w = _bore_probe(structure, axial, radius)
    full = np.zeros((structure.basis.N, basis.shapes.shape[1]), dtype=complex)
    full[structure.free] = basis.shapes
    n = np.size(axial) * phi.size
    values = (probe @ full).reshape(3, n, -1)  # (component, point, mode)
    ph = np.tile(phi, np.size(axial))
    cyl = cylindrical_components(values, ph[:, None]).reshape(3, np.size(axial), phi.size, -1)
    kernel = w * np.exp(-1j * basis.k * phi)
    return np.einsum("cpqj,q->jpc", cyl, kernel)


def _bore_probe(structure, axial, radius: float):
    """The probe (``(3 n_x n_φ, N)``, component-major) of the ring's field at the Gauss
    angles ``φ`` over the sector (its angles and weights of the mean over ``(−α/2, α/2)``)
    at every axial position ``axial`` (m) and ``radius`` (m)."""
    alpha = 2.0 * math.pi / structure.n_sectors
    nodes, weights = np.polynomial.legendre.leggauss(ANGLE_POINTS)
    phi, w = 0.5 * alpha * nodes, 0.5 * weights
    x = np.repeat(np.asarray(axial, dtype=float), phi.size)
    ph = np.tile(phi, np.size(axial))
    points = np.stack([x, -radius * np.sin(ph), radius * np.cos(ph)])
    return sp.csr_matrix(structure.basis.probes(points)), phi, w


def ring_line_loads(structure, axial: np.ndarray, radius: float, band: float = 0.0):
    """The ring's loads of the contacts, for the residual shapes of its bases: a function
    of the nodal diameter ``k`` returning, per axial position and per direction (radial,
    circumferential), the sector's part of the load ``e^{ikψ}`` spread round the ring.

    Parameters
    ----------
    structure : CyclicStructure
        The ring's sector.
    axial : numpy.ndarray
        ``(n,)`` axial positions ``x`` (m) of the contacts.
    radius : float
        Radius (m) the loads act at (just inside the ring's bore).
    band : float
        Axial width (m) each load is spread over (uniformly, three Gauss points; 0: a line).

    Returns
    -------
    callable
        ``k -> (2 n, n_free)`` complex rows (their scale does not matter: the residual shapes
        are normalised).
    """
    axial = np.asarray(axial, dtype=float)
    if band > 0.0:
        g, gw = np.polynomial.legendre.leggauss(3)
    else:
        g, gw = np.zeros(1), np.full(1, 2.0)
    x = (axial[:, None] + 0.5 * band * g[None, :]).ravel()  # (n_pos × n_g,) position-major
    probe, phi, w = _bore_probe(structure, x, radius)
    s, c = np.sin(phi), np.cos(phi)
    zero = np.zeros_like(phi)
    # (direction, component, φ): radial and circumferential in global axes (x, y, z)
    directions = np.stack([np.stack([zero, -s, c]), np.stack([zero, -c, -s])])
    # (position, point): each position's weights on its own axial Gauss points
    weights = np.kron(np.eye(axial.size), 0.5 * gw[None, :])

    def rows(k: int) -> sp.csr_matrix:
        wave = w * np.exp(1j * k * phi)  # (n_φ,)
        coeff = np.einsum("dcq,px,q->pdcxq", directions, weights, wave)
        coeff = coeff.reshape(2 * axial.size, -1)  # rows (position, direction) as probe's
        return sp.csr_matrix(coeff @ probe)[:, structure.free]

    return rows


@dataclass(frozen=True)
class CasingWaves:
    """The casing's rotating coordinates and their rows at the rotor's contacts.

    Attributes
    ----------
    basis : CyclicBasis
        The ring's Ritz bases (coordinates ordered as :class:`CyclicBasis` orders them: a
        pair block ``[c_1..c_m, d_1..d_m]`` per ``k > 0``, one block for ``k = 0``).
    amplitudes : tuple
        Per harmonic, ``(m, n_points, 3)`` Fourier amplitudes at the contacts' axial
        positions (:func:`ring_amplitudes`).
    """

    basis: CyclicBasis
    amplitudes: tuple

    @property
    def size(self) -> int:
        return self.basis.size

    def rows(self, angles: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Rows on the casing coordinates of its displacement at rotor points.

        Parameters
        ----------
        angles : numpy.ndarray
            ``(n,)`` angles ``φ`` (rad) of the points in the rotor's frame.
        directions : numpy.ndarray
            ``(n, 3)`` the direction read at each point in (radial, circumferential, axial)
            components; point ``p`` reads the amplitudes of contact point ``p % n_points``.

        Returns
        -------
        numpy.ndarray
            ``(n, size)``.
        """
        N = self.basis.n_sectors
        out = np.zeros((angles.size, self.size))
        for (h, start, m, pair), A in zip(self.basis.blocks(), self.amplitudes, strict=True):
            p = np.arange(angles.size) % A.shape[1]
            value = (
                np.einsum("jpc,pc->pj", A[:, p, :], directions) * np.exp(1j * h.k * angles)[:, None]
            )
            if pair:
                out[:, start : start + m] = math.sqrt(2.0 / N) * value.real
                out[:, start + m : start + 2 * m] = -math.sqrt(2.0 / N) * value.imag
            else:
                out[:, start : start + m] = value.real / math.sqrt(N)
        return out


def casing_harmonics(n_sectors: int) -> list[int]:
    """The nodal diameters a ring of ``n_sectors`` carries as waves: 0 to ``⌈N/2⌉ − 1``.

    ``k = N/2`` is left out: on an even ``N`` the sector holds only its standing wave in
    phase with the sectors, which does not turn into a wave of the rotating frame.
    """
    return [k for k in range(n_sectors // 2 + 1) if 2 * k != n_sectors]


def waves_of(structure, basis: CyclicBasis, axial: np.ndarray, radius: float) -> CasingWaves:
    """The ring's harmonic ``basis`` (of :func:`casing_harmonics`) as waves read at the axial
    positions ``axial`` (m) and the bore ``radius`` (m)."""
    amplitudes = tuple(ring_amplitudes(structure, b, axial, radius) for b in basis.harmonics)
    return CasingWaves(basis, amplitudes)


def casing_waves(structure, n_modes: int, axial: np.ndarray, radius: float) -> CasingWaves:
    """The ring's ``n_modes`` lowest modes of every nodal diameter of
    :func:`casing_harmonics` as waves (:func:`waves_of`)."""
    from ..reduction.cyclic_ritz import cyclic_basis

    harmonics = casing_harmonics(structure.n_sectors)
    return waves_of(structure, cyclic_basis(structure, n_modes, harmonics=harmonics), axial, radius)


def rotating_blocks(waves: CasingWaves, omega_rotor: float, direction: float, damping: float):
    """Mass, damping and stiffness of Eq. (1) and the circulatory power's form.

    Parameters
    ----------
    waves : CasingWaves
        The casing's coordinates.
    omega_rotor : float
        Rotation speed Ω (rad/s).
    direction : float
        σ (+1 or −1).
    damping : float
        Modal damping ratio ``ζ_c`` of the casing.

    Returns
    -------
    M, C, K : scipy.sparse.csr_matrix
        ``(n, n)`` blocks of Eq. (1) (``M = I``).
    Ka : scipy.sparse.csr_matrix
        The skew part of ``K`` (its power ``−ẋᵀ K_a x`` enters the energy balance).
    """
    n = waves.size
    C = sp.lil_matrix((n, n))
    K = sp.lil_matrix((n, n))
    Ka = sp.lil_matrix((n, n))
    for h, start, m, pair in waves.basis.blocks():
        w = h.omega
        if not pair:
            idx = np.arange(start, start + m)
            C[idx, idx] = 2.0 * damping * w
            K[idx, idx] = w * w
            continue
        beta = h.k * direction * omega_rotor
        c, d = np.arange(start, start + m), np.arange(start + m, start + 2 * m)
        C[c, c] = C[d, d] = 2.0 * damping * w
        C[c, d], C[d, c] = 2.0 * beta, -2.0 * beta
        K[c, c] = K[d, d] = w * w - beta * beta
        circ = 2.0 * damping * w * beta
        K[c, d], K[d, c] = circ, -circ
        Ka[c, d], Ka[d, c] = circ, -circ
    eye = sp.identity(n, format="csr")
    return eye, C.tocsr(), K.tocsr(), Ka.tocsr()
