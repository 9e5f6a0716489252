"""One reductor, many sizes: ``ThermoelasticCraigBampton.reduce(n_uv, n_theta)`` (pyMOR style).

A reductor built at the largest sizes must give, for any smaller sizes, the reduced model a
reductor built directly with those sizes gives (round-off for dense eigen-solves; ARPACK's
tolerance for the 3D blade), and the ``"auto"`` scene reduction must reuse its one reductor.
"""

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import femrub as fr
from femrub.fem.material import Material
from femrub.geometry import box_blade
from femrub.model.rub import solid_model
from femrub.reduction import PROJECTIONS, ThermoelasticCraigBampton, craig_bampton_thermal
from femrub.reduction.sizes import reduce_model
from femrub.reduction.truncation import ColumnMap
from femrub.scene.scene import load_scene

ALPHA = 3.0
#: dense LAPACK eigen-solves (paper bar): the truncated bases agree to round-off
TOL_DENSE = 1e-12
#: ARPACK (3D blade, interior above DENSE_EIGEN_BELOW dofs): its convergence tolerance
TOL_ARPACK = 1e-9


def _rel(a, b) -> float:
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)) if b.size else 0.0


def _arrays(rom) -> dict:
    """Every operator of a reduced model, dense."""
    dense = lambda X: X.toarray() if hasattr(X, "toarray") else np.asarray(X)  # noqa: E731
    out = {"A": dense(rom.A), "B": dense(rom.B), "x0": rom.x0}
    out.update({n: getattr(rom.contact, n) for n in ("G", "Gv", "Hm", "Ht")})
    for i, t in enumerate(rom.loads):
        out[f"load{i}"], out[f"power{i}"] = t.vector, t.power
    out.update({f"obs:{k}": dense(O) for k, O in rom.observations.items()})
    e = rom.energy
    out.update({n: dense(getattr(e, n)) for n in ("Qk", "Qe", "Pth", "Pd")})
    out.update(heat_content=e.heat_content, heat_outflow=e.heat_outflow)
    if rom.to_full is not None:
        out["to_full"] = dense(rom.to_full)
    return out


def _assert_same_model(rom, ref, tol):
    assert rom.layout == ref.layout
    a, b = _arrays(rom), _arrays(ref)
    assert a.keys() == b.keys()
    for k in b:
        assert a[k].shape == b[k].shape, k
        assert _rel(a[k], b[k]) <= tol, k
    for k in ("n_uv", "n_theta", "n_qu", "n_qv", "n_reduced", "projection"):
        assert rom.info[k] == ref.info[k], k


@pytest.fixture(scope="module")
def paper():
    full = fr.bar_model(alpha=ALPHA)
    x0 = np.zeros(full.n_dofs)
    x0[full.layout.t] = np.linspace(0.0, 30.0, full.layout.n_t)  # K: exercises restrict()
    return full.with_(x0=x0)


@pytest.mark.parametrize("projection", PROJECTIONS)
def test_paper_sizes_from_the_full_size_reductor(paper, projection):
    big = ThermoelasticCraigBampton(paper, projection=projection)  # every shape
    assert (big.n_uv, big.n_theta) == (38, 19)
    for sizes in [(3, 12), (2, 5), (7, 0), (0, 4), (38, 19)]:  # RM1, RM2, edges, full basis
        direct = ThermoelasticCraigBampton(paper, *sizes, projection=projection)
        _assert_same_model(big.reduce(*sizes), direct.reduce(), TOL_DENSE)
        Xr = np.random.default_rng(3).standard_normal((4, direct.layout.n))
        assert _rel(big.reconstruct(Xr, *sizes), direct.reconstruct(Xr)) < TOL_DENSE
        X = direct.reconstruct(Xr)
        assert _rel(big.restrict(X, *sizes), direct.restrict(X)) < 1e-9
    # no arguments: the largest sizes, as the reductor's attributes describe them
    rom = big.reduce()
    assert rom.layout == big.layout and rom.info["n_uv"] == big.n_uv
    assert rom.n_dofs == big.R.shape[1] == big.left.shape[1]


