"""A bladed disk rubbing a flexible casing ring: every blade tip against the casing.

The disk's sector (:mod:`femrub.model.cyclic`, prestressed at Ω) and the casing ring's
sector are reduced harmonic by harmonic (:mod:`femrub.reduction.cyclic_ritz`: the modes of
every nodal diameter and, for the disk, the residual shapes of the tip contacts), so the
whole wheel is never meshed. The state is ``u = [disk coordinates, casing coordinates]``
(mass ``I``): the disk's ``diag(ω̂²)`` stiffness and modal damping ``2 ζ_d ω̂``, the casing's
rotating-frame blocks (:mod:`femrub.model.casing_waves`, Eq. 1 there).

Contact ``(s, p)``: point ``p`` of the tip of blade ``s`` (at ``φ_sp = s α + φ_p`` in the
rotor's frame), with the gap of the single blade's rub (:mod:`femrub.model.rub`)::

    g_sp(t) = c(σ Ω t + φ_sp) + (r_tip − r_p) − n_p · u_static(p)
              − n_sp · (u_blade(s, p) − u_casing(φ_sp))                          (1)

``c(ψ)`` the clearance of the round casing plus its ``k``-lobed out-of-roundness
``a cos(k (ψ − ψ_0))`` (:class:`~femrub.geometry.casing_ring.RingDistortion`; the bore's
radius grows at a crest), ``r_tip`` the blades' largest tip radius, ``u_static`` the
centrifugal growth at Ω. Coulomb friction acts along the axial and circumferential tangents
with the casing sliding at ``−σ Ω r_p`` (:func:`~femrub.contact.casing.sliding_velocity`);
the tangential relative displacement is the blade's less the casing's.

Mistuning: blade ``s`` has its stiffness scaled by ``1 + δ_s``. With ``K_b`` the stiffness of
the blade's elements on the sector (centroid outside the disk's rim) and ``U_s`` the disk
coordinates' field in sector ``s``, the disk's reduced stiffness gains
``Σ_s δ_s U_sᵀ K_b U_s`` (Eq. 5 of docs/bladed-disk.md; the tuned basis kept: the mistuning
projected on the tuned wheel's modes and residual shapes, as in the subset-of-nominal-modes
method).
"""

from __future__ import annotations

import math
from contextlib import nullcontext
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from ..blas import SERIAL_SETUP_DOFS, one_blas_thread
from ..contact.abradable import CasingGrid
from ..contact.casing import (
    Concentric,
    Lobed,
    RampedSweptGap,
    RampedSweptGapRate,
    sliding_velocity,
    swept_gap,
)
from ..contact.points import ContactPoints, locate_contacts
from ..fem.assembly import ThermoelasticMatrices
from ..fem.elasticity import isotropic_stiffness
from ..fem.forms import lame_parameters
from ..geometry.cyclic_sector import sector_angle, sector_turns
from ..reduction.cyclic_ritz import CyclicBasis, cross_matrix
from .build import ContactSpec, first_order_model
from .casing_waves import CasingWaves, cylindrical_components, rotating_blocks
from .first_order import CasingSweep, FirstOrderModel, Parameters
from .wheel_probes import UNITS as PROBE_UNITS
from .wheel_probes import wheel_probe_rows

__all__ = [
    "CasingSurface",
    "WheelConfig",
    "WheelMap",
    "WheelThermal",
    "contact_rows_of_sector",
    "mistuning_stiffness",
    "tip_contacts",
    "contact_heat_rows",
    "wheel_casing_grid",
    "wheel_model",
    "wheel_thermal",
]


@dataclass(frozen=True)
class WheelConfig:
    """What a bladed-disk rub needs besides its structures (SI units).

    Attributes
    ----------
    rotation_speed : float
        Ω (rad/s), the speed the disk was prestressed at.
    clearance : float
        Radial clearance (m) between the round casing's bore and the blades' largest tip
        radius at rest.
    lobes, distortion, distortion_phase : int, float, float
        The casing's out-of-roundness ``a cos(k (ψ − ψ_0))`` (m; rad).
    direction : float
        σ: +1 counterclockwise about ``+x``, −1 clockwise.
    friction : float
        Coulomb μ.
    restitution : float
        Newton's coefficient e.
    disk_damping, casing_damping : float
        Modal damping ratios ζ_d and ζ_c.
    ramp : float
        Time (s) over which the out-of-roundness grows from zero (0: there from the start).
    """

    rotation_speed: float
    clearance: float
    lobes: int = 0
    distortion: float = 0.0
    distortion_phase: float = 0.0
    direction: float = 1.0
    friction: float = 0.0
    restitution: float = 0.0
    disk_damping: float = 0.0
    casing_damping: float = 0.0
    ramp: float = 0.0


