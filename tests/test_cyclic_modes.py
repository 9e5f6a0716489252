"""Cyclic-symmetry modes of a bladed disk sector and a casing ring against the whole structure.

The whole structure is the sector's mesh turned N times with its shared face nodes merged, so
both problems discretise the same structure with the same elements: every cyclic mode, turned
out over the N copies, is a mode of the whole structure to round-off (a double one, its real
and imaginary parts, for 0 < k < N/2), and the whole structure's lowest frequencies (ARPACK)
are cyclic ones, of the nodal diameter of their spatial DFT over the sectors.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree
from small_wheel import STEEL, TITANIUM, N, disk_sector

from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import lowest_modes
from femrub.fem.material import Material
from femrub.fem.prestress import centrifugal_prestress
from femrub.geometry.casing_ring import RingDistortion, casing_ring_sector
from femrub.geometry.cyclic_sector import axis_rotation, face_pairs, full_wheel
from femrub.model.cyclic import (
    cyclic_projection,
    cyclic_structure,
    harmonic_modes,
    mode_table,
    nodal_diameter_content,
)


@pytest.fixture(scope="module")
def disk():
    return disk_sector()


@pytest.fixture(scope="module")
def rest(disk):
    return cyclic_structure(disk, TITANIUM)


@pytest.fixture(scope="module")
def ring():
    return casing_ring_sector(N, 0.08, 0.004, 0.03, distortion=RingDistortion(3, 1e-5), h=0.01)


def _located(basis):
    """``(n_locations, 3)`` dofs of the three components at each dof location."""
    comp = np.empty(basis.N, dtype=np.int64)
    comp[basis.element_dofs] = (np.arange(basis.Nbfun) % 3)[:, None]
    first = np.flatnonzero(comp == 0)
    cols = [first]
    for c in (1, 2):
        dofs = np.flatnonzero(comp == c)
        dist, idx = cKDTree(basis.doflocs[:, dofs].T).query(basis.doflocs[:, first].T)
        assert dist.max() < 1e-12
        cols.append(dofs[idx])
    return np.column_stack(cols)


class Whole:
    """The whole structure meshed from the turned sectors: its matrices and lowest modes."""

    def __init__(self, sector, material, n_modes, omega=0.0):
        self.sector = sector
        mesh, self.copies = full_wheel(sector)
        self.disc = discretise(mesh, 2)
        pre = centrifugal_prestress(self.disc, material, omega, "linear") if omega else None
        self.mats = assemble(self.disc, material, prestress=pre)
        lam, V = lowest_modes(self.mats.K, self.mats.M, n_modes)
        self.frequency = np.sqrt(lam) / (2 * np.pi)
        u = np.zeros((self.disc.basis_u.N, n_modes))
        u[self.mats.free_u] = V
        nodal = self.disc.basis_u.nodal_dofs
        self.content = np.array(
            [nodal_diameter_content(u[nodal, j], self.copies, sector.angle) for j in range(n_modes)]
        )

    def expand(self, structure, k, shape):
        """The whole structure's free dofs of a sector shape of nodal diameter ``k``:
        copy ``s`` is ``e^{i k s α} R(s α) u``."""
        sector_dofs = _located(structure.basis)
        whole = self.disc.basis_u
        whole_dofs = _located(whole)
        tree = cKDTree(whole.doflocs[:, whole_dofs[:, 0]].T)
        u = np.zeros(structure.basis.N, dtype=complex)
        u[structure.free] = shape
        out = np.zeros(whole.N, dtype=complex)
        for s in range(N):
            turn = axis_rotation(s * self.sector.angle)
            where = turn @ structure.basis.doflocs[:, sector_dofs[:, 0]]
            dist, idx = tree.query(where.T)
            assert dist.max() < 1e-9
            values = np.exp(1j * k * s * self.sector.angle) * (u[sector_dofs] @ turn.T)
            out[whole_dofs[idx]] = values
        return out[self.mats.free_u]

    def residual(self, x, frequency):
        """The normwise backward error ``‖K x − ω² M x‖₁ / ((‖K‖₁ + ω² ‖M‖₁) ‖x‖₁)``.

        Round-off alone leaves it near the machine epsilon, whatever the mode; the residual
        relative to ``‖K x‖`` instead has a floor of ``ε ‖K‖ / λ``, near 1e-8 for the lowest
        modes of this mesh. A shape of the wrong nodal diameter scores 1e-7 or more."""
        w2 = (2 * np.pi * frequency) ** 2
        r = self.mats.K @ x - w2 * (self.mats.M @ x)
        scale = spla.norm(self.mats.K, 1) + w2 * spla.norm(self.mats.M, 1)
        return np.linalg.norm(r, 1) / (scale * np.linalg.norm(x, 1))


def _check_against_whole(structure, whole, n_families, n_whole):
    """Every cyclic mode is a whole mode (twice for 0 < k < N/2: its real and imaginary
    parts); the whole structure's lowest frequencies are cyclic ones, of the nodal diameter
    of their spatial DFT."""
    found = []
    for k in structure.nodal_diameters:
        freq, shapes = harmonic_modes(structure, int(k), n_families)
        for f, q in zip(freq, shapes.T, strict=True):
            x = whole.expand(structure, int(k), q)
            parts = np.column_stack([x.real, x.imag])
            assert max(whole.residual(p, f) for p in parts.T if np.any(p)) < 1e-14
            double = 0 < k < N / 2
            assert np.linalg.matrix_rank(parts, tol=1e-6 * np.abs(x).max()) == (2 if double else 1)
            found += [(f, int(k))] * (2 if double else 1)
    found.sort()
    cyclic = np.array([f for f, _ in found])
    for f, content in zip(whole.frequency[:n_whole], whole.content[:n_whole], strict=True):
        j = int(np.argmin(np.abs(cyclic - f)))
        assert abs(cyclic[j] - f) < 1e-8 * f
        assert found[j][1] == int(np.argmax(content)) and content.max() > 0.999
    return cyclic


def test_sector_faces_are_periodic_and_the_blade_is_fused(disk):
    p = disk.mesh.mesh.p
    left, right = disk.mesh.require("left"), disk.mesh.require("right")
    image = face_pairs(p, left, right, disk.rotation, 1e-9)
    assert np.allclose(disk.rotation @ p[:, left], p[:, image], atol=1e-12)
    radius = disk.mesh.radius()
    assert np.isclose(radius.min(), 0.02) and radius.max() > 0.045 + 0.029
    assert disk.info["tip_radius"] == pytest.approx(radius.max())
    assert disk.mesh.require("root").size and disk.mesh.require("tip").size
    whole, copies = full_wheel(disk)
    assert whole.n_vertices == N * (disk.mesh.n_vertices - left.size)
    assert np.isclose(whole.volume(), N * disk.mesh.volume(), rtol=1e-12)


def test_cyclic_constraint_turns_the_left_face_onto_the_right(disk, rest):
    structure = rest
    q = np.random.default_rng(0).standard_normal(cyclic_projection(structure, 1).shape[1])
    u = cyclic_projection(structure, 1) @ q
    phase = np.exp(2j * np.pi / N)
    expected = phase * (u[structure.left] @ disk.rotation.T)
    assert np.allclose(u[structure.right], expected, rtol=0, atol=1e-12 * np.abs(u).max())
    assert np.isrealobj(cyclic_projection(structure, N // 2).data)


@pytest.mark.parametrize("omega", [0.0, 3000.0])
def test_bladed_disk_cyclic_modes_match_the_whole_wheel(disk, rest, omega):
    method = "linear" if omega else "off"
    structure = cyclic_structure(disk, TITANIUM, omega=omega, prestress=method) if omega else rest
    whole = Whole(disk, TITANIUM, 8, omega)
    cyclic = _check_against_whole(structure, whole, 2, 8)
    if omega:  # the prestress stiffens the blades
        at_rest = mode_table(rest, 1).frequency_hz
        spinning = mode_table(structure, 1).frequency_hz
        assert np.all(spinning > 1.05 * at_rest)
        assert cyclic[0] == pytest.approx(spinning.min())


def test_casing_ring_cyclic_modes_match_the_whole_ring(ring):
    structure = cyclic_structure(ring, STEEL)
    _check_against_whole(structure, Whole(ring, STEEL, 6), 2, 6)
    assert ring.info["distortion"].lobes == 3


def test_harmonic_modes_are_hermitian_and_refuse_a_foreign_nodal_diameter(rest):
    structure = rest
    f, shapes = harmonic_modes(structure, 1, 2)
    assert f.shape == (2,) and np.iscomplexobj(shapes) and np.all(np.diff(f) > 0)
    with pytest.raises(ValueError, match="nodal diameter 4 outside 0..3"):
        harmonic_modes(structure, 4, 1)


@pytest.mark.parametrize("method", ["linear", "nonlinear"])
def test_the_sector_prestress_is_the_whole_wheels_equilibrium(disk, method):
    """The sector's static state at Ω (k = 0), turned out over the copies, zeroes the whole
    wheel's residual ``f_int(u) − f_Ω(u)``; the nonlinear state differs from the linear one."""
    from femrub.fem import centrifugal as cf
    from femrub.fem.forms import lame_parameters

    omega = 6000.0
    structure = cyclic_structure(disk, TITANIUM, omega=omega, prestress=method)
    whole = Whole(disk, TITANIUM, 0)
    u = np.zeros(whole.disc.basis_u.N)
    u[whole.mats.free_u] = whole.expand(structure, 0, structure.static[structure.free]).real
    basis, lam, mu = whole.disc.basis_u, *lame_parameters(110e9, 0.3, 3)
    linear = method == "linear"
    load = cf.centrifugal_force(basis, u, 4500.0 * omega**2, (1.0, 0.0, 0.0))
    r = cf.internal_force(basis, u, lam, mu, linear) - load
    free = whole.mats.free_u
    assert np.linalg.norm(r[free]) < 1e-8 * np.linalg.norm(load[free])
    if not linear:
        other = cyclic_structure(disk, TITANIUM, omega=omega, prestress="linear").static
        assert not np.allclose(structure.static, other, rtol=1e-6, atol=0)


