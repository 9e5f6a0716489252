"""A bladed disk whose blade is lofted through section files (``geometry.kind = "sections"``).

The synthetic blade: twisted NACA 0012 sections written by the test in centimetres, each
wrapped onto the cylinder of its radius about the axis ``x`` (non-planar, as measured
sections on stream surfaces are), the blade standing at ``φ = 20°`` in the files. The
sector must turn it onto ``φ = 0`` without scaling it, extend it into the rim, fuse and
mesh it periodic; its cyclic modes are the whole wheel's.
"""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial.distance import pdist
from small_wheel import TITANIUM, N
from test_cyclic_modes import Whole, _check_against_whole
from test_wheel_scene import WHEEL

from femrub.app.cli import main
from femrub.app.modes import rotor_sector
from femrub.geometry.cyclic_sector import face_pairs, full_wheel, sector_angle
from femrub.geometry.naca import naca4_sides
from femrub.geometry.sections import read_sections
from femrub.geometry.sections_disk import fit_problem, place_sections, root_centroid
from femrub.model.cyclic import cyclic_structure
from femrub.scene import SceneError, load_scene

#: the blade's section radii (cm), chords (cm), twists (degrees) and its angle in the files
RADII, CHORDS, TWISTS, PHI0 = (4.8, 6.15, 7.5), (1.5, 1.35, 1.2), (30.0, 40.0, 50.0), 20.0
#: the disk (m): bore, rim, thickness; the element sizes (m)
DISK = dict(hub_radius=0.02, rim_radius=0.045, thickness=0.015)
H, H_MIN = 0.01, 0.004


def _unrolled(chord, twist):
    """Closed NACA 0012 section (cm) unrolled: axial ``x`` and arc length, chord at ``twist``
    from the axis, mid-chord at the origin."""
    upper, lower = naca4_sides("0012", 30)
    loop = np.hstack([upper, lower[:, -2:0:-1]]) - np.array([[0.5], [0.0]])
    c, s = math.cos(math.radians(twist)), math.sin(math.radians(twist))
    return np.array([[c, -s], [s, c]]) @ (chord * loop)


def _section(radius, chord, twist):
    """The section (cm) wrapped onto the cylinder ``r = radius``, mid-chord at ``φ = PHI0``."""
    x, arc = _unrolled(chord, twist)
    phi = math.radians(PHI0) + arc / radius
    return np.vstack([x, -radius * np.sin(phi), radius * np.cos(phi)])


def _arc_centroid(chord, twist):
    """The arc coordinate (cm) of the unrolled section's area centroid (shoelace)."""
    x, a = _unrolled(chord, twist)
    xn, an = np.roll(x, -1), np.roll(a, -1)
    cross = x * an - xn * a
    return float(((a + an) * cross).sum() / (3.0 * cross.sum()))


