"""3D blades: assembly against exact solutions, box vs 1D bar, many contacts, VTK output."""

import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest
import scipy.sparse.linalg as spla
import skfem as fem

import femrub as fr
from femrub.contact.casing import Concentric, Lobed, TwoLobePiollet, casing_profile
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import angular_frequencies
from femrub.geometry import GeometryError, box_blade
from femrub.model.rub import solid_model
from femrub.output.vtk import VTKSeries

P = fr.PAPER


def test_cantilever_bending_converges_to_euler_bernoulli():
    E, rho, L, b, t = 110e9, 4500.0, 0.1, 0.01, 0.002
    mat = fr.Material(young=E, rho=rho, poisson=0.3)
    w_eb = 1.8751**2 * np.sqrt(E * b * t**3 / 12 / (rho * b * t * L**4))
    errs = []
    for h in (0.01, 0.005, 0.0025):
        mats = assemble(discretise(box_blade(span=L, chord=b, thickness=t, h=h)), mat)
        errs.append(angular_frequencies(mats.K, mats.M, 1)[0] / w_eb - 1)
    assert errs[0] > errs[1] > errs[2] > 0  # stiff from above, converging
    assert errs[2] < 0.01


def _block(n=3):
    mesh = fem.MeshTet.init_tensor(*(np.linspace(0, s, n + 1) for s in (0.2, 0.1, 0.05)))
    bu = fem.Basis(mesh, fem.ElementVector(fem.ElementTetP2()))
    return mesh, bu, bu.with_element(fem.ElementTetP1())


def test_free_thermal_expansion_3d_block_exact():
    mesh, bu, bt = _block()
    mat = fr.Material(young=200e9, rho=7800.0, poisson=0.3, expansion=12e-6)
    # symmetry planes: u_x = 0 on x = 0, u_y = 0 on y = 0, u_z = 0 on z = 0 (free expansion)
    fixed = np.concatenate(
        [bu.get_dofs(lambda x, c=c: np.isclose(x[c], 0.0)).all(f"u^{c + 1}") for c in range(3)]
    )
    mats = fr.assemble_thermoelastic(bu, bt, mat, lumping="hrz", fixed_u=fixed)
    theta = 80.0
    u = spla.spsolve(mats.K.tocsc(), -(mats.Kut @ np.full(mats.n_t, theta)))
    full = mats.prolongation_u() @ u
    exact = 12e-6 * theta * bu.doflocs  # u = α θ x, componentwise
    comp = np.arange(bu.N) % 3
    assert np.allclose(full, exact[comp, np.arange(bu.N)], atol=1e-12 * 0.2)


def test_steady_heat_conduction_exact():
    mesh, bu, bt = _block(4)
    mat = fr.Material(young=200e9, rho=7800.0, conductivity=15.0)
    hot, cold = bt.get_dofs(lambda x: np.isclose(x[0], 0.2)), bt.get_dofs(lambda x: x[0] < 1e-12)
    mats = fr.assemble_thermoelastic(bu, bt, mat, fixed_t=np.r_[hot.all(), cold.all()])
    from femrub.fem import forms

    Kfull = forms.conductivity.assemble(bt, k=15.0, area=1.0)
    T = np.zeros(bt.N)
    T[hot.all()] = 100.0
    rhs = -(Kfull @ T)[mats.free_t]
    T[mats.free_t] = spla.spsolve(mats.Ktt.tocsc(), rhs)
    assert np.allclose(T, 100.0 * bt.doflocs[0] / 0.2, atol=1e-9)  # linear profile, exact


@pytest.fixture(scope="module")
def slender_box():
    rho = P.total_mass / (P.area * P.length)
    mat = fr.Material(young=P.young, rho=rho, poisson=0.0, rho_c=4500 * 585.0, conductivity=3.35)
    blade = box_blade(span=P.length, chord=1e-3, thickness=1e-3, h=0.01, n_contact=1)
    return blade, mat


def test_slender_box_axial_frequency_matches_bar(slender_box):
    blade, mat = slender_box
    disc = discretise(blade)
    mats, bu = assemble(disc, mat, coupling="none"), disc.basis_u
    w_ax = np.pi / 2 * np.sqrt(P.young / mat.rho) / P.length
    w2, V = spla.eigsh(mats.K.tocsc(), k=8, M=mats.M.tocsc(), sigma=(0.9 * w_ax) ** 2)
    z = np.arange(bu.N)[mats.free_u] % 3 == 2  # span along z
    m = mats.M.diagonal()
    share = np.array([(V[z, k] ** 2 * m[z]).sum() / (V[:, k] ** 2 * m).sum() for k in range(8)])
    k = int(np.argmax(share))
    assert share[k] > 0.9
    assert np.sqrt(w2[k]) == pytest.approx(w_ax, rel=0.01)


def test_slender_box_contact_matches_bar(slender_box):
    blade, mat = slender_box
    model, _ = solid_model(
        blade,
        mat,
        casing=Concentric(P.gap),
        coupling="none",
        tip_force=(np.array([0.0, 0.0, 7.0]), lambda t: np.sin(P.force_frequency * t)),
    )
    assert model.layout.n_t == 0  # nothing thermal asked: no temperature dofs
    r3 = fr.ThetaMethod(model, 1e-5).run(0.04)
    r1 = fr.ThetaMethod(fr.bar_model(coupling="none", alpha=0.0), 1e-5).run(0.04)
    assert r3.first_contact_time() == pytest.approx(r1.first_contact_time(), abs=5e-5)
    assert r3.impulse.sum() == pytest.approx(r1.impulse.sum(), rel=0.02)
    assert r3.force.sum(axis=1).max() == pytest.approx(r1.force.max(), rel=0.15)