def test_dims_errors(paper):
    red = ThermoelasticCraigBampton(paper, 4, 6)
    with pytest.raises(ValueError, match="n_uv"):
        red.reduce(5, 6)
    with pytest.raises(ValueError, match="n_theta"):
        red.reduce(4, 7)
    rom = red.reduce(2, 3)
    with pytest.raises(ValueError, match="entries"):
        red.reconstruct(np.zeros(rom.n_dofs))  # sizes of the largest model by default
    assert red.reconstruct(np.zeros(rom.n_dofs), 2, 3).shape == (paper.n_dofs,)
    with pytest.raises(ValueError, match="already reduced") as err:
        ThermoelasticCraigBampton(rom)
    assert "\n" not in str(err.value)
    rom2, red2 = craig_bampton_thermal(paper, 4, 6)
    assert (red2.n_uv, red2.n_theta) == (4, 6) and rom2.layout == red.layout


@pytest.fixture(scope="module")
def blade():
    """A coarse 3D box blade rubbing a casing (P1, two contact points), interior > 400 dofs."""
    mesh = box_blade(h=0.008, n_contact=2)
    mat = Material(young=110e9, rho=4500.0, rho_c=4500.0 * 585.0, conductivity=7.0)
    model, _ = solid_model(mesh, mat, rotation_speed=1000.0, friction=0.3, order=1, reach="all")
    return model


@pytest.mark.parametrize("projection", ["petrov-galerkin", "adjoint"])
def test_3d_box_blade_sizes_from_one_reductor(blade, projection):
    assert blade.layout.n_u - blade.boundary["u"].size > 400  # ARPACK, not dense LAPACK
    big = ThermoelasticCraigBampton(blade, 20, 16, projection=projection)
    for sizes in [(10, 8), (7, 3)]:
        direct = ThermoelasticCraigBampton(blade, *sizes, projection=projection)
        _assert_same_model(big.reduce(*sizes), direct.reduce(), TOL_ARPACK)


def test_condensed_solve_is_the_full_stiffness_solve(paper, blade):
    assert blade.boundary.get("u_rows") is not None  # contacts on patch means
    for model in (paper, blade):
        red = ThermoelasticCraigBampton(model, 2, 1)
        K = model.blocks.K
        f = np.random.default_rng(5).standard_normal(K.shape[0])
        x = red.stiffness_solver()(f)
        assert _rel(x, spla.spsolve(K.tocsc(), f)) < 1e-8
        assert np.linalg.norm(K @ x - f) < 1e-9 * np.linalg.norm(f)


def test_auto_reduction_reuses_its_reductor(paper):
    scene = load_scene("paper", {"reduction.method": "auto", "reduction.max_n_theta": 12})
    rom, red, report = reduce_model(paper, scene)
    assert (red.n_uv, red.n_theta) == (38, 12)  # the largest sizes allowed
    sizes = report["n_uv"], report["n_theta"]
    assert sizes[0] < red.n_uv and rom.n_dofs == report["n_reduced"]
    _assert_same_model(rom, red.reduce(*sizes), 0.0)
    fixed = load_scene(
        "paper",
        {
            "reduction.method": "craig-bampton",
            "reduction.n_uv": sizes[0],
            "reduction.n_theta": sizes[1],
        },
    )
    rom_fixed, red_fixed, _ = reduce_model(paper, fixed)
    assert (red_fixed.n_uv, red_fixed.n_theta) == sizes
    _assert_same_model(rom, rom_fixed, TOL_DENSE)


def test_interior_solves_by_blocks_and_free(blade, monkeypatch):
    """Sparse right-hand sides solved a few columns at a time equal the dense solve; a
    released solver refuses to solve."""
    from femrub.reduction import interior

    red = ThermoelasticCraigBampton(blade, 4, 2)
    s = red.solver
    n = 2 * s.n_u + s.n_t
    rhs = sp.random(n, 11, density=0.02, random_state=3, format="csc")
    dense_T = s.solve_transposed(rhs.toarray())
    monkeypatch.setattr(interior, "BLOCK", 4)  # 11 columns: blocks of 4, 4, 3
    assert _rel(s.solve(rhs), s.solve(rhs.toarray())) < 1e-12
    assert _rel(s.solve_transposed(rhs), dense_T) < 1e-12
    s.free()
    for solve, size in ((s.solve_K, s.n_u), (s.solve, n), (s.solve_transposed, n)):
        with pytest.raises(RuntimeError, match="released"):
            solve(np.ones(size))
    # the bases are kept: reduce and reconstruct still work without the factorisations
    Xr = np.ones(red.reduce(2, 1).n_dofs)
    assert red.reconstruct(Xr, 2, 1).shape == (blade.n_dofs,)


