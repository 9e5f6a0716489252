"""Cyclic-symmetry modes of a bladed disk sector and a casing ring against the whole structure.

The whole structure is the sector's mesh turned N times with its shared face nodes merged, so
both problems discretise the same structure with the same elements: the frequencies agree to
the eigen-solvers' round-off, and every whole-structure mode's nodal diameter (its spatial DFT
over the sectors) is the one the cyclic solve gave it.
"""

from __future__ import annotations

import numpy as np
import pytest

from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import lowest_modes
from femrub.fem.material import Material
from femrub.fem.prestress import centrifugal_prestress
from femrub.geometry.bladed_disk import bladed_disk_sector
from femrub.geometry.casing_ring import RingDistortion, casing_ring_sector
from femrub.geometry.cyclic_sector import face_pairs, full_wheel
from femrub.model.cyclic import (
    cyclic_projection,
    cyclic_structure,
    harmonic_modes,
    mode_table,
    nodal_diameter_content,
)

N = 6
TITANIUM = Material(young=110e9, rho=4500.0, poisson=0.3)
STEEL = Material(young=200e9, rho=7800.0, poisson=0.3)
BLADE = dict(code="0012", span=0.03, root_chord=0.015, tip_chord=0.012, twist=20.0, n_sections=3)


@pytest.fixture(scope="module")
def disk():
    return bladed_disk_sector(N, 0.02, 0.045, 0.015, BLADE, h=0.015)


@pytest.fixture(scope="module")
def ring():
    return casing_ring_sector(N, 0.08, 0.004, 0.03, distortion=RingDistortion(3, 1e-5), h=0.01)


def _whole_modes(sector, material, n_modes, omega=0.0, method="linear"):
    """Frequencies (Hz) and nodal diameters of the whole structure's lowest modes."""
    mesh, copies = full_wheel(sector)
    disc = discretise(mesh, 2)
    pre = centrifugal_prestress(disc, material, omega, method) if omega else None
    mats = assemble(disc, material, prestress=pre)
    lam, V = lowest_modes(mats.K, mats.M, n_modes)
    u = np.zeros((disc.basis_u.N, n_modes))
    u[mats.free_u] = V
    nodal = disc.basis_u.nodal_dofs
    content = [nodal_diameter_content(u[nodal, j], copies, sector.angle) for j in range(n_modes)]
    return np.sqrt(lam) / (2 * np.pi), np.array(content)


def _cyclic_spectrum(structure, n_families):
    """The whole structure's spectrum from the cyclic one: (frequency, k), doubles twice."""
    table = mode_table(structure, n_families)
    k = table.nodal_diameter
    count = np.where((k == 0) | (2 * k == N), 1, 2)
    freq = np.repeat(table.frequency_hz, count)
    nd = np.repeat(k, count)
    order = np.argsort(freq, kind="stable")
    return freq[order], nd[order]


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


def test_cyclic_constraint_turns_the_left_face_onto_the_right(disk):
    structure = cyclic_structure(disk, TITANIUM)
    q = np.random.default_rng(0).standard_normal(cyclic_projection(structure, 1).shape[1])
    u = cyclic_projection(structure, 1) @ q
    phase = np.exp(2j * np.pi / N)
    expected = phase * (u[structure.left] @ disk.rotation.T)
    assert np.allclose(u[structure.right], expected, rtol=0, atol=1e-12 * np.abs(u).max())
    assert np.isrealobj(cyclic_projection(structure, N // 2).data)


@pytest.mark.parametrize("omega", [0.0, 3000.0])
def test_bladed_disk_cyclic_modes_match_the_whole_wheel(disk, omega):
    method = "linear" if omega else "off"
    structure = cyclic_structure(disk, TITANIUM, omega=omega, prestress=method)
    freq, nd = _cyclic_spectrum(structure, 2)
    n = 8  # the first family (1 + 2 + 2 + 1 modes) and two of the second
    whole, content = _whole_modes(disk, TITANIUM, n, omega)
    np.testing.assert_allclose(freq[:n], whole, rtol=1e-8)
    np.testing.assert_array_equal(np.argmax(content, axis=1)[:6], np.sort(nd[:6]))
    assert np.all(content.max(axis=1) > 0.999)
    if omega:  # the prestress stiffens the blades
        rest = _cyclic_spectrum(cyclic_structure(disk, TITANIUM), 1)[0]
        assert np.all(freq[:6] > 1.05 * rest[:6])


def test_casing_ring_cyclic_modes_match_the_whole_ring(ring):
    structure = cyclic_structure(ring, STEEL)
    freq, nd = _cyclic_spectrum(structure, 1)
    whole, content = _whole_modes(ring, STEEL, freq.size)
    np.testing.assert_allclose(freq, whole, rtol=1e-8)
    np.testing.assert_array_equal(np.argmax(content, axis=1), nd)
    assert ring.info["distortion"].lobes == 3


def test_harmonic_modes_are_hermitian_and_refuse_a_foreign_nodal_diameter(disk):
    structure = cyclic_structure(disk, TITANIUM)
    f, shapes = harmonic_modes(structure, 1, 2)
    assert f.shape == (2,) and np.iscomplexobj(shapes) and np.all(np.diff(f) > 0)
    with pytest.raises(ValueError, match="nodal diameter 4 outside 0..3"):
        harmonic_modes(structure, 4, 1)
