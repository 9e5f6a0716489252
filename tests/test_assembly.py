"""Assembly against closed-form references: statics, free expansion, axial frequencies."""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse.linalg as spla
import skfem as fem

import femrub as fr
from femrub.cases.analytic import (
    fixed_free_frequencies,
    free_thermal_expansion,
    static_tip_deflection,
)

CASE = fr.PAPER


def test_paper_bar_sizes_and_lumped_mass():
    mats, tip = fr.bar_matrices(CASE)
    assert mats.n_u == mats.n_t == 20
    m = mats.M.diagonal()
    assert np.allclose(m[:-1], 0.1 / 20) and np.isclose(m[tip], 0.1 / 40)
    assert np.isclose(mats.M.sum(), 0.1 - 0.1 / 40)  # the clamped root node holds m/2n
    # the heat capacity lumped the same way: rho c A L / n per node, half at the tip
    node = CASE.density * CASE.specific_heat * CASE.area * CASE.length / 20
    c = mats.Ctt.diagonal()
    assert np.allclose(c[:-1], node, rtol=1e-12) and np.isclose(c[tip], node / 2, rtol=1e-12)
    model = fr.bar_model(CASE)
    assert model.n_dofs == 60  # u, v, θ on 20 free nodes (paper: n^uv = 38 + 2, n^θ = 19 + 1)


def test_static_tip_deflection():
    mats, tip = fr.bar_matrices(CASE)
    f = np.zeros(mats.n_u)
    f[tip] = 7.0
    u = spla.spsolve(mats.K.tocsc(), f)
    exact = static_tip_deflection(7.0, CASE.length, CASE.young, CASE.area)
    assert u[tip] == pytest.approx(exact, rel=1e-12)
    assert exact > CASE.gap  # the paper's load closes the 15 µm gap (19.1 µm)


@pytest.mark.parametrize("n", [1, 7, 20])
def test_free_thermal_expansion_physical_coupling(n):
    case = CASE.with_(coupling="physical", expansion=8.6e-6, n_elements=n)
    mats, tip = fr.bar_matrices(case)
    theta = np.full(mats.n_t, 50.0)  # uniform rise (root dof held at 0 is not in θ)
    mesh = fem.MeshLine(np.linspace(0, case.length, n + 1))
    bu = fem.Basis(mesh, fem.ElementVector(fem.ElementLineP1()))
    bt = fem.Basis(mesh, fem.ElementLineP1())
    full = fr.assemble_thermoelastic(
        bu, bt, case.material, area=case.area, coupling="physical", fixed_u=[0]
    )
    u = spla.spsolve(full.K.tocsc(), -(full.Kut @ np.full(full.n_t, 50.0)))
    exact = free_thermal_expansion(8.6e-6, 50.0, case.length)
    assert u[-1] == pytest.approx(exact, rel=1e-10)
    assert np.allclose(u, 8.6e-6 * 50.0 * mesh.p[0, 1:], rtol=1e-10)
    assert mats.Kut.shape == (n, n) and np.isfinite(theta).all()


def test_paper_coupling_is_beta_times_stiffness():
    mats, _ = fr.bar_matrices(CASE)
    assert np.allclose((mats.Kut - CASE.beta * mats.K).toarray(), 0.0)
    theta = np.linspace(0, 10, mats.n_t)
    u = spla.spsolve(mats.K.tocsc(), -(mats.Kut @ theta))
    assert np.allclose(u, -CASE.beta * theta)  # static expansion u = -β θ, β < 0 expands


@pytest.mark.parametrize("lumping,n,tol", [("row-sum", 20, 4e-3), ("consistent", 200, 2e-5)])
def test_axial_frequencies(lumping, n, tol):
    case = CASE.with_(lumping=lumping, n_elements=n)
    mats, _ = fr.bar_matrices(case)
    w2 = sla.eigh(mats.K.toarray(), mats.M.toarray(), eigvals_only=True)[:3]
    exact = fixed_free_frequencies(case.length, case.young, case.rho_mass, 3)
    assert np.allclose(np.sqrt(w2), exact, rtol=tol * np.arange(1, 4) ** 2)


def test_frequencies_converge_with_mesh():
    errs = []
    for n in (10, 20, 40):
        mats, _ = fr.bar_matrices(CASE.with_(n_elements=n, lumping="consistent"))
        w = np.sqrt(sla.eigh(mats.K.toarray(), mats.M.toarray(), eigvals_only=True)[0])
        errs.append(
            abs(w / fixed_free_frequencies(CASE.length, CASE.young, CASE.rho_mass, 1)[0] - 1)
        )
    assert errs[0] > errs[1] > errs[2]
    assert errs[1] / errs[2] == pytest.approx(4.0, rel=0.05)  # second order in the mesh size


def test_hrz_lumping_keeps_p2_masses_positive():
    mesh = fem.MeshTet().refined(1)
    basis = fem.Basis(mesh, fem.ElementVector(fem.ElementTetP2()))
    from femrub.fem import forms
    from femrub.fem.lumping import hrz, row_sum

    M = forms.mass.assemble(basis, rho=7800.0, area=1.0)
    assert row_sum(M).diagonal().min() <= 0.0  # the trap HRZ avoids
    Ml = hrz(M, 3)
    assert Ml.diagonal().min() > 0.0
    assert Ml.sum() == pytest.approx(M.sum(), rel=1e-12)


def test_thermal_dofs_dropped_when_not_needed():
    model = fr.bar_model(CASE, coupling="none", alpha=0.0)
    assert model.layout.n_t == 0 and model.n_dofs == 40
    assert "temperature" in model.info["dropped"][0]
    assert "tip_temperature" not in model.observations
    kept = fr.bar_model(CASE, coupling="none", alpha=1.0)  # heat input alone keeps θ
    assert kept.layout.n_t == 20
