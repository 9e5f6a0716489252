"""A bladed disk against a flexible casing ring, reduced harmonic by harmonic.

The reduced wheel (:mod:`femrub.reduction.cyclic_ritz`) is checked against the whole wheel
meshed from the turned sectors: its static response to a load at one blade's tip, read at
every blade's tips, and its lowest frequencies. The casing's rotating-frame blocks are
checked against the waves they must carry (frequencies ``ω ± kΩ`` seen from the rotor), and
a rub of the tuned wheel against the lobed, flexible casing closes its energy balance and
loads every blade alike, one blade passage apart.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree
from small_wheel import STEEL, TITANIUM, N, disk_sector

import femrub as fr
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import lowest_modes
from femrub.geometry.casing_ring import casing_ring_sector
from femrub.geometry.cyclic_sector import axis_rotation, full_wheel
from femrub.model.casing_waves import casing_waves, ring_line_loads, rotating_blocks
from femrub.model.cyclic import cyclic_structure, spinning
from femrub.model.wheel import (
    WheelConfig,
    contact_rows_of_sector,
    mistuning_stiffness,
    tip_contacts,
    wheel_model,
)
from femrub.reduction.cyclic_ritz import cyclic_basis

SPEED = 1000.0  # rad/s
CLEARANCE = 2e-5  # m


@pytest.fixture(scope="module")
def sector():
    return disk_sector()


@pytest.fixture(scope="module")
def rest(sector):
    return cyclic_structure(sector, TITANIUM)


@pytest.fixture(scope="module")
def reduced(rest):
    contacts = tip_contacts(rest, 2)
    normal, tangent = contact_rows_of_sector(rest, contacts)
    return contacts, normal, cyclic_basis(rest, 3, sp.vstack([normal, tangent]))


def _components(basis):
    comp = np.empty(basis.N, dtype=np.int64)
    comp[basis.element_dofs] = (np.arange(basis.Nbfun) % 3)[:, None]
    return comp


class WholeWheel:
    """The whole wheel meshed from the turned sectors, and sector rows carried onto it."""

    def __init__(self, sector, structure, material=TITANIUM):
        mesh, _ = full_wheel(sector)
        self.disc = discretise(mesh, 2)
        self.mats = assemble(self.disc, material)
        self.structure = structure
        self.tree = cKDTree(self.disc.basis_u.doflocs.T)
        self.comp_full = _components(self.disc.basis_u)
        self.comp_sector = _components(structure.basis)

    def row(self, local_row, s):
        """A sector row (free dofs, sector axes) read in sector ``s`` of the whole wheel."""
        R = axis_rotation(2.0 * math.pi * s / N)
        sector_row = np.zeros(self.structure.basis.N)
        sector_row[self.structure.free] = local_row
        out = np.zeros(self.disc.basis_u.N)
        for d in np.flatnonzero(sector_row):
            dist, idx = self.tree.query(R @ self.structure.basis.doflocs[:, d], k=3)
            assert dist.max() < 1e-9
            out[idx] += sector_row[d] * R[self.comp_full[idx], self.comp_sector[d]]
        return out[self.mats.free_u]


def test_reduced_wheel_static_response_at_every_tip_equals_the_whole_wheel(sector, rest, reduced):
    contacts, normal, disk = reduced
    whole = WholeWheel(sector, rest)
    rows = normal.toarray()
    u = spla.splu(whole.mats.K.tocsc()).solve(whole.row(rows[0], 0))
    D = disk.sector_rows(normal)  # (N, n_c, size)
    x = D[0, 0] / disk.omega**2
    full = np.array([[whole.row(rows[p], s) @ u for p in range(contacts.n)] for s in range(N)])
    reduced_tips = D @ x
    assert np.abs(reduced_tips - full).max() <= 1e-7 * np.abs(full).max()
    assert np.abs(full[1:]).max() < 0.01 * abs(full[0, 0])  # a load at one blade stays there


def test_reduced_wheel_lowest_frequencies_are_the_whole_wheels(sector, rest, reduced):
    _, _, disk = reduced
    whole = WholeWheel(sector, rest)
    # the two lowest families whole (2N modes): a cut inside a family's cluster of nearly
    # equal frequencies leaves which of them the eigen-solver returns to its start vector
    lam, _ = lowest_modes(whole.mats.K, whole.mats.M, 2 * N + 2)
    whole_f = np.sqrt(lam[: 2 * N]) / (2 * math.pi)
    reduced_f = np.sort(disk.omega)[: 2 * N] / (2 * math.pi)
    assert reduced_f[2 * N - 1] < 0.9 * np.sqrt(lam[2 * N]) / (2 * math.pi)
    np.testing.assert_allclose(reduced_f, whole_f, rtol=1e-6)


def test_casing_blocks_carry_waves_at_omega_plus_and_minus_k_omega():
    ring = casing_ring_sector(N, 0.08, 0.004, 0.03, h=0.012)
    structure = cyclic_structure(ring, STEEL)
    waves = casing_waves(structure, 1, np.array([0.0]), 0.08 + 1e-6)
    M, C, K, _ = rotating_blocks(waves, SPEED, 1.0, 0.0)
    n = M.shape[0]
    first_order = np.block([[np.zeros((n, n)), np.eye(n)], [-K.toarray(), -C.toarray()]])
    seen = np.sort(np.abs(sla.eigvals(first_order).imag))
    expected = []
    for h in waves.basis.harmonics:
        for w in h.omega:
            expected += [w, w] if h.k == 0 else [w + h.k * SPEED, abs(w - h.k * SPEED)] * 2
    np.testing.assert_allclose(seen, np.sort(expected), rtol=1e-10)


@pytest.mark.parametrize("k", [1, 2])
def test_ring_bases_with_residual_shapes_give_the_whole_rings_static_response(k):
    """The ring under a radial line load ``cos(kψ)`` on its bore: the harmonic basis of one
    mode and the load's residual shapes gives the whole ring's static response on the bore
    (meshed from the turned sectors); the mode alone does not."""
    radius, axial = 0.08, 0.01
    ring = casing_ring_sector(N, radius, 0.004, 0.03, h=0.012)
    structure = cyclic_structure(ring, STEEL)
    reading = radius * (1.0 + 1e-6)
    loads = ring_line_loads(structure, np.array([axial]), reading)
    f0 = loads(k)[0].toarray().ravel()  # the radial line load's part on sector 0
    probe = ring_line_loads(structure, np.array([axial]), reading)(0)[0].toarray().ravel().real
    whole = WholeWheel(ring, structure, STEEL)
    phase = np.exp(1j * k * 2.0 * math.pi * np.arange(N) / N)
    F = sum(whole.row((phase[s] * f0).real, s) for s in range(N))
    U = spla.splu(whole.mats.K.tocsc()).solve(F)
    bore = np.array([whole.row(probe, s) @ U for s in range(N)])  # mean radial, each sector

    def reduced(load_rows):
        h = cyclic_basis(structure, 1, load_rows, harmonics=[k]).harmonics[0]
        u0 = h.shapes @ ((h.shapes.conj().T @ f0) / h.omega**2)
        return np.array([(phase[s] * (probe @ u0)).real for s in range(N)])

    scale = np.abs(bore).max()
    assert np.abs(reduced(loads) - bore).max() < 1e-8 * scale
    assert np.abs(reduced(None) - bore).max() > 0.2 * scale  # measured 0.61 (k=1), 0.69 (k=2)


def _rub(sector, flexible: bool, friction: float = 0.02):
    """The tuned wheel against the 3-lobed casing (flexible ring, or rigid), 20 revolutions."""
    spinning_disk = spinning(
        cyclic_structure(sector, TITANIUM, prestress="linear"), TITANIUM, SPEED
    )
    contacts = tip_contacts(spinning_disk, 2)
    normal, tangent = contact_rows_of_sector(spinning_disk, contacts)
    disk = cyclic_basis(spinning_disk, 3, sp.vstack([normal, tangent]))
    tip_radius = sector.info["tip_radius"]
    waves = None
    if flexible:
        ring = casing_ring_sector(N, tip_radius + CLEARANCE, 0.004, 0.03, h=0.01)
        bore = tip_radius + 2e-5
        waves = casing_waves(cyclic_structure(ring, STEEL), 2, contacts.points[0], bore)
    revolution = 2 * math.pi / SPEED
    config = WheelConfig(
        rotation_speed=SPEED,
        clearance=CLEARANCE,
        lobes=3,
        distortion=2e-4,
        friction=friction,
        disk_damping=0.02,
        casing_damping=0.01,
        ramp=2 * revolution,
    )
    model, _ = wheel_model(
        config, spinning_disk, disk, contacts, waves, tip_radius=tip_radius, blade_size=0.03
    )
    steps = 3000  # per revolution: a blade passage is 500 steps
    return model, fr.ThetaMethod(model, h=revolution / steps).run(20 * revolution), contacts.n


@pytest.fixture(scope="module")
def rub(sector):
    return _rub(sector, flexible=True)


@pytest.fixture(scope="module")
def frictionless_rub(sector):
    return _rub(sector, flexible=True, friction=0.0)


def test_tuned_wheel_rub_closes_its_energy_balance(rub):
    model, res, _ = rub
    assert res.status == "ok", res.message
    assert res.impulse.sum() > 0.0
    e = res.energy
    exchanged = max(np.abs(e[k]).max() for k in ("damping_work", "contact_work"))
    assert np.abs(e["energy_error"]).max() < 1e-9 * exchanged


def test_energy_forms_give_the_power_of_the_free_wheel(rub):
    """``dE/dt = Ẋᵀ (Q_k + Q_e) X`` equals the damping form ``Xᵀ P_d X`` on any state of the
    free wheel (no contact, no load), gyroscopic and circulatory casing terms included."""
    model, _, _ = rub
    f = model.energy
    rng = np.random.default_rng(3)
    X = rng.standard_normal(model.layout.n)
    rate = spla.spsolve(model.A.tocsc(), model.B @ X)
    Q = f.Qk + f.Qe
    power = rate @ (0.5 * (Q + Q.T) @ X)  # d/dt of ½ Xᵀ Q X
    assert power == pytest.approx(X @ (f.Pd @ X), rel=1e-8)


def test_blades_a_lobe_apart_carry_the_same_forces(rub):
    """Blades a lobe period apart (2 of the 6 for 3 lobes) meet the same casing at the same
    instants from the same start: their forces are equal at every step."""
    model, res, nc = rub
    per_blade = res.impulse.reshape(res.impulse.shape[0], N, nc)
    assert per_blade.sum() > 0.0
    for s in (2, 4):
        np.testing.assert_allclose(
            per_blade[:, s], per_blade[:, 0], rtol=0, atol=1e-9 * per_blade.max()
        )
    assert np.abs(per_blade[:, 1] - per_blade[:, 0]).max() > 1e-3 * per_blade.max()


def test_tuned_wheel_loads_every_blade_alike_up_to_the_travelling_phase(frictionless_rub):
    """Once settled, blade ``s`` meets the casing as blade 0 does ``s`` blade passages later
    (σ = +1): its force history is blade 0's, shifted by ``s`` passages (frictionless)."""
    model, res, nc = frictionless_rub
    per_blade = res.impulse.reshape(res.impulse.shape[0], N, nc).sum(axis=2)
    revolution = int(round(2 * math.pi / SPEED / res.h))
    passage = revolution // N
    window = slice(per_blade.shape[0] - revolution // 2, per_blade.shape[0])
    blade0 = per_blade[window, 0].cumsum()
    assert blade0[-1] > 0.0
    for s in range(1, N):
        ahead = per_blade[window.start - s * passage : window.stop - s * passage, s].cumsum()
        assert np.abs(ahead - blade0).max() <= 1e-6 * blade0[-1]


def test_uniform_mistuning_does_not_couple_nodal_diameters(rest, reduced):
    _, _, disk = reduced
    added = mistuning_stiffness(rest, disk, np.full(N, 0.05), TITANIUM, 0.045)
    k = disk.nodal_diameter
    coupling = np.abs(added[k[:, None] != k[None, :]]).max()
    assert coupling <= 1e-9 * np.abs(added).max()
    one_blade = mistuning_stiffness(rest, disk, [0.05] + [0.0] * (N - 1), TITANIUM, 0.045)
    assert np.abs(one_blade[k[:, None] != k[None, :]]).max() > 1e-3 * np.abs(one_blade).max()