@pytest.fixture(scope="module")
def rub():
    blade = box_blade(span=0.1, chord=0.03, thickness=0.003, h=0.006, hub_radius=0.3, n_contact=5)
    mat = fr.Material(young=110e9, rho=4500.0, rho_c=4500 * 585.0, conductivity=7.0)
    model, fields = solid_model(
        blade,
        mat,
        casing=Lobed(clearance=2e-6, depth=3e-6, lobes=2),
        rotation_speed=1000.0,
        friction=0.05,
    )
    return model, fields


def test_many_contacts_lcp_complementarity(rub):
    model, _ = rub
    assert model.n_contacts == 5 and model.layout.n_t > 0
    c = model.contact  # Coulomb μ on every contact, the casing sliding past at Ω r
    assert np.all(c.friction == 0.05) and c.heat_law == "power"
    assert np.allclose(c.casing_velocity[:, 1], -1000.0 * 0.4, rtol=1e-3)  # r = 0.4 m
    prev, several = None, 0
    for s in fr.ThetaMethod(model, 1e-5, activation="paper").iterate(0.004):
        P_ = s.impulse
        assert np.all(P_ >= 0)
        several += int((P_ > 0).sum() >= 2)
        if prev is not None:
            e = np.where(prev > 0, 1.0, 0.0)
            U = (s.gap_velocity + e * prev) / (1 + e)
            tol = 1e-9 * (1 + np.abs(s.gap_velocity).max())
            assert np.all(U[P_ > 0] >= -tol) and np.all(np.abs(P_ * U) <= tol * (1 + P_.max()))
        prev = s.gap_velocity.copy()
    assert several > 10
    # default rule: no impulse at an open gap, several contacts at once
    prev, several = None, 0
    for s in fr.ThetaMethod(model, 1e-5).iterate(0.004):
        several += int((s.impulse > 0).sum() >= 2)
        assert np.all(s.impulse >= 0) and np.all(s.gap[s.impulse > 0] <= 1e-15)
    assert several > 10


def test_vtk_series_reads_back(rub, tmp_path):
    model, fields = rub
    h = 1e-5
    series = VTKSeries(tmp_path / "vtk", model, fields, h=h, stride=100)
    res = fr.ThetaMethod(model, h).run(0.002, on_state=series)
    assert res.status == "ok"
    root = ET.parse(series.pvd_path).getroot()
    sets = root.findall("./Collection/DataSet")
    times = [float(d.get("timestep")) for d in sets]
    assert times == pytest.approx(np.arange(0, 0.002 + 1e-12, 100 * h))
    last = meshio.read(tmp_path / "vtk" / sets[-1].get("file"))
    assert last.points.shape == (fields.mesh.p.shape[1], 3)
    for name, width in (("displacement", 3), ("velocity", 3), ("contact_force", 3)):
        assert last.point_data[name].shape == (last.points.shape[0], width)
    assert last.point_data["temperature"].shape == (last.points.shape[0],)
    vm = last.cell_data["von_mises"][0]
    assert vm.shape == (fields.mesh.t.shape[1],) and np.all(vm >= 0) and vm.max() > 0
    # the tip temperature in the file is the run's
    tip_T = float(res.signal("tip_temperature")[-1])
    w = fields.contacts.heat[:, fields.vertex_dofs_t].mean(axis=0).A1
    assert float(w @ last.point_data["temperature"]) == pytest.approx(tip_T, rel=1e-6)


def test_casing_profiles():
    two = TwoLobePiollet()
    ang = np.linspace(0, 2 * np.pi, 2001)
    g = two.gap(ang)
    assert g.max() == pytest.approx(0.356e-3, rel=1e-3) and g.min() == pytest.approx(-0.356e-3)
    assert np.sum(np.diff(np.sign(g)) != 0) == 4  # two lobes: four crossings per revolution
    for prof in (two, Lobed(1e-4, 2e-4, 3)):
        num = np.gradient(prof.gap(ang), ang)
        assert np.allclose(prof.slope(ang)[5:-5], num[5:-5], atol=1e-3 * np.abs(num).max())
    with pytest.raises(ValueError, match="unknown casing profile"):
        casing_profile("square")


def test_missing_groups_and_bad_inputs():
    blade = box_blade(span=0.1, chord=0.03, thickness=0.003, h=0.01)
    mat = fr.Material(young=110e9, rho=4500.0)
    blade.node_sets.pop("root")
    with pytest.raises(GeometryError, match="root"):
        solid_model(blade, mat)
    blade = box_blade(span=0.1, chord=0.03, thickness=0.003, h=0.01)
    with pytest.raises(ValueError, match="order"):
        solid_model(blade, mat, order=3)
    with pytest.raises(ValueError, match="heat_partition"):
        solid_model(blade, mat, heat_partition=2.0)
    from femrub.geometry import read_abaqus

    with pytest.raises(GeometryError, match="unit"):
        read_abaqus(__file__, length_unit="furlong")
