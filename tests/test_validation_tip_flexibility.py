"""The Rotor 37 contact-flexibility page (femrub against CalculiX at the contact dofs) is
what ``benchmarks/calculix_rotor37.py --render-only`` writes from its committed, stamped
JSON; the flexibility it measures is the static one minus the kept modes' part; without
the shared data or ``ccx`` the benchmark skips and writes nothing."""

import json

import numpy as np
import pytest
import scipy.linalg as sla


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("calculix_rotor37")


@pytest.fixture(scope="module")
def doc(bench):
    return json.loads(bench.DATA.read_text())


def _system(n=30, seed=3):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    K = A @ A.T + n * np.eye(n)
    B = rng.standard_normal((n, n))
    M = B @ B.T / n + np.eye(n)
    return K, M


def test_static_flexibility_is_the_inverse_stiffness_at_the_dofs(bench):
    K, M = _system()
    rows = np.array([4, 7, 19])
    flex = bench.contact_flexibility(K, M, rows, kept=3)
    np.testing.assert_allclose(flex["static"], np.linalg.inv(K)[np.ix_(rows, rows)], rtol=1e-10)
    lam, V = sla.eigh(K, M, subset_by_index=[0, 2])  # mass-normalised
    np.testing.assert_allclose(flex["modal"], (V[rows] / lam) @ V[rows].T, rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(flex["residual"], flex["static"] - flex["modal"], atol=1e-15)
    np.testing.assert_allclose(flex["frequency_hz"], np.sqrt(lam) / (2 * np.pi), rtol=1e-10)


def test_every_mode_kept_leaves_no_residual_flexibility(bench):
    K, M = _system(12)
    flex = bench.contact_flexibility(K, M, np.arange(4), kept=12)
    assert np.abs(flex["residual"]).max() < 1e-10 * np.abs(flex["static"]).max()


def test_page_is_what_the_json_renders(bench, doc):
    assert bench.PAGE.read_text() == bench.render(doc), (
        "docs/validation/rotor37-tip-flexibility.md differs from what "
        "`python benchmarks/calculix_rotor37.py --render-only` writes from its JSON"
    )


def test_page_is_stamped_and_measured_on_the_48_contact_dofs(bench, doc):
    page = bench.PAGE.read_text()
    stamp = doc["machine"]
    assert stamp["commit"] and stamp["date"] in page and stamp["commit"] in page
    assert doc["ccx_version"] in page and len(doc["contact_nodes"]) == 16
    for side in ("ccx", "femrub"):
        assert np.asarray(doc[side]["static"]).shape == (48, 48)
    ratio = np.asarray(doc["comparison"]["static"]["diagonal_ratio"])
    assert ratio.shape == (48,) and (ratio > 0).all()


def test_exported_matrices_give_the_frequencies_of_the_ccx_run(doc):
    np.testing.assert_allclose(
        doc["ccx_matrix_frequency_hz"], doc["ccx"]["frequency_hz"], rtol=1e-4
    )


def test_render_reads_its_numbers_from_the_json(bench, doc):
    changed = json.loads(json.dumps(doc))
    changed["comparison"]["static"]["diagonal_ratio"][0] = 9.0
    changed["comparison"]["all_nodes_x"] = 1.5
    text = bench.render(changed)
    assert "+800.0 %" in text and "x: +50.0 %" in text and "9.000×" in text


def test_page_is_in_the_validation_section(bench):
    assert "validation/rotor37-tip-flexibility" in (bench.DOCS / "validation.md").read_text()


def test_benchmark_skips_without_the_shared_data(bench, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("FEMRUB_SHARED_DATA", str(tmp_path / "absent"))
    monkeypatch.setattr(bench, "DATA", tmp_path / "flex.json")
    monkeypatch.setattr(bench, "MODES_DATA", tmp_path / "modes.json")
    monkeypatch.setattr(bench, "PAGE", tmp_path / "flex.md")
    bench.main([])
    assert "skipped: no Rotor 37 deck" in capsys.readouterr().out
    assert not list(tmp_path.iterdir())


def test_femrub_tetrahedra_in_calculix_have_femrub_flexibility(bench, load_benchmark):
    """The C3D10 export of a femrub discretisation, solved by ccx, has femrub's static
    flexibility at a tip corner: the two codes assemble the same quadratic tetrahedra."""
    import skfem

    from femrub.fem.discretisation import assemble, discretise
    from femrub.fem.material import Material
    from femrub.geometry.blade_mesh import BladeMesh

    if load_benchmark("_calculix").ccx_executable() is None:
        pytest.skip("ccx (calculix-ccx) is not installed")
    axes = (np.linspace(0, 0.04, 5), np.linspace(0, 0.01, 3), np.linspace(0, 0.01, 3))
    mesh = skfem.MeshTet.init_tensor(*axes)
    corner = int(np.flatnonzero((mesh.p == [[0.04], [0.01], [0.01]]).all(axis=0))[0])
    blade = BladeMesh(
        mesh=mesh,
        node_sets={
            "root": np.flatnonzero(mesh.p[0] == 0),
            "tip": np.flatnonzero(mesh.p[0] > 0.039),
        },
        contact_points=mesh.p[:, [corner]],
        radial_axis="z",
        source="beam",
        info={
            "edge_midpoints": 0.5 * (mesh.p[:, mesh.edges[0]] + mesh.p[:, mesh.edges[1]]),
            "contact_map": {"vertex": np.array([corner])},
        },
    )
    disc = discretise(blade, 2)
    material = Material(young=210e9, rho=9000.0, poisson=0.3, rho_c=1.0, conductivity=1.0)
    mats = assemble(disc, material, lumping="consistent").mechanical()
    fem = bench.femrub_side(disc, mats)
    ccx = bench.tet10_side(disc)
    np.testing.assert_allclose(ccx["static"], fem["static"], rtol=1e-6)
    np.testing.assert_allclose(ccx["frequency_hz"][:3], fem["frequency_hz"][:3], rtol=1e-3)


def test_refinement_study_measures_point_and_face_flexibility(bench):
    """Two coarse levels: a point force's flexibility is above the uniform traction's and
    both grow as the mesh resolves more deformation (the committed study goes further)."""
    study = bench.refinement_study((1, 2))
    point, face = np.array(study["point"]), np.array(study["face"])
    assert study["n_free_dofs"][1] > study["n_free_dofs"][0]
    assert (point > face).all() and (np.diff(point) > 0).all() and (np.diff(face) > 0).all()
    # Euler-Bernoulli end deflection P L^3 / (3 E I) of the 40 x 10 x 10 mm beam, 1 N
    beam = 0.04**3 / (3 * 210e9 * 0.01**4 / 12)
    assert 0.9 * beam < face[-1] < 1.3 * beam


def test_page_shows_the_refinement_study_from_the_json(bench, doc):
    ref = doc["refinement"]
    page = bench.PAGE.read_text()
    assert f"| {ref['point'][-1] * 1e6:.4f} |" in page and ref["machine"]["commit"] in page