@dataclass(frozen=True)
class CasingSurface:
    """What the casing's surface carries besides its shape: the abradable coating and the
    wall's heat, both on the cells every blade's contacts sweep (:func:`wheel_casing_grid`).

    Attributes
    ----------
    wear : :class:`~femrub.contact.abradable.Abradable` or None
        The coating (its wear map in the casing's fixed frame).
    casing_heat : :class:`~femrub.contact.casing_heat.CasingHeat` or None
        The wall's lumped temperatures and the clearance their expansion takes.
    heat_law : str
        ``"power"`` (the casing takes ``(1 − η)`` of the friction power) or ``"alpha"``.
    heat_partition : float
        η, the share of the frictional power that enters the blades.
    alpha : numpy.ndarray
        ``(N n_c,)`` heat coefficients (m/s) of the ``"alpha"`` law, blade by blade.
    """

    wear: object = None
    casing_heat: object = None
    heat_law: str = "alpha"
    heat_partition: float = 1.0
    alpha: np.ndarray | float = 0.0


@dataclass(frozen=True)
class WheelThermal:
    """The blades' temperature on the wheel's coordinates
    (:mod:`femrub.model.cyclic_thermal`, reduced by :mod:`femrub.reduction.cyclic_ritz`).

    Attributes
    ----------
    basis : CyclicBasis
        The temperature's harmonic bases (``C^θθ``-orthonormal: reduced heat capacity ``I``,
        conductivity ``diag(μ)``, ``μ = basis.omega²`` in 1/s).
    Kut : numpy.ndarray
        ``(n_disk, n_θ)`` thermal-stress coupling ``K^uθ`` on the disk's and the
        temperature's coordinates (N/K per unit coordinates).
    Ctu : numpy.ndarray
        ``(n_θ, n_disk)`` thermoelastic heating ``C^θu``.
    heat_rows : numpy.ndarray
        ``(N n_c, n_θ)``: the temperature at contact ``(s, p)`` (and where its frictional
        heat enters), blade by blade.
    heat_content : numpy.ndarray
        ``(n_θ,)``: the whole wheel's heat content ``Σ_s 1ᵀ C^θθ θ_s`` (J) per coordinate.
    heat_outflow : tuple of numpy.ndarray
        ``(n_disk,)`` and ``(n_θ,)``: the heat flow out of the wheel ``Σ_s 1ᵀ (C^θu u̇_s +
        K^θθ θ_s)`` (W) per velocity and per temperature coordinate (the root is held at
        ambient).
    """

    basis: CyclicBasis
    Kut: np.ndarray
    Ctu: np.ndarray
    heat_rows: np.ndarray
    heat_content: np.ndarray
    heat_outflow: tuple


def wheel_thermal(thermal, basis: CyclicBasis, disk: CyclicBasis, contacts: ContactPoints):
    """:class:`WheelThermal` of the sector's temperature ``thermal``
    (:class:`~femrub.model.cyclic_thermal.ThermalSector`) on ``basis``, coupled to the disk's
    coordinates ``disk`` (:func:`~femrub.reduction.cyclic_ritz.cross_matrix` of ``K^uθ``
    and ``C^θu``), with the tip ``contacts``' temperature rows."""
    rows = contact_heat_rows(thermal, contacts)
    t = thermal.structure
    ones = np.ones(t.free.size)

    def whole(b: CyclicBasis, row) -> np.ndarray:  # Σ over the sectors of a sector row
        return b.sector_rows(np.atleast_2d(row)).sum(axis=(0, 1))

    return WheelThermal(
        basis,
        cross_matrix(disk, basis, thermal.Kut),
        cross_matrix(basis, disk, thermal.Ctu),
        basis.sector_rows(rows).reshape(basis.n_sectors * contacts.n, -1),
        whole(basis, t.M.T @ ones),
        (whole(disk, thermal.Ctu.T @ ones), whole(basis, t.K.T @ ones)),
    )


def contact_heat_rows(thermal, contacts: ContactPoints) -> sp.csr_matrix:
    """``(n_c, n_free_θ)``: each tip contact's temperature (and heat input) weights on the
    sector's free temperature dofs."""
    return sp.csr_matrix(contacts.heat[:, thermal.structure.free])