def _write_sections(folder):
    folder.mkdir()
    for k, args in enumerate(zip(RADII, CHORDS, TWISTS, strict=True)):
        with open(folder / f"section{k}.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["x", "y", "z"])
            w.writerows(_section(*args).T.tolist())
    return folder


def _scene_text(folder, **rotor) -> str:
    keys = {"sectors": N, **DISK, **rotor}
    lines = "\n".join(f"{k} = {v!r}" for k, v in keys.items())
    return f"""
name = "sections-wheel"
[geometry]
kind = "sections"
path = "{folder.as_posix()}"
length_unit = "cm"
axis = "x"
h = {H!r}
h_min = {H_MIN!r}
[material]
young = {TITANIUM.young!r}
poisson = {TITANIUM.poisson!r}
density = {TITANIUM.rho!r}
[rotor]
{lines}
families = 2
[scheme]
h = 1e-6
t_end = 1e-5
"""


def _scene(tmp, folder, **rotor):
    path = tmp / "wheel.toml"
    path.write_text(_scene_text(folder, **rotor))
    return load_scene(str(path))


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return _write_sections(tmp_path_factory.mktemp("sections") / "blade")


@pytest.fixture(scope="module")
def sector(folder, tmp_path_factory):
    return rotor_sector(_scene(tmp_path_factory.mktemp("scene"), folder))


def test_the_sections_are_turned_onto_the_sector_not_scaled(folder):
    raw = read_sections(folder, "cm")
    blade = place_sections(raw, "x")
    centre = root_centroid(blade.sections[0])
    assert abs(sector_angle(centre[:, None])[0]) < 1e-12
    phi_c = math.radians(PHI0) + _arc_centroid(CHORDS[0], TWISTS[0]) / RADII[0]
    assert blade.turn == pytest.approx(-phi_c, abs=1e-5)
    for before, after in zip(raw, blade.sections, strict=True):
        assert np.allclose(pdist(after.T), pdist(before.T), rtol=0, atol=1e-12)
        assert np.allclose(np.hypot(after[1], after[2]), np.hypot(before[1], before[2]))
    x = blade.sections[0][0]
    assert x.min() == pytest.approx(-x.max())


def test_a_section_listed_the_other_way_round_lofts_the_same_blade(folder, tmp_path):
    """The twisted sections' leading edges, as split_section names them, flip between hub
    and tip; a section listed clockwise among anticlockwise ones swaps its sides: both are
    matched to the hub section's, and the loft is the same solid."""
    from femrub.geometry.section_blade import sections_blade

    other = tmp_path / "reversed"
    other.mkdir()
    for f in sorted(folder.glob("*.csv")):
        rows = f.read_text().splitlines()
        if f.name == "section1.csv":
            rows = rows[:1] + rows[:0:-1]
        (other / f.name).write_text("\n".join(rows) + "\n")
    volumes = [sections_blade(d, h=0.004).info["cad_volume"] for d in (folder, other)]
    assert volumes[1] == pytest.approx(volumes[0], rel=1e-9)


def test_sector_is_periodic_fused_and_its_tip_is_the_curved_tip_face(sector):
    mesh = sector.mesh
    p = mesh.mesh.p
    left, right = mesh.require("left"), mesh.require("right")
    image = face_pairs(p, left, right, sector.rotation, 1e-9)
    assert np.allclose(sector.rotation @ p[:, left], p[:, image], atol=1e-12)
    t = mesh.mesh.t
    incidence = sp.csr_matrix((np.ones(t.size), (np.repeat(np.arange(t.shape[1]), 4), t.T.ravel())))
    assert connected_components(incidence @ incidence.T, directed=False)[0] == 1
    whole, _ = full_wheel(sector)
    assert np.isclose(whole.volume(), N * mesh.volume(), rtol=1e-12)
    radius = mesh.radius()
    tip_r = RADII[-1] / 100
    assert radius.min() == pytest.approx(DISK["hub_radius"], rel=1e-9)
    assert radius.max() == pytest.approx(tip_r, rel=1e-6)
    tip = mesh.require("tip")
    assert sector.info["tip_radius"] == pytest.approx(radius[tip].max())
    assert sector.info["tip_radius"] == pytest.approx(tip_r, rel=1e-6)
    # the whole curved tip face on the cylinder r = tip_r (within its filling's sag), and
    # nothing of the blade's sides
    assert tip.size >= 5 and np.all(np.abs(radius[tip] - tip_r) < 1e-3 * tip_r)
    wide = CHORDS[-1] * math.sin(math.radians(TWISTS[-1])) / RADII[-1]  # its angular width
    assert np.ptp(sector_angle(p[:, tip])) == pytest.approx(wide, rel=0.1)
    assert np.linalg.svd(p[:, tip] - p[:, tip].mean(axis=1, keepdims=True))[1][-1] > 1e-5
    assert sector.info["root_depth"] > RADII[0] / 100 - DISK["rim_radius"]


def test_sections_disk_cyclic_modes_match_the_whole_wheel(sector):
    structure = cyclic_structure(sector, TITANIUM)
    whole = Whole(sector, TITANIUM, 6)
    cyclic = _check_against_whole(structure, whole, 2, 6)
    assert cyclic[0] > 0


#: the 6-blade wheel's casing ring (test_wheel_scene.py), at its speed
RING = WHEEL[WHEEL.index("[casing.ring]") : WHEEL.index("[contact]")] + (
    '[loads]\nrotation_speed = 1000.0\ncentrifugal = "linear"\n'
)


def test_the_wheel_run_takes_the_sector_its_contacts_on_the_tip(folder, tmp_path):
    """What ``femrub run`` builds of the wheel before its bases: the prestressed sector, the
    tip contacts on the curved tip face, the ring around the largest tip radius."""
    from femrub.app.wheel import wheel_parts

    path = tmp_path / "wheel.toml"
    path.write_text(_scene_text(folder, contacts=3) + RING)
    parts = wheel_parts(load_scene(str(path)))
    tip_r = RADII[-1] / 100
    assert parts.tip_radius == pytest.approx(tip_r, rel=1e-6)
    assert parts.bore == pytest.approx(parts.tip_radius + 20e-6)
    assert parts.contacts.radii == pytest.approx(np.full(3, tip_r), rel=1e-3)
    assert parts.rows.shape == (9, parts.disk.free.size) and parts.ring is not None


def _one_line_refusal(tmp, folder, monkeypatch, **rotor) -> str:
    import femrub.geometry.sections_disk as sd

    def meshed(*args, **kw):  # the refusal comes before any meshing
        raise AssertionError("meshed")

    monkeypatch.setattr(sd, "sections_disk_sector", meshed)
    with pytest.raises(SceneError) as err:
        rotor_sector(_scene(tmp, folder, **rotor))
    msg = str(err.value)
    assert "\n" not in msg
    return msg


def test_a_rim_above_the_root_is_refused(folder, tmp_path, monkeypatch):
    msg = _one_line_refusal(tmp_path, folder, monkeypatch, rim_radius=0.05)
    assert msg.startswith("rotor.rim_radius = 0.05: ")
    root = float(msg.split("r = ")[1].split(" m")[0])
    assert root == pytest.approx(RADII[0] / 100, rel=1e-6)
    assert f"rim_radius < {root:.6g} m" in msg


def test_a_disk_thinner_than_the_root_is_refused(folder, tmp_path, monkeypatch):
    msg = _one_line_refusal(tmp_path, folder, monkeypatch, thickness=0.01)
    axial = np.ptp(_section(RADII[0], CHORDS[0], TWISTS[0])[0]) / 100  # the root's, in m
    assert msg.startswith("rotor.thickness = 0.01: ")
    assert msg.endswith(f"(thickness >= {axial:.6g} m)")


def test_sections_too_wide_for_the_sectors_are_refused(folder, tmp_path, monkeypatch):
    blade = place_sections(read_sections(folder, "cm"), "x")
    lo, hi = blade.extent(DISK["rim_radius"])
    fits = int(0.95 * math.pi / max(-lo, hi))
    assert N <= fits < 60
    msg = _one_line_refusal(tmp_path, folder, monkeypatch, sectors=fits + 1)
    assert msg.startswith(f"rotor.sectors = {fits + 1}: ")
    assert f"φ = {math.degrees(lo):.3g}° to {math.degrees(hi):.3g}°" in msg
    assert msg.endswith(f"the largest N that fits is {fits}")
    assert max(-lo, hi) > max(-blade.phi[0], blade.phi[1])  # the extension spreads wider
    assert fit_problem(blade, fits, **DISK) is None  # the largest N itself is taken ...
    monkeypatch.undo()
    largest = rotor_sector(_scene(tmp_path, folder, sectors=fits))  # ... and meshed
    assert largest.n_sectors == fits and largest.mesh.require("tip").size


def test_a_wheel_of_non_naca_blades_other_than_sections_is_refused(tmp_path):
    path = tmp_path / "w.toml"
    scheme = "[scheme]\nh = 1e-6\nt_end = 1e-5\n"
    path.write_text('[geometry]\nkind = "box"\n[rotor]\nsectors = 6\n' + scheme)
    with pytest.raises(SceneError, match="geometry.kind = 'box'.*'naca' or 'sections'"):
        load_scene(str(path))


ROTOR37_WHEEL = """
name = "rotor37-disk"
[geometry]
kind = "sections"
path = "{folder}"
pattern = "R37_profile*.csv"
length_unit = "cm"
axis = "x"
h = 0.015
h_min = 0.005
[rotor]
sectors = {sectors}
hub_radius = 0.14
rim_radius = 0.175
thickness = 0.045
families = 1
[loads]
rotation_speed = 0.0
[scheme]
h = 1e-6
t_end = 1e-5
"""


def test_rotor37_on_a_disk_modes_lie_just_below_the_clamped_blade(shared_data, tmp_path, capsys):
    folder = (shared_data / "rotor37-sections").as_posix()
    scene = tmp_path / "r37.toml"
    scene.write_text(ROTOR37_WHEEL.format(folder=folder, sectors=36))
    assert main(["modes", str(scene), "-o", str(tmp_path / "no"), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "rotor.sectors = 36: " in err
    fits = int(err.split("the largest N that fits is ")[1].split()[0])
    assert 8 <= fits < 36
    scene.write_text(ROTOR37_WHEEL.format(folder=folder, sectors=8))  # fewer solves than N
    out = tmp_path / "out"
    assert main(["modes", str(scene), "-o", str(out), "-q"]) == 0
    with open(out / "modes.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["structure"] == "disk"]
    assert sorted(int(r["nodal_diameter"]) for r in rows) == [0, 1, 2, 3, 4]
    first = np.array([float(r["frequency_hz"]) for r in rows])
    # the blade alone, clamped at its hub section, at the same element size
    blade = tmp_path / "blade.toml"
    text = ROTOR37_WHEEL.format(folder=folder, sectors=8).split("[rotor]")[0]
    blade.write_text(text + "[rotor]\nfamilies = 1\n" + ROTOR37_WHEEL.split("families = 1")[1])
    assert main(["modes", str(blade), "-o", str(tmp_path / "blade"), "-q"]) == 0
    with open(tmp_path / "blade" / "modes.csv", newline="") as fh:
        clamped = float(next(csv.DictReader(fh))["frequency_hz"])
    # on the disk the blade stands on its root's extension down to the rim (up to 1 cm
    # under the trailing edge, Rotor 37's hub being conical): lower, but not far lower;
    # the stiff disk leaves the first family nearly the same at every nodal diameter
    assert np.all(first < clamped) and np.all(first > 0.8 * clamped)
    assert np.ptp(first) < 1e-3 * first.min()