def test_coincidences_lock_the_disks_backward_wave_on_the_casings_forward_wave():
    """k Ω = ω_d + ω_c: the disk's backward wave seen from the casing, cos(k θ − (k Ω − ω_d) t),
    has the casing's forward wave's frequency ω_c; k = 0 has no travelling wave."""
    from femrub.model.coincidence import coincidences
    from femrub.model.cyclic import ModeTable

    k = np.array([0, 1, 2, 0, 1, 2])
    family = np.array([1, 1, 1, 2, 2, 2])
    disk = ModeTable(k, family, np.array([100.0, 110.0, 130.0, 400.0, 420.0, 450.0]), 500.0)
    casing = ModeTable(k[:3], family[:3], np.array([900.0, 700.0, 300.0]), 0.0)
    found = coincidences(disk, casing)
    assert len(found) == 4 and all(c.nodal_diameter >= 1 for c in found)
    for c in found:
        wd, wc = 2 * np.pi * c.disk_frequency_hz, 2 * np.pi * c.casing_frequency_hz
        assert c.nodal_diameter * c.rotation_speed - wd == pytest.approx(wc)
    assert [c.rotation_speed for c in found] == sorted(c.rotation_speed for c in found)
    first = found[0]
    assert (first.nodal_diameter, first.disk_family, first.casing_family) == (2, 1, 1)
    assert first.rotation_speed == pytest.approx(2 * np.pi * (130.0 + 300.0) / 2)