def wheel_casing_grid(
    config: WheelConfig, structure, contacts: ContactPoints, n_blades: int, cells, footprint=0.0
) -> CasingGrid:
    """The casing cells swept by the tip contacts of all ``n_blades`` blades.

    Contact ``(s, p)`` sits at casing angle ``σ Ω t + φ_sp`` (Eq. 1) and axial position
    ``x_p`` (the sector's axis); the grid's radius is the largest tip radius grown at Ω.
    ``cells``: the coating's or the casing heat's configuration (``n_angle``, ``n_axial``);
    ``footprint``: the circumferential width (m) a contact reads the coating over.
    """
    _, angles = _contact_angles(contacts, n_blades)
    growth = contacts.normal_displacement(structure.static)
    return CasingGrid(
        angles,
        np.tile(contacts.points[0], n_blades),
        float(np.max(contacts.radii + growth)),
        config.direction * float(config.rotation_speed),
        n_angle=cells.n_angle,
        n_axial=cells.n_axial,
        footprint=footprint,
    )


@dataclass(frozen=True)
class WheelMap:
    """What output needs to turn a wheel state into blades and fields.

    Attributes
    ----------
    disk : CyclicBasis
        The disk's coordinates (the first ``disk.size`` of ``u``).
    casing : CasingWaves or None
        The casing's coordinates (the next ``casing.size``).
    contacts : ContactPoints
        The tip contacts of the sector's blade (sector axes).
    n_blades : int
        ``N``.
    temperature : CyclicBasis or None
        The blades' temperature coordinates (the state's last ``temperature.size``), or
        ``None`` without temperature dofs.
    """

    disk: CyclicBasis
    casing: CasingWaves | None
    contacts: ContactPoints
    n_blades: int
    temperature: CyclicBasis | None = None

    @property
    def n_disk(self) -> int:
        return self.disk.size

    @property
    def n_casing(self) -> int:
        return 0 if self.casing is None else self.casing.size


def tip_contacts(structure, n_points: int) -> ContactPoints:
    """``n_points`` contacts on the tip face of the sector's blade, spread along its chord.

    The tip face's vertices are ordered along the face's longest principal direction (the
    chord) and the vertices nearest to ``n_points`` evenly spaced positions are taken
    (each once); each contact acts on its part of the tip face
    (:func:`~femrub.contact.points.locate_contacts`, ``spread = "patch"``).
    """
    mesh = structure.sector.mesh
    tip = np.unique(mesh.require("tip"))
    p = mesh.mesh.p[:, tip]
    centred = p - p.mean(axis=1, keepdims=True)
    chord = np.linalg.svd(centred, full_matrices=False)[0][:, 0]
    s = chord @ centred
    targets = np.linspace(s.min(), s.max(), n_points + 2)[1:-1]
    picked = []
    for t in targets:
        order = np.argsort(np.abs(s - t) + 1e-3 * np.abs(centred).sum(axis=0))
        picked.append(next(i for i in order if i not in picked))
    return locate_contacts(structure.disc, p[:, picked], spread="patch")


def contact_rows_of_sector(structure, contacts: ContactPoints):
    """Normal ``(n_c, n_free)`` and tangent ``(2 n_c, n_free)`` rows of the contacts."""
    means = contacts.patch if contacts.patch is not None else contacts._means(structure.basis.N)
    means = sp.csr_matrix(means)[:, structure.free]
    normal = contacts._directions(contacts.normals[:, None, :]) @ means
    tangent = contacts._directions(contacts.tangents) @ means
    return sp.csr_matrix(normal), sp.csr_matrix(tangent)


def _casing_profile(config: WheelConfig):
    if config.lobes and config.distortion:
        phase = config.distortion_phase + math.pi / config.lobes  # crest: a larger bore
        return Lobed(config.clearance, abs(config.distortion), int(config.lobes), phase)
    return Concentric(config.clearance)


