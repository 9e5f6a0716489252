"""Centrifugal prestress: rotating rod (1D analytic/BVP), Southwell coefficients, invariance."""

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from femrub.fem import centrifugal as cf
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import lowest_modes
from femrub.fem.forms import lame_parameters
from femrub.fem.material import Material
from femrub.fem.prestress import centrifugal_prestress
from femrub.geometry import box_blade


def _rod_tip_growth(R, L, E, rho, omega, nonlinear):
    """Tip growth of a rotating rod (uniaxial, ν = 0), Saint Venant–Kirchhoff or linear.

    d/dX [(1 + u') S] + ρ Ω² (X + u) = 0, S = E (u' + ½ u'²) (or E u'), u(R) = 0, S(R+L) = 0.
    """
    k2 = rho * omega**2 / E

    def strain(N):  # u' from the nominal stress N / E = (1 + e)(e + e²/2)
        e = N.copy()
        for _ in range(60 if nonlinear else 0):
            e -= ((1 + e) * (e + e * e / 2) - N) / ((e + e * e / 2) + (1 + e) ** 2)
        return e

    def f(X, y):
        return np.vstack([strain(y[1]), -k2 * (X + y[0])])

    X = np.linspace(R, R + L, 200)
    sol = solve_bvp(f, lambda a, b: np.array([a[0], b[1]]), X, np.zeros((2, X.size)), tol=1e-10)
    assert sol.success
    return float(sol.sol(R + L)[0])


@pytest.fixture(scope="module")
def rod():
    R, L = 0.2, 0.1
    blade = box_blade(L, 0.01, 0.01, h=0.01, hub_radius=R, n_contact=1)
    return blade, discretise(blade, 2), R, L


@pytest.mark.parametrize("method", ["linear", "nonlinear"])
def test_rotating_rod_tip_growth(rod, method):
    """A 5 % strain rod: FE tip growth = 1D BVP to 1e-4; the two models differ by > 3 %."""
    blade, disc, R, L = rod
    E, rho, omega = 4e9, 8000.0, 1000.0
    ps = centrifugal_prestress(disc, Material(young=E, rho=rho, poisson=0.0), omega, method)
    tip = blade.mesh.p[2] > R + L - 1e-9
    growth = ps.u[disc.basis_u.nodal_dofs[2]][tip]
    ref = _rod_tip_growth(R, L, E, rho, omega, method == "nonlinear")
    other = _rod_tip_growth(R, L, E, rho, omega, method != "nonlinear")
    assert np.allclose(growth, ref, rtol=1e-4)
    assert abs(other - ref) > 0.03 * ref
    assert ps.residual < 1e-9
    assert ps.iterations >= (2 if method == "nonlinear" else 1)


def test_southwell_coefficients():
    """Uniform cantilever spinning about an axis through its root (hub radius 0):
    ω² = ω0² + S Ω² with S = 1.193 (first flapwise mode, displacement along the axis) and
    1.193 − 1 (first lead-lag mode, in the plane of rotation) (Southwell; Wright et al.,
    J. Appl. Mech. 49 (1982) 197)."""
    blade = box_blade(0.2, 0.012, 0.008, h=0.008, n_contact=1)  # axis x: chord = flap
    disc = discretise(blade, 2)
    mat = Material(young=200e9, rho=8000.0, poisson=0.3)
    mats = assemble(disc, mat)
    lam0, V = lowest_modes(mats.K, mats.M, 2)
    Vf = mats.prolongation_u() @ V
    comp = np.argmax([np.abs(Vf[disc.basis_u.nodal_dofs[i]]).max(0) for i in (0, 1)], axis=0)
    assert sorted(comp) == [0, 1]  # one flap (x) and one lag (y) mode
    expected = np.where(comp == 0, 1.1932, 0.1932)
    omega = 600.0
    for method in ("linear", "nonlinear"):
        lam = lowest_modes(centrifugal_prestress(disc, mat, omega, method).K, mats.M, 2)[0]
        S = (lam - lam0) / omega**2
        assert np.allclose(S, expected, rtol=0.015), (method, S)


def test_rigid_rotation_is_stress_free(rod):
    """Total-Lagrangian internal force vanishes under a finite rigid rotation; linear not."""
    _, disc, _, _ = rod
    basis = disc.basis_u
    c, s = np.cos(0.3), np.sin(0.3)
    Q = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    X = basis.doflocs
    comp = np.empty(basis.N, dtype=int)
    for i in range(3):
        comp[basis.nodal_dofs[i]] = i
        comp[basis.edge_dofs[i]] = i
    u = ((Q - np.eye(3)) @ X)[comp, np.arange(basis.N)]
    lam, mu = lame_parameters(110e9, 0.3, 3)
    f_nl = cf.internal_force(basis, u, lam, mu)
    f_lin = cf.internal_force(basis, u, lam, mu, linear=True)
    assert np.linalg.norm(f_nl) < 1e-8 * np.linalg.norm(f_lin)