def test_the_disks_modes_over_speeds_equal_single_speed_solves(disk):
    """One assembly, the nonlinear prestress solved speed after speed from the previous
    state: the same frequencies as independent solves at each speed."""
    from femrub.model.cyclic import mode_tables_over_speeds

    speeds = [3000.0, 6000.0]
    rest = cyclic_structure(disk, TITANIUM, prestress="nonlinear")
    tables = mode_tables_over_speeds(rest, TITANIUM, speeds, 1)
    assert [t.rotation_speed for t in tables] == speeds
    for omega, table in zip(speeds, tables, strict=True):
        alone = cyclic_structure(disk, TITANIUM, omega=omega, prestress="nonlinear")
        assert np.allclose(table.frequency_hz, mode_table(alone, 1).frequency_hz, rtol=1e-8)
    assert np.all(tables[1].frequency_hz > tables[0].frequency_hz)


def _southwell_tables(speeds, rest_hz, slope):
    """Disk tables (k = 0..3, one family) with ``ω² = ω_0² + S Ω²`` exactly."""
    from femrub.model.cyclic import ModeTable

    k = np.arange(4)
    return [
        ModeTable(k, np.ones(4, int), np.sqrt(rest_hz**2 + slope * (w / (2 * np.pi)) ** 2), w)
        for w in speeds
    ]


