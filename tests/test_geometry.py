"""Tests of the gmsh blade builders, BladeMesh I/O, errors and the mesh CLI."""

from __future__ import annotations

import os
from pathlib import Path

import gmsh
import numpy as np
import pytest

from femrub.geometry import (
    BladeMesh,
    GeometryError,
    box_blade,
    length_scale,
    naca_blade,
    read_mesh,
    rotor37_sections_blade,
)
from femrub.geometry.cli import main as mesh_cli
from femrub.geometry.gmsh_session import gmsh_session
from femrub.geometry.naca import naca4_sides
from femrub.geometry.sections import read_section
from femrub.geometry.tet_ops import edge_lengths, tet_volumes

SHARED = Path(
    os.environ.get(
        "FEMRUB_SHARED_DATA", Path(__file__).resolve().parents[1].parent / "shared" / "data"
    )
)


@pytest.fixture(scope="module")
def sections_dir() -> Path:
    folder = SHARED / "rotor37-sections"
    if not folder.is_dir():
        pytest.skip(
            f"Rotor 37 sections not found at {folder}"
            " (set FEMRUB_SHARED_DATA to the shared data folder)"
        )
    return folder


@pytest.fixture(scope="module")
def box() -> BladeMesh:
    return box_blade(span=0.08, chord=0.02, thickness=0.004, h=0.004, hub_radius=0.3, n_contact=6)


@pytest.fixture(scope="module")
def naca() -> BladeMesh:
    return naca_blade(
        "2412", span=0.1, root_chord=0.05, tip_chord=0.035, twist=30.0, n_sections=4, h=0.005
    )


def _one_line_error(excinfo, *words: str) -> None:
    message = str(excinfo.value)
    assert "\n" not in message
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"


# ---------------------------------------------------------------- box blade
def test_box_volume_exact(box):
    assert box.volume() == pytest.approx(0.08 * 0.02 * 0.004, rel=1e-10)
    assert box.info["cad_volume"] == pytest.approx(0.08 * 0.02 * 0.004, rel=1e-10)
    assert np.all(tet_volumes(box.mesh.p, box.mesh.t) > 0)


def test_box_root_and_tip_planes(box):
    z = box.mesh.p[2]
    root, tip = box.require("root"), box.require("tip")
    np.testing.assert_allclose(z[root], 0.3, atol=1e-12)
    np.testing.assert_allclose(z[tip], 0.38, atol=1e-12)
    assert set(root) == set(np.flatnonzero(np.abs(z - 0.3) < 1e-12))
    assert set(tip) == set(np.flatnonzero(np.abs(z - 0.38) < 1e-12))


def test_box_contact_points_on_tip_centre_line(box):
    c = box.contact_points
    assert c.shape == (3, 6)
    np.testing.assert_allclose(c[2], 0.38, atol=1e-12)
    np.testing.assert_allclose(c[1], 0.0, atol=1e-12)
    np.testing.assert_allclose(c[0], np.linspace(0.001, 0.019, 6), atol=1e-12)
    contact = box.require("contact")
    np.testing.assert_allclose(box.mesh.p[:, contact], c, atol=1e-14)
    assert set(contact) <= set(box.node_sets["tip"])
    # machine axis x: the casing radial direction at the tip centre line is +z
    np.testing.assert_allclose(
        box.radial_direction(), np.tile([[0.0], [0.0], [1.0]], 6), atol=1e-12
    )


def test_box_mesh_size_controls_count():
    coarse = box_blade(h=0.006, n_contact=0)
    fine = box_blade(h=0.003, n_contact=0)
    assert fine.n_tets > 2 * coarse.n_tets
    assert edge_lengths(coarse.mesh.p, coarse.mesh.t).max() < 2.0 * 0.006


# ---------------------------------------------------------------- NACA blade
def test_naca_volume_matches_occ(naca):
    assert naca.volume() == pytest.approx(naca.info["cad_volume"], rel=1e-2)
    assert np.all(tet_volumes(naca.mesh.p, naca.mesh.t) > 0)


