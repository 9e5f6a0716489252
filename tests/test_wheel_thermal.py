"""The blades' temperature on a bladed disk: the reduced wheel against the whole wheel.

The whole wheel is the sector's mesh turned N times (``full_wheel``), assembled as one
structure. A constant heat input at one contact of one blade has a steady temperature and a
steady thermal expansion; the reduced wheel (thermal modes and static heat shapes per nodal
diameter, the disk's bases holding the static responses to the thermal stresses of every
temperature shape) reproduces both to round-off on every blade, and its heat content is the
whole wheel's.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree
from small_wheel import TITANIUM, N, disk_sector
from test_cyclic_modes import _located

from femrub.fem.discretisation import assemble, discretise
from femrub.geometry.cyclic_sector import axis_rotation, full_wheel
from femrub.model.cyclic import cyclic_structure
from femrub.model.cyclic_thermal import expansion_rows, heat_rows_with_content, thermal_sector
from femrub.model.wheel import (
    CasingSurface,
    WheelConfig,
    contact_heat_rows,
    contact_rows_of_sector,
    tip_contacts,
    wheel_model,
    wheel_thermal,
)
from femrub.output.wheel_vtk import WheelFields
from femrub.reduction.cyclic_ritz import cyclic_bases

HEATED_BLADE, HEATED_CONTACT = 2, 1
POWER = 50.0  # W


@pytest.fixture(scope="module")
def reduced():
    sector = disk_sector()
    structure = cyclic_structure(sector, TITANIUM)
    thermal = thermal_sector(structure, TITANIUM)
    contacts = tip_contacts(structure, 2)
    heat = contact_heat_rows(thermal, contacts)
    (temperature,) = cyclic_bases(thermal.structure, [2], heat_rows_with_content(thermal, heat))
    normal, tangent = contact_rows_of_sector(structure, contacts)
    contact = sp.vstack([normal, tangent])
    expansion = expansion_rows(thermal, temperature)
    (disk,) = cyclic_bases(structure, [3], lambda k: sp.vstack([contact, expansion(k)]).tocsr())
    wheel = wheel_thermal(thermal, temperature, disk, contacts)
    return sector, structure, thermal, contacts, disk, wheel


@pytest.fixture(scope="module")
def whole(reduced):
    sector = reduced[0]
    mesh, _ = full_wheel(sector)
    disc = discretise(mesh, 2)
    return disc, assemble(disc, TITANIUM)


def _copy_dofs(sector_locs, whole_locs, s, angle):
    """Indices in ``whole_locs`` of the sector's dof locations turned into copy ``s``."""
    turned = axis_rotation(s * angle) @ sector_locs
    dist, idx = cKDTree(whole_locs.T).query(turned.T)
    assert dist.max() < 1e-9
    return idx


def _steady(reduced):
    """The reduced wheel's steady temperature and displacement coordinates under ``POWER``
    at the heated contact: ``diag(μ) η = Hᵀ q`` and ``diag(ω̂²) x = −K^uθ η``."""
    *_, disk, wheel = reduced
    q = np.zeros(wheel.heat_rows.shape[0])
    q[HEATED_BLADE * reduced[3].n + HEATED_CONTACT] = POWER
    eta = (wheel.heat_rows.T @ q) / wheel.basis.omega**2
    x = -(wheel.Kut @ eta) / disk.omega**2
    return eta, x


def _whole_steady(reduced, whole):
    """The whole wheel's steady temperature and displacement (every dof) under the same
    heat, put in at the heated contact's weights on the heated blade's copy."""
    sector, structure, thermal, contacts, *_ = reduced
    disc, mats = whole
    bt = thermal.structure.basis
    dofs = _copy_dofs(bt.doflocs, disc.basis_t.doflocs, HEATED_BLADE, sector.angle)
    f = np.zeros(disc.basis_t.N)
    weights = sp.csr_matrix(contacts.heat)[HEATED_CONTACT].toarray().ravel()
    np.add.at(f, dofs, POWER * weights)
    theta = np.zeros(disc.basis_t.N)
    theta[mats.free_t] = spla.spsolve(mats.Ktt.tocsc(), f[mats.free_t])
    u = np.zeros(disc.basis_u.N)
    u[mats.free_u] = spla.spsolve(mats.K.tocsc(), -(mats.Kut @ theta[mats.free_t]))
    return theta, u