def test_coincidences_over_speeds_are_exact_for_southwells_law():
    """Interpolating ω_d² linearly in Ω² is exact when ω_d² = ω_0² + S Ω²: each root found
    between listed speeds solves k Ω = ω_d(Ω) + ω_c to round-off; a pair whose equation keeps
    its sign over the list gets the estimate from the nearest end; bad lists are refused."""
    from femrub.model.coincidence import coincidences_over_speeds
    from femrub.model.cyclic import ModeTable

    rest_hz, slope = np.array([500.0, 800.0, 900.0, 950.0]), 1.0
    speeds = 2 * np.pi * np.linspace(0.0, 1000.0, 4)
    casing = ModeTable(np.arange(4), np.ones(4, int), np.array([900.0, 700.0, 300.0, 200.0]), 0.0)
    found = coincidences_over_speeds(_southwell_tables(speeds, rest_hz, slope), casing)
    assert [c.nodal_diameter for c in found] == [3, 2, 1]
    assert [c.method for c in found] == ["interpolated", "interpolated", "outside-range"]
    for c in found[:2]:
        k, w = c.nodal_diameter, c.rotation_speed
        wd = 2 * np.pi * np.sqrt(rest_hz[k] ** 2 + slope * (w / (2 * np.pi)) ** 2)
        assert c.disk_frequency_hz == pytest.approx(wd / (2 * np.pi), rel=1e-12)
        assert speeds[0] < w < speeds[-1]
        assert k * w - wd == pytest.approx(2 * np.pi * c.casing_frequency_hz, rel=1e-10)
    top = found[-1]  # k = 1: k Ω < ω_d + ω_c up to the top speed: ω_d taken there
    assert top.rotation_speed == pytest.approx(2 * np.pi * (np.hypot(800.0, 1000.0) + 700.0))
    with pytest.raises(ValueError, match="two or more increasing speeds"):
        coincidences_over_speeds(_southwell_tables(speeds[::-1], rest_hz, slope), casing)


def test_a_coincidence_found_between_two_speeds_solves_the_equation_there(disk, ring):
    """The 3-diameter coincidence of the small wheel and a soft ring, found between 10 000 and
    20 000 rad/s, checked by a solve at the speed found: |k Ω − ω_d(Ω) − ω_c| is within the
    interpolation's error, far below the first estimate's from the lower speed."""
    from femrub.model.coincidence import coincidences, coincidences_over_speeds
    from femrub.model.cyclic import mode_tables_over_speeds, spinning

    soft = Material(young=5e9, rho=7800.0, poisson=0.3)
    casing = mode_table(cyclic_structure(ring, soft), 1)
    rest = cyclic_structure(disk, TITANIUM, prestress="linear")
    tables = mode_tables_over_speeds(rest, TITANIUM, [10000.0, 20000.0], 1)
    found = coincidences_over_speeds(tables, casing)
    hit = [c for c in found if c.method == "interpolated"]
    assert [c.nodal_diameter for c in hit] == [3] and 10000.0 < hit[0].rotation_speed < 20000.0
    wc = 2 * np.pi * casing.frequency(3, 1)

    def mismatch(speed):
        wd = 2 * np.pi * mode_table(spinning(rest, TITANIUM, speed), 1).frequency(3, 1)
        return abs(3 * speed - wd - wc) / wc

    first = next(c for c in coincidences(tables[0], casing) if c.nodal_diameter == 3)
    assert mismatch(hit[0].rotation_speed) < 2e-3
    assert mismatch(hit[0].rotation_speed) < 0.02 * mismatch(first.rotation_speed)