def test_tangent_is_the_derivative_of_the_residual(rod):
    """K_T(u) δu matches the finite difference of f_int − f_Ω (central, relative 1e-6)."""
    _, disc, _, _ = rod
    basis = disc.basis_u
    rng = np.random.default_rng(0)
    u = 1e-3 * rng.standard_normal(basis.N)
    du = rng.standard_normal(basis.N)
    lam, mu = lame_parameters(110e9, 0.3, 3)
    rho, w2, axis = 4500.0, 1000.0**2, [1, 0, 0]

    def r(x):
        f = cf.internal_force(basis, x, lam, mu)
        return f - cf.centrifugal_force(basis, x, rho * w2, axis)

    KT = cf.tangent_stiffness(basis, u, lam, mu) - w2 * cf.spin_mass(basis, rho, axis)
    eps = 1e-7
    fd = (r(u + eps * du) - r(u - eps * du)) / (2 * eps)
    assert np.linalg.norm(KT @ du - fd) < 1e-6 * np.linalg.norm(fd)


def test_spin_mass_is_the_vector_form(rod):
    """``M_P`` assembled as ``m ⊗ P`` on the scalar basis equals the vector form
    ``∫ ρ P δu · v`` (an oblique axis: every block of ``P`` non-zero)."""
    from skfem import BilinearForm
    from skfem.helpers import dot

    basis = rod[1].basis_u
    axis = [0.3, -0.2, 1.0]
    a = cf.axis_params(axis)

    @BilinearForm
    def form(du, v, w):
        return 4500.0 * dot(cf._radial(a, du), v)

    reference = form.assemble(basis)
    assert cf._scalar_basis(basis) is not None
    difference = abs(cf.spin_mass(basis, 4500.0, axis) - reference).max()
    assert difference <= 1e-12 * abs(reference).max()


def test_warm_start_reaches_the_cold_equilibrium(rod):
    """Started from the prestress at another speed (above or below), Newton reaches the
    equilibrium of a start from rest (5 % strain rod), in fewer iterations from nearby."""
    blade, disc, R, L = rod
    material = Material(young=4e9, rho=8000.0, poisson=0.0)
    cold = centrifugal_prestress(disc, material, 1000.0, "nonlinear")
    for other in (800.0, 1200.0):
        start = centrifugal_prestress(disc, material, other, "nonlinear")
        warm = centrifugal_prestress(disc, material, 1000.0, "nonlinear", start=start)
        assert warm.residual < 1e-9 and warm.omega == 1000.0
        np.testing.assert_allclose(warm.u, cold.u, rtol=0, atol=1e-9 * np.abs(cold.u).max())
        assert abs(warm.K - cold.K).max() <= 1e-7 * abs(cold.K).max()
    near = centrifugal_prestress(disc, material, 990.0, "nonlinear")
    assert (
        centrifugal_prestress(disc, material, 1000.0, "nonlinear", start=near).iterations
        < cold.iterations
    )


def test_a_diverging_load_increment_is_rejected_once(rod):
    """A rod too soft for Newton at the full load (its first correction grows in energy,
    ``Θ₀`` about 3.6) and at half of it: the continuation rejects the full load once, after
    two iterations, and goes straight to the quarter that growth predicts, which converges
    (halving once per rejection would spend two more iterations on the half). It reaches
    the equilibrium of a continuation warm-started from a quarter of the load."""
    blade, disc, R, L = rod
    material = Material(young=7e7, rho=8000.0, poisson=0.3)
    messages = []
    ps = centrifugal_prestress(disc, material, 1000.0, "nonlinear", log=messages.append)
    assert ps.rejected == 1 and ps.increments > 1 and ps.residual < 1e-9
    first = next(i for i, m in enumerate(messages) if "rejected" in m)
    assert sum("Newton iteration" in m for m in messages[:first]) == 2
    assert "next 0.25 of Ω²" in messages[first]
    assert sum("Newton iteration 0," in m for m in messages) == ps.increments + ps.rejected
    quarter = centrifugal_prestress(disc, material, 500.0, "nonlinear")
    again = centrifugal_prestress(disc, material, 1000.0, "nonlinear", start=quarter)
    np.testing.assert_allclose(ps.u, again.u, rtol=0, atol=1e-9 * np.abs(again.u).max())
