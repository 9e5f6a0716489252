"""femrub campbell: certified reduced prestress and Ritz frequencies, MAC tracking, files."""

import json

import numpy as np
import pytest

from femrub.app.campbell import campbell, parse_speeds
from femrub.app.cli import main
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import lowest_modes
from femrub.fem.prestress import centrifugal_prestress
from femrub.scene import SceneError, load_scene

BOX = """
name = "box-spin"
[geometry]
kind = "box"
span = 0.2
chord = 0.012
thickness = 0.008
h = 0.01
n_contact = 2
[material]
young = 200e9
density = 8000.0
poisson = 0.3
[loads]
rotation_speed = 600.0
centrifugal = "{method}"
[scheme]
h = 1e-5
t_end = 1e-4
"""


def _scene(tmp_path, method):
    path = tmp_path / f"box-{method}.toml"
    path.write_text(BOX.format(method=method))
    return load_scene(str(path))


def test_parse_speeds():
    assert np.allclose(parse_speeds("0:1800:10")[[0, -1]], [0, 1800])
    assert parse_speeds("0:1800:10").size == 181
    assert np.allclose(parse_speeds("0,900,1800"), [0, 900, 1800])
    with pytest.raises(SceneError, match="--speeds"):
        parse_speeds("0:abc")


def test_campbell_nonlinear_matches_full_solves(tmp_path):
    """Reduced frequencies = full prestress + eigen-solve at a speed that is no sample; lines
    start at the clamped frequencies and the lead-lag/flap lines rise (Southwell)."""
    scene = _scene(tmp_path, "nonlinear")
    res = campbell(scene, parse_speeds("0:1200:100"), modes=3, samples=3)
    assert res.info["status"] == "ok" and res.info["max_error_bound"] < 1e-3
    assert 700.0 not in res.info["sample_speeds"]
    assert res.info["worst_tracking_mac"] > 0.9
    disc = discretise(scene_blade(scene), 2)
    from femrub.app import translate as tr

    mats = assemble(disc, tr.material_of(scene))
    f0 = np.sqrt(lowest_modes(mats.K, mats.M, 3, vectors=False)) / (2 * np.pi)
    assert np.allclose(res.frequencies[0], f0, rtol=1e-6)
    # an independent full solve at a tabulated speed
    ps = centrifugal_prestress(disc, tr.material_of(scene), 700.0, "nonlinear")
    f = np.sqrt(lowest_modes(ps.K, mats.M, 3, vectors=False)) / (2 * np.pi)
    i = int(np.flatnonzero(res.speeds == 700.0)[0])
    assert np.allclose(np.sort(res.frequencies[i]), f, rtol=1e-4)
    assert np.all(np.diff(res.frequencies[:, :2], axis=0) > 0)


def scene_blade(scene):
    from femrub.app.blade import load_blade

    return load_blade(scene)


def test_campbell_cli_linear(tmp_path):
    """Linear prestress: the first modal samples suffice; CSV and PNG."""
    _scene(tmp_path, "linear")
    out = tmp_path / "cb"
    code = main(
        [
            "campbell",
            str(tmp_path / "box-linear.toml"),
            "--speeds",
            "0:1000:250",
            "--modes",
            "3",
            "-o",
            str(out),
            "-q",
        ]
    )
    assert code == 0
    doc = json.loads((out / "campbell.json").read_text())
    assert doc["sample_speeds"][0] == 0 and doc["sample_speeds"][-1] == 1000
    assert doc["max_error_bound"] < 1e-3
    table = np.loadtxt(out / "campbell.csv", delimiter=",", skiprows=1)
    assert table.shape == (5, 5) and np.allclose(table[:, 0], [0, 250, 500, 750, 1000])
    assert (out / "campbell.png").stat().st_size > 10_000


def _cli(tmp_path, out, *extra):
    return main(
        ["campbell", str(tmp_path / "box-nonlinear.toml"), "--modes", "3", "-o", str(out), "-q"]
        + list(extra)
    )


def test_a_failed_self_check_exits_nonzero_and_marks_its_files(tmp_path, capsys):
    """A tolerance no residual bound meets, refinement forbidden (--max-samples 2): exit 1,
    one line, the files say failed and no campbell.csv / campbell.png is written."""
    _scene(tmp_path, "nonlinear")
    out = tmp_path / "cb"
    code = _cli(
        tmp_path, out, "--speeds", "0:4000:1000", "--max-samples", "2", "--tolerance", "1e-13"
    )
    assert code == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "self-check failed" in err and "--max-samples" in err
    doc = json.loads((out / "campbell.json").read_text())
    assert doc["status"] == "failed" and doc["max_error_bound"] > doc["tolerance"]
    assert doc["files"] == ["campbell-failed.csv", "campbell-failed.png"]
    assert (out / "campbell-failed.csv").exists() and (out / "campbell-failed.png").exists()
    assert not (out / "campbell.csv").exists() and not (out / "campbell.png").exists()