def mistuning_stiffness(
    structure, disk: CyclicBasis, factors, material, rim_radius: float
) -> np.ndarray:
    """``Σ_s δ_s U_sᵀ K_b U_s`` (module docstring) on the disk's coordinates.

    Parameters
    ----------
    structure : CyclicStructure
        The disk's sector (its mesh, basis and free dofs).
    disk : CyclicBasis
        The disk's coordinates; ``U_s`` is their field in sector ``s``.
    factors : array_like
        ``(N,)`` δ_s (dimensionless, each > −1): blade ``s``'s stiffness times ``1 + δ_s``.
    material : Material
        The blades' material; ``K_b`` is the elastic stiffness (N/m) of the sector's
        elements whose centroid lies outside ``rim_radius`` (m): the blade, without the disk
        (whose vertices all lie inside the rim) or the prestress. The blade's root elements,
        which reach below the rim where the root is sunk into the disk, are the blade's:
        on a coarse mesh they hold much of a bending mode's strain energy.
    rim_radius : float
        The disk's rim radius (m).

    Returns
    -------
    numpy.ndarray
        ``(disk.size, disk.size)`` symmetric stiffness (rad²/s²: the coordinates are
        mass-normalised) to add to the disk's ``diag(ω̂²)``.
    """
    factors = np.asarray(factors, dtype=float)
    mesh = structure.sector.mesh.mesh
    radius = np.hypot(mesh.p[1], mesh.p[2])
    blade = np.flatnonzero(radius[mesh.t].mean(axis=0) > rim_radius * (1.0 + 1e-9))
    lam, mu = lame_parameters(material.young, material.poisson, 3)
    Kb = isotropic_stiffness(structure.basis.with_elements(blade), lam, mu)
    Kb = sp.csr_matrix(Kb)[structure.free][:, structure.free]
    out = np.zeros((disk.size, disk.size))
    with one_blas_thread if disk.size <= SERIAL_SETUP_DOFS else nullcontext():
        for s, delta in enumerate(factors):
            if delta == 0.0:
                continue
            U = disk.sector_field(np.eye(disk.size), s)  # (n_free, size)
            out += delta * (U.T @ (Kb @ U))
    return 0.5 * (out + out.T)


def _frames(contacts: ContactPoints, n_blades: int) -> np.ndarray:
    """``(N n_c, 3, 3)``: normal, axial and circumferential directions in global axes."""
    local = contacts.frames()  # (n_c, 3, 3) in the sector's axes
    return np.einsum("sab,pdb->spda", sector_turns(n_blades), local).reshape(-1, 3, 3)


def _surface_terms(surface: CasingSurface | None) -> dict:
    """The contact specification's terms of the casing's coating and heat."""
    if surface is None:
        return {}
    return dict(
        wear=surface.wear,
        casing_heat=surface.casing_heat,
        heat_law=surface.heat_law,
        heat_partition=surface.heat_partition,
        heat_coefficient=surface.alpha,
    )


def _contact_angles(contacts: ContactPoints, n_blades: int):
    """Angles (rad, rotor frame) of the sector's contacts ``(n_c,)`` and of every blade's
    ``(N n_c,)``, blade by blade."""
    phi = sector_angle(contacts.points)
    return phi, (2.0 * math.pi / n_blades * np.arange(n_blades)[:, None] + phi).ravel()


def _contact_rows(disk, casing, structure, contacts, n_blades):
    """Normal ``(N n_c, n_u)`` and tangent ``(2 N n_c, n_u)`` rows (blade less casing)."""
    normal, tangent = contact_rows_of_sector(structure, contacts)
    nc = contacts.n
    Dn = disk.sector_rows(normal).reshape(n_blades * nc, -1)
    Dt = disk.sector_rows(tangent).reshape(n_blades * 2 * nc, -1)
    if casing is None:
        return Dn, Dt
    phi, angles = _contact_angles(contacts, n_blades)
    Cn = casing.rows(
        angles, np.tile(cylindrical_components(contacts.normals, phi).T, (n_blades, 1))
    )
    tang = [cylindrical_components(contacts.tangents[:, j, :], phi).T for j in range(2)]
    dirs = np.tile(np.stack(tang, 1).reshape(2 * nc, 3), (n_blades, 1))
    Ct = casing.rows(np.repeat(angles, 2), dirs)
    return np.hstack([Dn, -Cn]), np.hstack([Dt, -Ct])


def _matrices(disk, casing, config, extra_stiffness):
    """``M, C, K`` of the state's displacement block and the circulatory form ``K_a``."""
    w = disk.omega
    Md, Cd = sp.identity(w.size), sp.diags(2.0 * config.disk_damping * w)
    Kd = sp.diags(w * w) + (0.0 if extra_stiffness is None else sp.csr_matrix(extra_stiffness))
    if casing is None:
        return Md, Cd, sp.csr_matrix(Kd), sp.csr_matrix((w.size, w.size))
    Mc, Cc, Kc, Ka = rotating_blocks(
        casing, config.rotation_speed, config.direction, config.casing_damping
    )
    blocks = [sp.block_diag([a, b], format="csr") for a, b in ((Md, Mc), (Cd, Cc), (Kd, Kc))]
    zero = sp.csr_matrix((w.size, w.size))
    return (*blocks, sp.block_diag([zero, Ka], format="csr"))