@pytest.mark.parametrize("projection", PROJECTIONS)
def test_smaller_sizes_are_blocks_of_the_largest_projection(paper, projection, monkeypatch):
    """Once the largest model is projected, a smaller size is sliced from it (no projection
    over the full state) when its elastic-energy basis is ``R`` (``_nested``), and equals the
    model projected at that size; otherwise that size is projected."""
    red = ThermoelasticCraigBampton(paper, 20, 12, projection=projection)
    red.reduce()
    calls = []
    real = red._project
    monkeypatch.setattr(red, "_project", lambda *a: calls.append(a) or real(*a))
    rom = red.reduce(6, 4)
    *_, cols, layout = red._columns(6, 4)
    assert bool(calls) == (not red._nested())
    ref = real(cols, layout)
    assert _rel(rom.A.toarray(), ref["A"]) < TOL_DENSE
    assert _rel(rom.energy.Pd.toarray(), ref["energy"].Pd.toarray()) < 1e-10
    assert _rel(rom.energy.Pth.toarray(), ref["energy"].Pth.toarray()) < 1e-10
    growth = rom.info["energy_growth_rate"]
    assert abs(growth - ref["growth"]) <= 1e-9 * max(1.0, abs(ref["growth"]))


@pytest.mark.parametrize("projection", PROJECTIONS)
def test_a_size_that_does_not_nest_takes_its_projections_from_the_largest(projection):
    """Once the largest model is projected, a size whose elastic-energy basis is its own
    (``_nested()`` false) takes its projected operators as blocks of the largest's (no
    columns of the left basis), equal to that size projected over the full state; a released
    reductor (no left basis) makes it the same, bit for bit."""
    damped = fr.bar_model(alpha=ALPHA, rayleigh=(0.0, 1e-6))  # C_ib: the shapes do not nest
    red = ThermoelasticCraigBampton(damped, 20, 12, projection=projection)
    if red._nested():
        pytest.skip("every size nests (a block of the largest model) with this projection")
    *_, cols, layout = red._columns(6, 4)
    direct = red._project(cols, layout)  # before the largest: over the full state
    red.reduce()
    rel = red.released()
    rom, again = red.reduce(6, 4), rel.reduce(6, 4)
    assert rel.left is None and again is not rom
    for k in ("A", "B"):
        assert _rel(getattr(rom, k).toarray(), direct[k]) < TOL_DENSE
        np.testing.assert_array_equal(getattr(again, k).toarray(), getattr(rom, k).toarray())
    assert _rel(rom.contact.G, direct["contact"].G) < TOL_DENSE
    assert _rel(rom.energy.Qe.toarray(), direct["energy"].Qe.toarray()) < TOL_DENSE
    assert _rel(rom.energy.Pd.toarray(), direct["energy"].Pd.toarray()) < 1e-10


def test_sliced_models_take_the_gap_functions_of_the_reductors_model(paper):
    """``for_model`` shares the projected operators; the gap and load functions are the new
    model's (a point of a speed sweep)."""
    red = ThermoelasticCraigBampton(paper, 8, 6, projection="second-order")
    red.reduce()
    other = paper.with_(contact=dataclasses.replace(paper.contact, gap0=paper.contact.gap0 * 2))
    rom = red.for_model(other).reduce(4, 3)
    assert np.allclose(rom.contact.gap0, 2 * paper.contact.gap0)
    assert _rel(rom.contact.G, red.reduce(4, 3).contact.G) == 0.0
    # the energy forms rest on the matrices only: made once, the same for every speed
    assert rom.energy is red.reduce(4, 3).energy
    fresh = ThermoelasticCraigBampton(paper, 8, 6, projection="second-order")
    fresh.reduce()
    alone = fresh.for_model(other).reduce(4, 3)  # made on ``other``: no size made before
    assert _rel(alone.energy.Pd.toarray(), rom.energy.Pd.toarray()) == 0.0
    assert alone.info["energy_growth_rate"] == rom.info["energy_growth_rate"]