def test_naca_untwisted_volume_matches_section_area_integral():
    upper, lower = naca4_sides("0012", 4000)
    x, y = np.hstack([upper, lower[:, ::-1]])
    area = 0.5 * abs(x @ np.roll(y, -1) - y @ np.roll(x, -1))
    cr, ct, span = 0.05, 0.035, 0.1
    expected = area * span * (cr * cr + cr * ct + ct * ct) / 3  # chord linear in span
    blade = naca_blade("0012", span, cr, ct, twist=0.0, h=0.006, n_contact=0)
    assert blade.info["cad_volume"] == pytest.approx(expected, rel=2e-3)
    assert blade.volume() == pytest.approx(expected, rel=2e-2)


def test_naca_tip_twisted_by_requested_angle(naca):
    p, tip, root = naca.mesh.p, naca.require("tip"), naca.require("root")
    ct, cr, angle = 0.035, 0.05, np.radians(30.0)
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])

    def nearest(nodes, xyz):
        d = np.linalg.norm(p[:, nodes] - np.asarray(xyz)[:, None], axis=0)
        return p[:, nodes[np.argmin(d)]], d.min()

    le_t, d1 = nearest(tip, [*(rot @ [-0.25 * ct, 0.0]), 0.1])
    te_t, d2 = nearest(tip, [*(rot @ [0.75 * ct, 0.0]), 0.1])
    le_r, d3 = nearest(root, [-0.25 * cr, 0.0, 0.0])
    te_r, d4 = nearest(root, [0.75 * cr, 0.0, 0.0])
    assert max(d1, d2, d3, d4) < 1e-9  # leading/trailing edges are mesh vertices
    chord_tip, chord_root = te_t - le_t, te_r - le_r
    twist = np.degrees(
        np.arctan2(chord_tip[1], chord_tip[0]) - np.arctan2(chord_root[1], chord_root[0])
    )
    assert twist == pytest.approx(30.0, abs=1e-6)
    assert np.linalg.norm(chord_tip) == pytest.approx(ct, rel=1e-9)


def test_naca_contact_points_on_tip_camber_line(naca):
    c = naca.contact_points
    assert c.shape == (3, 10)
    np.testing.assert_allclose(c[2], 0.1, atol=1e-9)
    assert set(naca.require("contact")) <= set(naca.require("tip"))
    # untwist the points: the camber line of NACA 2412 has y_c = m/p^2 (2 p x - x^2) ahead of p
    angle = -np.radians(30.0)
    x, y = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]) @ c[:2]
    xc = x / 0.035 + 0.25
    yc = np.where(
        xc < 0.4, 0.02 / 0.16 * (0.8 * xc - xc**2), 0.02 / 0.36 * (0.2 + 0.8 * xc - xc**2)
    )
    np.testing.assert_allclose(y / 0.035, yc, atol=2e-3)


def test_naca_lower_size_bound_limits_refinement():
    bounded = naca_blade("0012", h=0.004, h_min=0.002, n_contact=0)
    unbounded = naca_blade("0012", h=0.004, h_min=0.001, n_contact=0)
    edges = edge_lengths(bounded.mesh.p, bounded.mesh.t)
    # the size field never goes below h_min; a sharp trailing edge (wedge angle ~16 deg)
    # still forces some edges shorter, but not by more than a factor ~5
    assert edges.min() >= 0.15 * 0.002
    assert unbounded.n_tets > 1.5 * bounded.n_tets


# ---------------------------------------------------------------- Rotor 37 sections
def test_rotor37_section_units(sections_dir):
    raw = np.loadtxt(
        sections_dir / "R37_profile01.csv", delimiter=",", skiprows=1, encoding="utf-8-sig"
    )
    pts = read_section(sections_dir / "R37_profile01.csv", "cm")
    assert pts.shape == (3, 300)  # repeated closing point dropped
    np.testing.assert_allclose(pts, raw[:-1].T * 0.01)


