"""Modal Rayleigh damping through the reduction's interior factorisation.

:func:`~femrub.reduction.modal_damping.modal_rayleigh` takes the full blade's frequencies by
static condensation on ``K_ii`` (the stiffness without the contact dofs) instead of a
factorisation of ``K``: the coefficients must be those of
:func:`~femrub.fem.discretisation.assemble`'s ``damping_ratio`` (ARPACK's tolerance), for
contacts on nodes and on patch means, and the reductor given that factorisation must build
the bases it builds with its own.
"""

import numpy as np
import pytest

from femrub.app.cache import ModelCache
from femrub.app.simulation import build
from femrub.contact.casing import Concentric
from femrub.contact.points import locate_contacts
from femrub.fem.damping import rayleigh_coefficients
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import angular_frequencies
from femrub.fem.material import Material
from femrub.geometry import box_blade
from femrub.model.build import contact_boundary
from femrub.model.rub import rub_model
from femrub.reduction import ThermoelasticCraigBampton
from femrub.reduction.interior import InteriorStiffness
from femrub.reduction.modal_damping import modal_rayleigh
from femrub.scene.scene import load_scene

MAT = Material(young=110e9, rho=4500.0, rho_c=4500.0 * 585.0, conductivity=7.0)
ZETA = 0.02


@pytest.fixture(scope="module")
def blade():
    """A coarse P1 box blade (interior above the dense eigen-solver size: ARPACK)."""
    disc = discretise(box_blade(h=0.008, n_contact=3), order=1)
    return disc, assemble(disc, MAT, coupling="none")


@pytest.mark.parametrize("spread", ["node", "patch"])
def test_modal_rayleigh_is_the_full_stiffness_damping(blade, spread):
    disc, mats = blade
    points = locate_contacts(disc, spread=spread)
    seen = []

    def damping(m, boundary):
        seen.append(boundary)
        return modal_rayleigh(m, ZETA, (1, 5), boundary)[0]

    model, _ = rub_model(disc, mats, points, MAT, casing=Concentric(1e-4), damping=damping)
    assert (seen[0].get("u_rows") is not None) == (spread == "patch")
    assert np.array_equal(seen[0]["u"], model.boundary["u"])
    ref = assemble(disc, MAT, coupling="none", damping_ratio=ZETA, damping_modes=(1, 5))
    a, b = model.blocks.info["rayleigh"]
    assert np.allclose((a, b), ref.info["rayleigh"], rtol=1e-8, atol=0.0)
    assert abs(model.blocks.C - ref.C).max() <= 1e-8 * abs(ref.C).max()
    assert model.info["rayleigh"] == (a, b)
    assert mats.info.get("rayleigh") == (0.0, 0.0)  # the undamped blocks are left alone


def test_reductor_reuses_the_damping_factorisation(blade):
    disc, mats = blade
    points = locate_contacts(disc, spread="node")
    kept = []

    def damping(m, boundary):
        damped, stiffness, _ = modal_rayleigh(m, ZETA, (1, 5), boundary)
        kept.append(stiffness)
        return damped

    model, _ = rub_model(disc, mats, points, MAT, casing=Concentric(1e-4), damping=damping)
    stiffness = kept[0]
    for projection in ("static-mass", "second-order"):
        own = ThermoelasticCraigBampton(model, 12, 0, projection=projection)
        shared = ThermoelasticCraigBampton(model, 12, 0, projection=projection, stiffness=stiffness)
        assert shared.solver._lu_K is stiffness.lu
        assert np.allclose(shared.R, own.R, rtol=0.0, atol=1e-9 * np.abs(own.R).max())
        assert np.allclose(shared.omega2, own.omega2, rtol=1e-10)
    other = InteriorStiffness(2.0 * model.blocks.K, model.boundary["u"])
    with pytest.raises(ValueError, match="not this model's K_ii"):
        ThermoelasticCraigBampton(model, 4, 0, stiffness=other)
    stiffness.free()
    with pytest.raises(RuntimeError, match="released"):
        stiffness.solve_K(np.ones(stiffness.mech_i.size))


def test_contact_boundary_is_the_model_boundary(blade):
    disc, mats = blade
    for spread in ("node", "patch"):
        points = locate_contacts(disc, spread=spread)
        model, _ = rub_model(disc, mats, points, MAT, casing=Concentric(1e-4), friction=0.3)
        seen = {}

        def damping(m, bnd, seen=seen):
            seen.update(bnd)
            return m

        rub_model(disc, mats, points, MAT, casing=Concentric(1e-4), friction=0.3, damping=damping)
        assert np.array_equal(seen["u"], model.boundary["u"])
        if "u_rows" in model.boundary:
            assert (seen["u_rows"] != model.boundary["u_rows"]).nnz == 0
    assert contact_boundary(None, mats.n_u)["u"].size == 0


