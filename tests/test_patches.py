"""Contacts on tip patches (femrub.contact.patches) and their boundary coordinates in the
Craig–Bampton reduction (femrub.reduction.boundary_coordinates)."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla

import femrub as fr
from femrub.contact.casing import Concentric
from femrub.contact.points import locate_contacts
from femrub.fem.discretisation import assemble, discretise
from femrub.geometry import box_blade
from femrub.model.rub import rub_model
from femrub.reduction.craig_bampton import ThermoelasticCraigBampton

MAT = fr.Material(young=110e9, rho=4500.0, rho_c=4500.0 * 585.0, conductivity=7.0)


def _blade(h, n_contact=3):
    blade = box_blade(
        span=0.1, chord=0.02, thickness=0.01, h=h, hub_radius=0.3, n_contact=n_contact
    )
    disc = discretise(blade)
    return blade, disc, assemble(disc, MAT, coupling="none")


@pytest.fixture(scope="module")
def box():
    blade, disc, mats = _blade(0.01)
    points = locate_contacts(disc)
    model, _ = rub_model(
        disc, mats, points, MAT, casing=Concentric(1e-6), friction=0.2, rotation_speed=1000.0
    )
    return blade, disc, mats, points, model


def test_patches_partition_the_tip_face_and_average_displacements(box):
    blade, disc, mats, points, _ = box
    assert points.patch is not None and points.patch.shape == (3 * points.n, disc.basis_u.N)
    P = points.mean_rows(mats)
    np.testing.assert_allclose(np.asarray(P.sum(axis=1)).ravel(), 1.0)  # weights sum to 1
    # a rigid translation d has the patch mean d, along every component
    d = np.array([1e-3, -2e-3, 5e-4])
    comp = np.arange(disc.basis_u.N) % 3  # skfem interleaves the components
    u = d[comp][mats.free_u]
    np.testing.assert_allclose((P @ u).reshape(points.n, 3), np.tile(d, (points.n, 1)))
    # every tip vertex is in some patch, the force spread is the heat's
    tip = blade.require("tip")
    assert np.all(np.asarray(points.heat[:, tip].sum(axis=0)).ravel() > 0)
    used = np.unique(disc.basis_u.nodal_dofs[:, tip])
    assert set(np.unique(points.patch.indices)) == set(used)


def test_node_spread_acts_on_the_node_alone(box):
    _, disc, mats, points, _ = box
    nodes = locate_contacts(disc, spread="node")
    assert nodes.patch is None
    N = nodes.normal_rows(mats)
    assert N.nnz <= 3 * nodes.n and set(N.indices) <= set(mats.u_index(nodes.u_dofs.ravel()))
    assert points.normal_rows(mats).nnz > N.nnz  # the patches spread over the tip
    with pytest.raises(ValueError, match="spread must be one of"):
        locate_contacts(disc, spread="area")


def test_reduced_boundary_coordinates_are_the_patch_means(box):
    _, _, mats, points, model = box
    red = ThermoelasticCraigBampton(model, 12, 0, projection="static-mass")
    assert red.coordinates is not None
    L, Lr, nb = model.layout, red.layout, red.boundary["u"].size
    Ru = red.R[L.u][:, Lr.u]
    P = points.mean_rows(mats)
    PR = P @ Ru
    # each boundary coordinate is one patch mean (in the masters' order), the modes keep
    # every patch mean at zero
    np.testing.assert_allclose(np.sort(np.abs(PR[:, :nb]), axis=1)[:, -1], 1.0, atol=1e-12)
    np.testing.assert_allclose(np.abs(PR[:, :nb]).sum(axis=1), 1.0, atol=1e-12)
    assert np.abs(PR[:, nb:]).max() < 1e-12
    # the static response to patch forces is in the basis (Eq. 11 in patch coordinates)
    f = P.T @ np.random.default_rng(3).standard_normal(P.shape[0])
    u = spla.spsolve(mats.K.tocsc(), f)
    q = np.linalg.solve(Ru.T @ (mats.K @ Ru), Ru.T @ f)
    assert np.linalg.norm(Ru @ q - u) < 1e-9 * np.linalg.norm(u)
    assert np.linalg.norm(red.stiffness_solver()(f) - u) < 1e-9 * np.linalg.norm(u)
    # the reduced contacts act on the boundary coordinates alone
    rom = red.reduce()
    assert np.abs(rom.contact.G[nb : Lr.n_u]).max() < 1e-12
    assert np.abs(rom.contact.Gvt[Lr.v.start + nb : Lr.v.stop]).max() < 1e-12


def test_bases_change_coordinates_a_few_columns_at_a_time_with_the_same_numbers(box, monkeypatch):
    """``T̃ V`` and ``L̃ V`` taken in blocks of columns (the temporaries of a 0.6 GB basis) are
    the products of the whole basis, bit for bit."""
    from femrub.reduction import boundary_coordinates as bc

    *_, model = box
    red = ThermoelasticCraigBampton(model, 12, 0, projection="static-mass")
    coords, L = red.coordinates, model.layout
    V = np.random.default_rng(5).standard_normal((model.n_dofs, 11))
    right = V.copy()
    right[L.u], right[L.v] = coords.T @ V[L.u], coords.T @ V[L.v]
    left = V.copy()
    left[L.u], left[L.v] = coords.T_inv.T @ V[L.u], coords.T @ V[L.v]
    monkeypatch.setattr(bc, "COLUMN_BLOCK", 4)
    np.testing.assert_array_equal(coords.right(V.copy(), L), right)
    np.testing.assert_array_equal(coords.left(V.copy(), L), left)


def test_patch_compliance_converges_with_the_mesh():
    # radial compliance of a tip contact under a unit force: a point force on a node of a 3D
    # mesh has none that converges (it grows like log(1/h) as the mesh resolves the node);
    # the tip face's mean converges
    out = {"node": [], "patch": []}
    for h in (0.01, 0.005, 0.0033):
        _, disc, mats = _blade(h, n_contact=1)
        lu = spla.splu(mats.K.tocsc())
        for spread, c in out.items():
            n = locate_contacts(disc, spread=spread).normal_rows(mats).toarray()[0]
            c.append(n @ lu.solve(n))
    node, patch = np.diff(out["node"]), np.diff(out["patch"])
    assert node[0] > 0 and node[1] > 0.8 * node[0]  # no sign of levelling off
    assert abs(patch[1]) < 0.5 * abs(patch[0]) and abs(patch[1]) < 0.05 * out["patch"][-1]