def test_rotor37_sections_loft(sections_dir):
    blade = rotor37_sections_blade(sections_dir.parent, h=0.006)
    r = blade.radius()
    # README: radius about 17.67..25.11 cm (x is the axis; measured: 17.79..25.23 cm)
    assert 0.1760 < r.min() < 0.1800
    assert 0.2500 < r.max() < 0.2540
    assert blade.volume() == pytest.approx(blade.info["cad_volume"], rel=2e-2)
    assert blade.contact_points.shape == (3, 16)
    assert set(blade.require("contact")) <= set(blade.require("tip"))
    r_tip = blade.radius(blade.mesh.p[:, blade.node_sets["tip"]])
    assert blade.radius(blade.contact_points).min() > r_tip.min() - 1e-9
    assert r[blade.require("root")].max() < 0.19


# ---------------------------------------------------------------- save / read back
@pytest.mark.parametrize("name, binary", [("b.msh", False), ("b_bin.msh", True), ("b.vtu", False)])
def test_save_and_read_back(box, tmp_path, name, binary):
    path = box.save(tmp_path / name, binary=binary)
    back = read_mesh(path, radial_axis="x") if name.endswith(".vtu") else read_mesh(path)
    np.testing.assert_allclose(back.mesh.p, box.mesh.p)
    np.testing.assert_array_equal(back.mesh.t, box.mesh.t)
    np.testing.assert_allclose(back.contact_points, box.contact_points)
    for key in ("root", "tip", "contact"):
        np.testing.assert_array_equal(np.sort(back.node_sets[key]), np.sort(box.node_sets[key]))
    np.testing.assert_allclose(back.axis, [1.0, 0.0, 0.0])


# ---------------------------------------------------------------- errors and gmsh hygiene
def test_require_missing_group_message():
    blade = box_blade(h=0.006, n_contact=0)
    with pytest.raises(GeometryError) as excinfo:
        blade.require("contact")
    _one_line_error(excinfo, "'contact'", "root", "n_contact")
    with pytest.raises(GeometryError) as excinfo:
        blade.require("leading_edge")
    _one_line_error(excinfo, "'leading_edge'", "available")


def test_bad_inputs_raise_clear_errors(tmp_path):
    with pytest.raises(GeometryError) as excinfo:
        length_scale("inch")
    _one_line_error(excinfo, "'inch'", "'mm'")
    with pytest.raises(GeometryError) as excinfo:
        box_blade(h=0.002, h_min=0.004)
    _one_line_error(excinfo, "h_min")
    with pytest.raises(GeometryError) as excinfo:
        naca_blade("12")
    _one_line_error(excinfo, "'0012'")
    with pytest.raises(GeometryError) as excinfo:
        read_mesh(tmp_path / "missing.msh")
    _one_line_error(excinfo, "missing.msh", "check the path")
    bad = tmp_path / "bad.msh"
    bad.write_text("$MeshFormat\nthis is not a mesh\n")
    with pytest.raises(GeometryError) as excinfo:
        read_mesh(bad)
    _one_line_error(excinfo, "bad.msh")


def test_gmsh_errors_are_wrapped_and_cleaned_up():
    with pytest.raises(GeometryError) as excinfo:
        with gmsh_session():
            gmsh.model.getBoundingBox(3, 999)
    _one_line_error(excinfo, "gmsh failed", "Volume 999")
    assert not gmsh.isInitialized()


def test_gmsh_state_does_not_leak():
    assert not gmsh.isInitialized()
    box_blade(h=0.006, n_contact=2)
    assert not gmsh.isInitialized()
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("mine")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 123.0)
        models = gmsh.model.list()
        box_blade(h=0.006, n_contact=2)
        assert gmsh.model.getCurrent() == "mine"
        assert gmsh.option.getNumber("Mesh.MeshSizeMax") == 123.0
        assert gmsh.option.getNumber("General.Terminal") == 0
        assert gmsh.model.list() == models
    finally:
        gmsh.finalize()


# ---------------------------------------------------------------- CLI
def test_cli_box_and_read(tmp_path, capsys):
    out = tmp_path / "box.msh"
    assert mesh_cli(["box", "--h", "0.006", "--n-contact", "3", "-o", str(out)]) == 0
    assert out.is_file()
    assert mesh_cli(["read", str(out)]) == 0
    assert "3 contact points" in capsys.readouterr().out
    assert mesh_cli(["read", str(tmp_path / "nope.inp")]) == 2
    assert "error: Cannot read" in capsys.readouterr().err