def _as_matrices(M, C, K, thermal: WheelThermal | None = None) -> ThermoelasticMatrices:
    """The wheel's blocks of Eq. (2): ``M``, ``C``, ``K`` of the displacement coordinates
    and, with ``thermal``, the temperature's (capacity ``I``, conductivity ``diag(μ)``) and
    the couplings (zero on the casing's coordinates)."""
    n = M.shape[0]
    nt = 0 if thermal is None else thermal.basis.size
    Kut = np.zeros((n, nt))
    Ctu = np.zeros((nt, n))
    if thermal is not None:
        n_disk = thermal.Kut.shape[0]
        Kut[:n_disk], Ctu[:, :n_disk] = thermal.Kut, thermal.Ctu
    mu = np.zeros(0) if thermal is None else thermal.basis.omega**2
    return ThermoelasticMatrices(
        M=sp.csr_matrix(M),
        C=sp.csr_matrix(C),
        K=sp.csr_matrix(K),
        Kut=sp.csr_matrix(Kut),
        Ctu=sp.csr_matrix(Ctu),
        Ctt=sp.identity(nt, format="csr"),
        Ktt=sp.diags(mu).tocsr(),
        free_u=np.arange(n),
        free_t=np.arange(nt),
        n_u_all=n,
        n_t_all=nt,
        info={"coupling": None if thermal is None else "physical"},
    )


def _observations(Dn: np.ndarray, n_blades: int, nc: int, n_u: int, probes=None) -> dict:
    """Mean normal tip displacement of blade 0 and of every blade (the blade alone), and the
    probes' rows (``{key: (field, row)}`` on the disk's coordinates,
    :func:`~femrub.model.wheel_probes.wheel_probe_rows`), rows on the ``n_u`` displacement
    coordinates (``Dn`` on the disk's)."""

    def padded(rows):
        return np.hstack([rows, np.zeros((rows.shape[0], n_u - rows.shape[1]))])

    Dn = padded(Dn)
    per_blade = Dn.reshape(n_blades, nc, -1).mean(axis=1)
    return {
        "tip_displacement": ("u", per_blade[:1]),
        "tip_velocity": ("v", per_blade[:1]),
        "blade_tip_displacement": ("u", per_blade),
        "contact_displacement": ("u", Dn),
        **{key: (field, padded(row)) for key, (field, row) in (probes or {}).items()},
    }


def _heat_forms(thermal: WheelThermal, layout, n: int) -> dict:
    """The whole wheel's heat content and outflow on the state (the reduced ``C^θθ = I``
    and ``K^θθ`` alone would weigh every coordinate alike)."""
    content, outflow = np.zeros(n), np.zeros(n)
    content[layout.t] = thermal.heat_content
    v_disk, t_part = thermal.heat_outflow
    outflow[layout.v.start : layout.v.start + v_disk.size] = v_disk
    outflow[layout.t] = t_part
    return {"heat_content": content, "heat_outflow": outflow}


def _thermal_observations(thermal: WheelThermal | None, n_blades: int, nc: int) -> dict:
    """Mean tip temperature of blade 0 and of every blade, and every contact's (K)."""
    if thermal is None:
        return {}
    Q = thermal.heat_rows
    per_blade = Q.reshape(n_blades, nc, -1).mean(axis=1)
    return {
        "tip_temperature": ("theta", per_blade[:1]),
        "blade_tip_temperature": ("theta", per_blade),
        "contact_temperature": ("theta", Q),
    }