def test_smaller_sizes_share_the_largest_map_to_the_mesh(paper):
    """A smaller size's map to the mesh is the largest model's restricted to its columns,
    shared (:class:`ColumnMap`), not copied; it acts as the dense columns would."""
    red = ThermoelasticCraigBampton(paper, 20, 12, projection="second-order")
    largest = red.reduce()
    rom = red.reduce(6, 4)
    # the largest map is the basis itself with the mesh's constrained rows put back
    assert isinstance(largest.to_full, ColumnMap) and largest.to_full.full is red.R
    assert np.array_equal(np.asarray(largest.to_full), paper.to_full @ red.R)
    assert isinstance(rom.to_full, ColumnMap) and rom.to_full.full is red.R
    *_, cols, _ = red._columns(6, 4)
    dense = (paper.to_full @ red.R)[:, cols]
    direct = ThermoelasticCraigBampton(paper, 6, 4, projection="second-order").reduce()
    assert _rel(np.asarray(rom.to_full), np.asarray(direct.to_full)) < TOL_DENSE
    rng = np.random.default_rng(5)
    x, X = rng.standard_normal(cols.size), rng.standard_normal((cols.size, 3))
    Y = rng.standard_normal((2, dense.shape[0]))
    M = rom.to_full
    assert M.shape == dense.shape and M.dtype == dense.dtype
    assert _rel(M @ x, dense @ x) < 1e-14 and _rel(M @ X, dense @ X) < 1e-14
    assert _rel(M @ sp.csr_matrix(X), dense @ X) < 1e-14
    assert _rel(Y @ M, Y @ dense) < 1e-14
    rows = np.array([0, 3, 5])
    np.testing.assert_array_equal(M[rows], dense[rows])
    plain = ColumnMap(paper.to_full @ red.R, cols)  # no row map: the same rows
    np.testing.assert_array_equal(plain[rows], dense[rows])
    np.testing.assert_array_equal(plain[3], dense[3])
    np.testing.assert_array_equal(M[2:7], dense[2:7])
    np.testing.assert_array_equal(M[rows, 1:4], dense[rows, 1:4])
    np.testing.assert_array_equal(np.asarray(M), dense)
    clamped = np.flatnonzero(np.diff(sp.csr_matrix(paper.to_full).indptr) == 0)
    assert clamped.size and not np.any(M[clamped]) and M[int(clamped[0])].shape == (cols.size,)
    np.testing.assert_array_equal(M[int(clamped[0]) + 1], dense[int(clamped[0]) + 1])
    with pytest.raises(ValueError):
        M @ np.ones(cols.size + 1)
    with pytest.raises(ValueError):
        ColumnMap(dense, [0, 0])


def test_the_elastic_form_on_its_own_basis_without_a_copy_of_the_basis():
    """The elastic form and the thermal-stress work of a size whose elastic basis ``R_z`` is
    not ``R`` are the projections on ``R_z`` (``elastic_basis``, a copy of ``R``), computed
    as the projection on ``R`` plus the terms of the columns that differ."""
    import scipy.sparse as sp

    from femrub.fem.linalg import project
    from femrub.reduction.energy_forms import elastic_basis, reduced_energy

    damped = fr.bar_model(alpha=ALPHA, rayleigh=(0.0, 1e-6))
    red = ThermoelasticCraigBampton(damped, 20, 12, projection="static-mass")
    assert not red._nested()
    rom = red.reduce()
    L, nb = damped.layout, red.boundary["u"].size
    Rz = elastic_basis(damped, nb, red.R, red.layout)
    assert Rz is not red.R and not np.array_equal(Rz, red.R)
    forms, _ = reduced_energy(damped, nb, red.R, rom.A.toarray(), rom.B.toarray(), red.layout)
    P = sp.csr_matrix(damped.energy.Pth)
    P_u = sp.vstack([P[L.v], P[L.u], P[L.t]], format="csr")
    assert _rel(forms.Qe.toarray(), project(Rz, damped.energy.Qe, Rz)) < TOL_DENSE
    assert _rel(forms.Wth.toarray(), project(Rz, P_u, red.R)) < TOL_DENSE