def _full(scene, omega, modes=3):
    """Frequencies (Hz) of the full prestress and eigen-solve at ``omega``, and the state."""
    from femrub.app import translate as tr

    disc = discretise(scene_blade(scene), 2)
    mats = assemble(disc, tr.material_of(scene))
    ps = centrifugal_prestress(disc, tr.material_of(scene), omega, "nonlinear")
    return np.sqrt(lowest_modes(ps.K, mats.M, modes, vectors=False)) / (2 * np.pi), ps, disc


def test_the_bounds_hold_and_refine_to_the_tolerance(tmp_path):
    """Up to 4000 rad/s with the two first samples: samples are added until every bound is
    within 0.5 %; at requested speeds the full solve's frequencies lie within each bound
    (a bound that fails to bound fails here); the tip growth is the runs' at every speed."""
    from femrub.contact.points import locate_contacts

    scene = _scene(tmp_path, "nonlinear").with_changes({"contact.spread": "node"})
    res = campbell(scene, parse_speeds("0:4000:500"), modes=3, samples=2)
    info = res.info
    assert info["status"] == "ok" and max(info["error_bounds"]) <= 0.005 == info["tolerance"]
    assert info["prestress_residual_max"] <= 1e-3
    for omega in (1500.0, 3500.0):
        f, top, disc = _full(scene, omega)
        i = int(np.flatnonzero(res.speeds == omega)[0])
        error = np.max(np.abs(np.sort(res.frequencies[i]) - f) / f)
        assert error <= info["error_bounds"][i] + 1e-6, (omega, error, info["error_bounds"][i])
        growth = top.growth(locate_contacts(disc, spread="node"))
        assert info["tip_growth_max_m"][i] == pytest.approx(growth.max(), rel=1e-6)
        assert info["tip_growth_mean_m"][i] == pytest.approx(growth.mean(), rel=1e-6)


def test_exact_diagram_is_the_full_solve_at_every_speed(tmp_path):
    """--exact: each speed's frequencies are its own full prestress and eigen-solve (the
    prestress warm-started along the list), status exact, tip growth per speed."""
    from femrub.app import translate as tr

    _scene(tmp_path, "nonlinear")
    out = tmp_path / "cb"
    assert _cli(tmp_path, out, "--speeds", "0:1200:400", "--exact") == 0
    doc = json.loads((out / "campbell.json").read_text())
    assert doc["status"] == "exact" and doc["sample_speeds"] == [0.0, 400.0, 800.0, 1200.0]
    assert len(doc["tip_growth_max_m"]) == 4 and doc["tip_growth_max_m"][0] == 0.0
    table = np.loadtxt(out / "campbell.csv", delimiter=",", skiprows=1)
    scene = _scene(tmp_path, "nonlinear")
    disc = discretise(scene_blade(scene), 2)
    mats = assemble(disc, tr.material_of(scene))
    ps = centrifugal_prestress(disc, tr.material_of(scene), 800.0, "nonlinear")
    f = np.sqrt(lowest_modes(ps.K, mats.M, 3, vectors=False)) / (2 * np.pi)
    np.testing.assert_allclose(np.sort(table[2, 2:]), f, rtol=1e-7)  # CSV: 8 digits
    np.testing.assert_allclose(table[0, 2:], doc["rest_frequencies_hz"], rtol=1e-7)


def test_bounds_back_substituted_together_equal_one_speed_at_a_time(tmp_path, monkeypatch):
    """The speeds' residuals back-substituted together, by groups that share their nearest
    factorisation, give each speed the bounds it gets from its own solve."""
    from femrub.app import translate as tr
    from femrub.fem import speed_modes as sm

    scene = _scene(tmp_path, "nonlinear")
    disc = discretise(scene_blade(scene), 2)
    material = tr.material_of(scene)
    mats = assemble(disc, material).mechanical()
    speeds = parse_speeds("0:1200:100")
    args = (disc, material, mats, "nonlinear", speeds)
    together = sm.speed_modes(*args, modes=3, samples=3, max_samples=3)
    monkeypatch.setattr(sm, "SPEEDS_PER_SOLVE", 1)
    alone = sm.speed_modes(*args, modes=3, samples=3, max_samples=3)
    # residuals over SOLVE_BYTES: one speed per solve too, whatever SPEEDS_PER_SOLVE says
    monkeypatch.setattr(sm, "SPEEDS_PER_SOLVE", 32)
    monkeypatch.setattr(sm, "SOLVE_BYTES", 1)
    solves = []
    bounds = sm._Ritz._bounds

    def counted(out, *rest):
        solves.append(len(out))
        return bounds(out, *rest)

    monkeypatch.setattr(sm._Ritz, "_bounds", staticmethod(counted))
    capped = sm.speed_modes(*args, modes=3, samples=3, max_samples=3)
    assert solves == [1] * speeds.size
    np.testing.assert_allclose(capped.bounds, alone.bounds, rtol=1e-7, atol=1e-14)
    assert np.all(np.isfinite(together.bounds)) and together.bounds.max() > 0
    np.testing.assert_allclose(together.bounds, alone.bounds, rtol=1e-7, atol=1e-14)
    np.testing.assert_allclose(together.frequencies, alone.frequencies, rtol=1e-10)