def test_damping_stage_is_cached(tmp_path):
    """The pipeline's damping: a second build takes ``(a, b)`` from the cache, same ``C``."""
    over = {
        "physics.damping_ratio": 0.005,
        "scheme.t_end": 2e-5,
        "outputs.vtk_stride": 0,
        "reduction.method": "craig-bampton",
        "reduction.n_uv": 8,
        "reduction.n_theta": 0,
        "reduction.tolerance": 1.0,
        "loads.centrifugal": "off",
        "physics.thermal": "off",
    }
    scene = load_scene("twisted-naca", over)
    cache = ModelCache(tmp_path / "cache")
    lines = []
    first = build(scene, cache=cache, log=lines.append)
    assert any(t.startswith("modal damping 0.005") for t in lines)
    b = first.full.blocks
    w = angular_frequencies(b.K, b.M, 5)  # the full stiffness factorised
    ref = rayleigh_coefficients(0.005, w[0], w[4])
    assert np.allclose(b.info["rayleigh"], ref, rtol=1e-8, atol=0.0)
    lines.clear()
    second = build(scene, cache=cache, log=lines.append)
    assert not any(t.startswith("modal damping") for t in lines)
    assert any("cache: damping loaded" in t for t in lines)
    assert second.full.blocks.info["rayleigh"] == b.info["rayleigh"]
    assert abs(second.full.blocks.C - b.C).max() == 0.0


@pytest.mark.parametrize("modes", [4, 7])
def test_the_reported_frequencies_come_from_the_damping_s_eigen_solve(tmp_path, monkeypatch, modes):
    """A build that reports natural frequencies finds them in the damping's eigen-solve
    (through the interior factorisation, with as many modes as it needs beyond the damped
    ones): no second eigen-solve, the frequencies of a factorisation of ``K``."""
    import femrub.app.cached as cached

    solves = []
    own = cached.natural_frequencies
    monkeypatch.setattr(cached, "natural_frequencies", lambda m, k: solves.append(k) or own(m, k))
    over = {"physics.damping_ratio": 0.005, "physics.damping_modes": [1, 2]}
    scene = load_scene("twisted-naca", over)
    cache = ModelCache(tmp_path / "cache")
    sim = build(scene, cache=cache, modes=modes, stepper=False)
    assert solves == []
    b = sim.full.blocks
    ref = angular_frequencies(b.K, b.M, modes) / (2 * np.pi)
    assert np.allclose(sim.report["natural_frequencies_hz"], ref, rtol=1e-9, atol=0.0)
    lines = []  # and stored for the next build (another sweep worker)
    again = build(scene, cache=cache, modes=modes, stepper=False, log=lines.append)
    assert any("cache: frequencies loaded" in t for t in lines) and solves == []
    assert again.report["natural_frequencies_hz"] == sim.report["natural_frequencies_hz"]


def test_each_mode_of_the_run_s_model_reports_its_own_rayleigh_ratio():
    """``physics.damping_ratio`` is Rayleigh damping: the run's model has the ratio asked at
    the two damping modes, its own ``a / 2ω + b ω / 2`` at every other one, and
    ``--explain`` lists them."""
    from test_cache import SMALL

    from femrub.app.simulation import build
    from femrub.model.modes import damped_modes
    from femrub.scene import load_scene

    scene = load_scene(
        "twisted-naca",
        {**SMALL, "scheme.t_end": 2e-5, "physics.damping_ratio": 0.005, "reduction.n_uv": 12},
    )
    sim = build(scene)
    d = sim.report["damping"]
    f, z = np.array(d["frequency_hz"]), np.array(d["ratio"])
    a, b = d["rayleigh"]
    w = 2 * np.pi * f
    # Rayleigh, mode by mode: the coupled model's eigenvalues move a ratio by about 1e-8 from
    # build to build (up to 2e-6 relative); modal damping would differ by O(1)
    np.testing.assert_allclose(z, a / (2 * w) + b * w / 2, rtol=1e-5)
    assert z[0] == pytest.approx(0.005, rel=1e-3) and z[4] == pytest.approx(0.005, rel=1e-2)
    assert np.all(z[1:4] < 0.005) and z[-1] > 0.005  # less between, more above
    assert "each mode its own ratio" in sim.explain() and f"{f[0]:.5g} Hz" in sim.explain()
    import femrub as fr

    undamped = damped_modes(fr.bar_model())
    assert np.max(np.abs(undamped["ratio"])) < 1e-12 and undamped["rayleigh"] == [0.0, 0.0]