def test_steady_temperature_and_expansion_are_the_whole_wheels(reduced, whole):
    sector, structure, thermal, contacts, disk, wheel = reduced
    disc, _ = whole
    eta, x = _steady(reduced)
    theta, u = _whole_steady(reduced, whole)
    t_free = thermal.structure.free
    bt, bu = thermal.structure.basis, structure.basis
    located = _located(bu)
    whole_located = _located(disc.basis_u)
    tree = cKDTree(disc.basis_u.doflocs[:, whole_located[:, 0]].T)
    u_scale = np.abs(u).max()
    for s in range(N):
        # temperature: scalar, the same in the sector's and the whole wheel's axes
        field = np.zeros(bt.N)
        field[t_free] = wheel.basis.sector_field(eta, s)
        idx = _copy_dofs(bt.doflocs, disc.basis_t.doflocs, s, sector.angle)
        assert np.abs(field - theta[idx]).max() <= 1e-8 * theta.max()
        # displacement: the whole wheel's turned back into the sector's axes
        disp = np.zeros(bu.N)
        disp[structure.free] = disk.sector_field(x, s)
        turn = axis_rotation(s * sector.angle)
        dist, at = tree.query((turn @ bu.doflocs[:, located[:, 0]]).T)
        assert dist.max() < 1e-9
        back = u[whole_located[at]] @ turn  # rows u_wholeᵀ R = (Rᵀ u_whole)ᵀ
        assert np.abs(disp[located] - back).max() <= 1e-8 * u_scale
    assert theta.max() > 0.0 and u_scale > 0.0
    # the heated blade is the hottest, its contact the hottest point
    contact_t = wheel.heat_rows @ eta
    assert np.argmax(contact_t) == HEATED_BLADE * contacts.n + HEATED_CONTACT


def test_heat_content_and_outflow_are_the_whole_wheels(reduced, whole):
    """``Σ_s 1ᵀ C^θθ θ_s`` of the reduced coordinates equals the whole wheel's for any
    temperature of the basis, and so does the heat flowing out through the bores."""
    sector, structure, thermal, contacts, disk, wheel = reduced
    disc, mats = whole
    eta = np.random.default_rng(3).standard_normal(wheel.basis.size)
    theta = np.zeros(disc.basis_t.N)
    bt = thermal.structure.basis
    for s in range(N):
        field = np.zeros(bt.N)
        field[thermal.structure.free] = wheel.basis.sector_field(eta, s)
        theta[_copy_dofs(bt.doflocs, disc.basis_t.doflocs, s, sector.angle)] = field
    ones = np.ones(mats.free_t.size)
    content = ones @ (mats.Ctt @ theta[mats.free_t])
    outflow = ones @ (mats.Ktt @ theta[mats.free_t])
    assert wheel.heat_content @ eta == pytest.approx(content, rel=1e-9)
    assert wheel.heat_outflow[1] @ eta == pytest.approx(outflow, rel=1e-9)
    # the uniform temperature is in the basis: the heat content's field is exactly 1
    uniform = wheel.basis.sector_rows(thermal.structure.M @ np.ones(thermal.structure.free.size))
    assert np.allclose(wheel.heat_rows @ wheel.heat_content, 1.0, atol=1e-9)
    assert uniform.shape[0] == N


def test_the_rotors_frames_draw_every_blades_temperature(reduced):
    """The whole wheel's ``temperature`` point data is the temperature coordinates' sector
    field of copy ``s`` at the sector's vertices (a scalar: no turn)."""
    sector, structure, thermal, contacts, disk, wheel = reduced
    config = WheelConfig(rotation_speed=0.0, clearance=1e-4, friction=0.1)
    surface = CasingSurface(heat_law="power", heat_partition=0.5)
    tip = sector.info["tip_radius"]
    model, wheel_map = wheel_model(
        config,
        structure,
        disk,
        contacts,
        tip_radius=tip,
        blade_size=0.03,
        surface=surface,
        thermal=wheel,
    )
    assert model.layout.n_t == wheel.basis.size and wheel_map.temperature is wheel.basis
    fields = WheelFields(wheel_map, structure, None, 0.0, 1.0, thermal.structure)
    frames = fields.parts()["rub"](fields, model, 1e-6, np.float64)
    X = np.zeros(model.layout.n)
    eta = np.random.default_rng(5).standard_normal(wheel.basis.size)
    X[model.layout.t] = eta
    c = frames.compact(X[None], np.zeros((1, model.n_contacts)))
    t = thermal.structure
    vertex = t.basis.nodal_dofs[0]
    held = np.ones(t.basis.N, dtype=bool)
    held[t.free] = False
    for s in range(N):
        field = np.zeros(t.basis.N)
        field[t.free] = wheel.basis.sector_field(eta, s)
        got = c["temperature"][0, frames.map.copies[s], 0]
        np.testing.assert_allclose(got, field[vertex], rtol=0, atol=1e-10 * np.abs(field).max())
    assert np.all(c["temperature"][0, frames.map.copies[0][held[vertex]], 0] == 0.0)
    assert "temperature" in frames.writer.data
