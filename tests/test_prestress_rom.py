"""The quadrature-point forms and the reduced prestress against the assembled ones."""

from types import SimpleNamespace

import numpy as np
import pytest
from test_campbell import BOX

from femrub.app import translate as tr
from femrub.app.blade import load_blade
from femrub.fem import centrifugal as cf
from femrub.fem import quadrature
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.forms import lame_parameters
from femrub.fem.linalg import sparse_lu
from femrub.fem.prestress import centrifugal_prestress
from femrub.fem.prestress_rom import enrich, initial_reduced, prestress_problem
from femrub.fem.quadrature import gradient_operator
from femrub.fem.speed_modes import _Ritz, frequency_bounds
from femrub.scene import load_scene


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    path = tmp_path_factory.mktemp("box") / "box.toml"
    path.write_text(BOX.format(method="nonlinear"))
    scene = load_scene(str(path))
    disc = discretise(load_blade(scene), 2)
    material = tr.material_of(scene)
    return disc, material, assemble(disc, material).mechanical()


@pytest.mark.parametrize("linear", [False, True])
def test_quadrature_forms_equal_the_assembled_ones(box, linear):
    """``Bᵀ (w F S)``, ``K_T(u) X`` and ``Wᵀ K_T W`` equal the scikit-fem forms."""
    disc, material, _ = box
    basis = disc.basis_u
    lam, mu = lame_parameters(material.young, material.poisson, 3)
    op = gradient_operator(basis, lam, mu, linear=linear)
    rng = np.random.default_rng(0)
    u = 1e-3 * rng.standard_normal(basis.N)
    f = cf.internal_force(basis, u, lam, mu, linear)
    np.testing.assert_allclose(op.internal_force(u), f, atol=1e-12 * np.abs(f).max())
    K = cf.tangent_stiffness(basis, u, lam, mu, linear)
    X = rng.standard_normal((basis.N, 3))
    np.testing.assert_allclose(op.tangent_action(u, X), K @ X, atol=1e-12 * np.abs(K @ X).max())
    W = rng.standard_normal((basis.N, 4))
    P = op.projected_tangent(u, op.B @ W)
    np.testing.assert_allclose(P, W.T @ (K @ W), rtol=1e-10)
    assembled = op.assemble(op.moduli(op.gradients(u)))
    np.testing.assert_allclose(assembled.toarray(), K.toarray(), atol=1e-12 * abs(K).max())
    forms = op.quadratic_forms(op.gradients(u), (op.B @ W).reshape(-1, 9, 4))
    np.testing.assert_allclose(forms, np.diag(W.T @ (K @ W)), rtol=1e-10)


def test_chunked_forms_equal_the_whole_products(box, monkeypatch):
    """By chunks of quadrature points (7 here, the last one shorter): ``Wᵀ K_T W``, the
    sum of the chunks' ``B_cᵀ V`` and the Ritz residuals' ``K_T W Y`` with their quadratic
    forms at another state equal the products over all points at once."""
    disc, material, _ = box
    lam, mu = lame_parameters(material.young, material.poisson, 3)
    op = gradient_operator(disc.basis_u, lam, mu)
    monkeypatch.setattr(quadrature, "CHUNK", 7)
    assert op.n_points % 7 and len(op.chunks()) > 2
    rng = np.random.default_rng(2)
    u, other = 1e-3 * rng.standard_normal((2, disc.basis_u.N))
    W = rng.standard_normal((disc.basis_u.N, 5))
    BW = op.B @ W
    K = cf.tangent_stiffness(disc.basis_u, u, lam, mu, False)
    np.testing.assert_allclose(op.project(op.gradients(u), BW), W.T @ (K @ W), rtol=1e-10)
    V = rng.standard_normal((op.B.shape[0], 3))
    summed = np.zeros((op.B.shape[1], 3))
    for lo, hi in op.chunks():
        op.add_transposed(lo, V[9 * lo : 9 * hi], summed)
    np.testing.assert_allclose(summed, op.B.T @ V, atol=1e-12 * np.abs(op.B.T @ V).max())
    ritz = SimpleNamespace(setting=SimpleNamespace(problem=SimpleNamespace(op=op)), BW=BW)
    Y = rng.standard_normal((5, 3))
    KX, forms = _Ritz._tangent_applied(ritz, op.gradients(u), Y, op.gradients(other), 2)
    np.testing.assert_allclose(KX, K @ (W @ Y), atol=1e-12 * np.abs(K @ (W @ Y)).max())
    K_other = cf.tangent_stiffness(disc.basis_u, other, lam, mu, False)
    X = W @ Y[:, :2]
    np.testing.assert_allclose(forms, np.einsum("ij,ij->j", X, K_other @ X), rtol=1e-10)