def wheel_model(
    config: WheelConfig,
    structure,
    disk: CyclicBasis,
    contacts: ContactPoints,
    casing: CasingWaves | None = None,
    *,
    tip_radius: float,
    blade_size: float,
    mistuning=None,
    probes=(),
    surface: CasingSurface | None = None,
    thermal: WheelThermal | None = None,
) -> tuple[FirstOrderModel, WheelMap]:
    """The first-order model of the wheel against the casing (module docstring).

    Parameters
    ----------
    config : WheelConfig
        Speed, clearance, distortion, friction, damping.
    structure : CyclicStructure
        The disk's sector at ``config.rotation_speed`` (its ``static`` growth enters Eq. 1).
    disk : CyclicBasis
        Its harmonic bases (with the residual shapes of ``contacts``).
    contacts : ContactPoints
        The tip contacts of the sector's blade (:func:`tip_contacts`).
    casing : CasingWaves, optional
        The flexible casing; a rigid one when ``None``.
    tip_radius : float
        The blades' largest tip radius (m) at rest.
    blade_size : float
        The blade's size (m; the model's ``length_scale``, which scales its stop limit on
        displacements).
    mistuning : numpy.ndarray, optional
        ``(n_disk, n_disk)`` stiffness added to the disk's coordinates
        (:func:`mistuning_stiffness`).
    probes : sequence of WheelProbe, optional
        Probes observed on the blades they read (:mod:`femrub.model.wheel_probes`), with
        their units in ``info["signal_units"]``.
    surface : CasingSurface, optional
        The casing's coating and wall heat, and the heat law (none when ``None``).
    thermal : WheelThermal, optional
        The blades' temperature: the frictional heat enters it at the contacts (their share
        η, ``surface.heat_partition``); without it the wheel has no temperature dofs.
    """
    N, nc = disk.n_sectors, contacts.n
    Nrows, Trows = _contact_rows(disk, casing, structure, contacts, N)
    M, C, K, Ka = _matrices(disk, casing, config, mistuning)
    growth = contacts.normal_displacement(structure.static)
    _, angles = _contact_angles(contacts, N)
    offsets = np.tile(tip_radius - contacts.radii - growth, N)
    profile = _casing_profile(config)
    omega = float(config.rotation_speed)
    gap, rate = swept_gap(profile, angles, omega, offsets, config.direction)
    if config.ramp > 0.0 and rate is not None:
        gap = RampedSweptGap(profile, config.direction * omega, angles, offsets, config.ramp)
        rate = RampedSweptGapRate(gap)
    radii = np.tile(contacts.radii, N)
    friction = {}
    if config.friction > 0.0:
        friction = dict(
            tangents=Trows,
            friction=float(config.friction),
            casing_velocity=sliding_velocity(radii, omega, config.direction),
            frames=_frames(contacts, N),
        )
    spec = ContactSpec(
        normals=Nrows,
        gap=gap,
        gap_rate=rate,
        restitution=config.restitution,
        names=[f"blade{s}_contact{p}" for s in range(N) for p in range(nc)],
        **friction,
        **_surface_terms(surface),
        **({} if thermal is None else {"heat_dofs": thermal.heat_rows}),
    )
    n_disk = disk.size
    observed = {k: v for p in probes for k, v in wheel_probe_rows(p, disk).items()}
    units = {key: PROBE_UNITS[field] for key, (field, _) in observed.items()}
    observe = _observations(Nrows[:, :n_disk], N, nc, Nrows.shape[1], observed)
    model = first_order_model(
        _as_matrices(M, C, K, thermal),
        contact=spec,
        observe=observe | _thermal_observations(thermal, N, nc),
        thermal=thermal is not None,
        info=dict(
            kind="bladed-disk",
            n_blades=N,
            n_contacts=N * nc,
            disk_coordinates=n_disk,
            casing_coordinates=0 if casing is None else casing.size,
            temperature_coordinates=0 if thermal is None else thermal.basis.size,
            rotation_speed=omega,
            rotation_direction=float(config.direction),
            **({"signal_units": units} if units else {}),
        ),
        length_scale=float(blade_size),
        parameters=Parameters(rotation_speed=omega),
        sweep=CasingSweep(profile, angles, offsets, radii, omega, config.direction),
    )
    energy = model.energy
    n_u = model.layout.n_u
    circulatory = sp.bmat([[None, sp.csr_matrix((n_u, n_u))], [-Ka, None]], format="csr")
    n_t = model.n_dofs - 2 * n_u
    circulatory = sp.block_diag([circulatory, sp.csr_matrix((n_t, n_t))], format="csr")
    energy = replace(energy, Pd=sp.csr_matrix(energy.Pd + circulatory))
    if thermal is not None:
        energy = replace(energy, **_heat_forms(thermal, model.layout, model.n_dofs))
    model = model.with_(energy=energy)
    temperature = None if thermal is None else thermal.basis
    return model, WheelMap(disk, casing, contacts, N, temperature)