def test_energy_polynomial_is_the_projected_energy(box):
    """The reduced force and tangent of the quartic energy are ``Vᵀ f_int(V q)`` and
    ``Vᵀ K_T(V q) V`` of the full forms (random basis and coordinates)."""
    disc, material, mats = box
    lu = sparse_lu(mats.K, symmetric=True)
    problem = prestress_problem(disc, material, "nonlinear", mats.K, lu.solve)
    reduced = initial_reduced(problem)
    rng = np.random.default_rng(1)
    # two vectors at once, then one: Γ grown row block by row block
    reduced = reduced.enriched(rng.standard_normal((problem.free.size, 2)))
    reduced = reduced.enriched(rng.standard_normal(problem.free.size))
    q = 1e-3 * rng.standard_normal(4) / np.sqrt(np.diag(reduced.V.T @ (mats.K @ reduced.V)))
    u = reduced.displacement(q)
    V = reduced.full
    op = problem.op
    f = V.T @ op.internal_force(u)
    np.testing.assert_allclose(reduced.energy.force(q), f, rtol=1e-9, atol=1e-12 * abs(f).max())
    K = V.T @ op.tangent_action(u, V)
    np.testing.assert_allclose(reduced.energy.tangent(q), K, rtol=1e-9, atol=1e-9 * abs(K).max())


def test_reduced_prestress_equals_the_full_newton(box):
    """Certified to η ≤ 1e-8 along a speed list, the reduced prestress is the full Newton
    solution (relative 1e-6) at speeds that were not training speeds."""
    disc, material, mats = box
    lu = sparse_lu(mats.K, symmetric=True)
    problem = prestress_problem(disc, material, "nonlinear", mats.K, lu.solve)
    speeds = np.array([700.0, 1900.0, 3100.0, 4000.0])
    reduced, q, eta, _ = enrich(initial_reduced(problem), speeds**2, 1e-8)
    assert eta.max() <= 1e-8
    for omega, x in zip(speeds[[0, 2]], q[[0, 2]], strict=True):
        full = centrifugal_prestress(disc, material, omega, "nonlinear").u
        rel = np.linalg.norm(reduced.displacement(x) - full) / np.linalg.norm(full)
        assert rel < 1e-6, (omega, rel)


def test_frequency_bounds():
    """Exact Ritz pairs have zero bounds; with a wide gap the bound is Kato–Temple's
    ``ε² / gap`` in the pencil ``M x = μ K x``, quadratic in the residual."""
    lam = np.array([1.0e6, 4.0e6, 9.0e6])
    assert np.allclose(frequency_bounds(lam, np.zeros(3), 2), 0.0)
    res = np.full(3, 1.0)  # ‖ρ‖_{K⁻¹}: 1e-3 of √λ₁
    small = frequency_bounds(lam, res, 2)
    assert np.all(frequency_bounds(lam, 10 * res, 2) > 50 * small)
    mu, eps = 1 / lam, res / lam**1.5
    delta = eps[0] ** 2 / (mu[0] - mu[1] - eps[1])
    assert small[0] == pytest.approx(1 - np.sqrt(mu[0] / (mu[0] + delta)), rel=1e-12)


@pytest.mark.parametrize("newton", [False, True])
def test_corrections_together_equal_each_alone(box, newton):
    """Speeds corrected together (residuals on threads, one back-substitution or one
    conjugate-gradient run per factorisation for all of them) give each speed's correction
    and ``η`` as that speed corrected alone; the speeds nearest each factorisation use it."""
    disc, material, mats = box
    lu = sparse_lu(mats.K, symmetric=True)
    problem = prestress_problem(disc, material, "nonlinear", mats.K, lu.solve)
    speeds = np.array([900.0, 2500.0, 3600.0, 4000.0])
    reduced = initial_reduced(problem)
    top = reduced.displacement(reduced.path(speeds[-1:] ** 2)[0])
    op = problem.op
    K_top = (op.assemble(op.moduli(op.gradients(top))) - speeds[-1] ** 2 * problem.MP)[
        problem.free
    ][:, problem.free]
    problem.add_factor(speeds[-1] ** 2, sparse_lu(K_top.tocsr(), symmetric=True).solve)
    assert [problem.nearest(s) for s in speeds**2] == [0, 0, 1, 1]
    u = np.array([reduced.displacement(x) for x in reduced.path(speeds**2)])
    eta, d = problem.corrections(u, speeds**2, newton=newton)
    for k in range(speeds.size):
        eta_k, d_k = problem.corrections(u[k : k + 1], speeds[k : k + 1] ** 2, newton=newton)
        assert eta[k] == pytest.approx(eta_k[0], rel=1e-9)
        np.testing.assert_allclose(d[k], d_k[0], rtol=0, atol=1e-9 * np.abs(d_k).max())
    assert np.all(eta > 0)
    if not newton:  # each speed's residual back-substituted with its nearest factorisation
        for k, f in ((0, 0), (3, 1)):
            alone = problem.factors[f][1](problem.residual(u[k], speeds[k] ** 2))
            np.testing.assert_allclose(d[k], alone, rtol=0, atol=1e-9 * np.abs(alone).max())
    if newton:  # the Newton correction is not the back-substitution alone
        plain = problem.corrections(u, speeds**2, newton=False)[1]
        assert np.abs(plain - d).max() > 1e-3 * np.abs(d).max()
