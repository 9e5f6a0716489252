"""Cache and sweep keys cover every input byte: mid-side nodes, the files a scene names."""

from __future__ import annotations

import numpy as np
import pytest

from femrub.app.cache import ModelCache
from femrub.app.cached import Stages
from femrub.app.run import scene_hash
from femrub.fem.discretisation import discretise
from femrub.fem.material import Material
from femrub.geometry.abaqus_reader import read_abaqus
from femrub.scene import loads_scene

#: two C3D10 tetrahedra sharing the face 1-2-3 (mm); mid-side nodes numbered from 11
CORNERS = {1: (0, 0, 0), 2: (10, 0, 0), 3: (0, 10, 0), 4: (0, 0, 10), 5: (4, 4, -10)}
TETS = [(1, 2, 3, 4), (1, 3, 2, 5)]
EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


def _deck(folder, nudge=None, name="blade.inp"):
    """A deck; ``nudge``: ``(node id, axis, mm)`` moved (a corner or a mid-side node)."""
    xyz = {k: np.array(v, float) for k, v in CORNERS.items()}
    mid, elements = {}, []
    for number, tet in enumerate(TETS, start=1):
        conn = list(tet)
        for i, j in EDGES:
            edge = tuple(sorted((tet[i], tet[j])))
            if edge not in mid:
                mid[edge] = 11 + len(mid)
                xyz[mid[edge]] = 0.5 * (xyz[edge[0]] + xyz[edge[1]])
            conn.append(mid[edge])
        elements.append(", ".join(map(str, [number, *conn])))
    if nudge is not None:
        node, axis, mm = nudge
        xyz[node][axis] += mm
    lines = ["*NODE"] + [f"{k}, {x:.9g}, {y:.9g}, {z:.9g}" for k, (x, y, z) in xyz.items()]
    lines += ["*ELEMENT, TYPE=C3D10, ELSET=ALL", *elements]
    lines += ["*NSET, NSET=TIP", "5", "*BOUNDARY", "1, 1, 3", "2, 1, 3", "4, 1, 3"]
    (folder / name).write_text("\n".join(lines) + "\n")
    return folder / name


def _assemble(path, cache, notes):
    blade = read_abaqus(path, "mm", tip="TIP")
    disc = discretise(blade, 2)
    material = Material(young=110e9, rho=4500.0)
    return Stages(cache, notes.append).assemble(disc, material)


@pytest.mark.parametrize("node", [5, 11, 16], ids=["corner", "mid-side", "mid-side-2"])
def test_one_coordinate_of_one_node_changes_the_key_and_the_matrices(tmp_path, node, monkeypatch):

    cache, notes = ModelCache(tmp_path / "cache"), []
    first = _assemble(_deck(tmp_path), cache, notes)
    notes.clear()
    other = _deck(tmp_path, nudge=(node, 2, 0.5), name="other.inp")
    second = _assemble(other, cache, notes)
    assert any("assembly stored" in n for n in notes), notes  # a miss, not a reuse
    assert not any("assembly loaded" in n for n in notes)
    assert abs(second.K - first.K).max() > 1e-6 * abs(first.K).max()
    notes.clear()
    again = _assemble(other, cache, notes)  # the same file: a hit
    assert any("assembly loaded" in n for n in notes)
    assert abs(again.K - second.K).max() == 0.0


def _mesh_scene(folder, mesh="blade.inp"):
    text = f"""
[geometry]
kind = "mesh"
path = "{mesh}"
length_unit = "mm"
[scheme]
h = 1e-6
t_end = 1e-5
"""
    return loads_scene(text, "s.toml", folder)


def test_scene_hash_follows_the_mesh_file_and_its_includes(tmp_path):
    _deck(tmp_path, name="part.inp")
    (tmp_path / "blade.inp").write_text("*HEADING\nmain\n*INCLUDE, INPUT=part.inp\n")
    scene = _mesh_scene(tmp_path)
    before = scene_hash(scene)
    assert scene_hash(scene) == before
    _deck(tmp_path, nudge=(13, 0, 1e-3), name="part.inp")  # one mid-side node, 1 µm
    assert scene_hash(scene) != before


def test_the_files_are_read_again_only_when_their_status_changes(tmp_path, monkeypatch):
    """The 40 points of a map on one deck read it once for their keys; a file written again
    (here: the same bytes, its times moved) is read again, and a changed one gives a new
    key even at the same size."""
    import os

    import femrub.app.inputs as inputs

    _deck(tmp_path, name="part.inp")
    (tmp_path / "blade.inp").write_text("*HEADING\nmain\n*INCLUDE, INPUT=part.inp\n")
    scene = _mesh_scene(tmp_path)
    before = scene_hash(scene)
    read = []
    feed = inputs._feed_file
    monkeypatch.setattr(inputs, "_feed_file", lambda h, path: (read.append(path), feed(h, path)))
    assert [scene_hash(scene) for _ in range(3)] == [before] * 3 and read == []
    part = tmp_path / "part.inp"
    st = part.stat()
    os.utime(part, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    assert scene_hash(scene) == before and part.resolve() in read
    text = part.read_text()
    part.write_text(text.replace("2, 10, 0, 0", "2, 10, 0, 1", 1))  # the same size, new bytes
    assert len(part.read_text()) == len(text) and scene_hash(scene) != before


def test_an_edited_mesh_file_makes_a_resumed_sweep_rerun_its_points(tmp_path, monkeypatch):
    import csv

    import femrub.app.sweep as sweep_mod
    from femrub.app.cli import main
    from femrub.geometry import box_blade

    def serial(scene, todo, scheduler, workers, progress, cache=None):
        for r in todo:
            r.update(
                sweep_mod.run_point(
                    scene.data, scene.source, str(scene.base_dir), r["params"], r["folder"]
                )
            )

    def skipped():
        with open(out / "interaction.csv") as fh:
            return [r["skipped"] for r in csv.DictReader(fh)]

    monkeypatch.setattr(sweep_mod, "_compute", serial)
    mesh = tmp_path / "blade.msh"
    box_blade(0.1, 0.03, 0.003, h=0.02, n_contact=2).save(mesh)
    scene = tmp_path / "mesh.toml"
    scene.write_text(
        '[geometry]\nkind = "mesh"\npath = "blade.msh"\nlength_unit = "m"\n'
        '[contact]\ncasing = { kind = "concentric", clearance = "50 um" }\n'
        '[reduction]\nmethod = "none"\n'
        "[scheme]\nh = 1e-6\nt_end = 4e-6\n"
    )
    out = tmp_path / "sweep"
    argv = ["sweep", str(scene), "-o", str(out), "--param", "friction=0.1,0.2", "-q"]
    assert main(argv) == 0
    assert main(argv) == 0
    assert skipped() == ["True", "True"]
    box_blade(0.1, 0.03, 0.0031, h=0.02, n_contact=2).save(mesh)  # the file edited
    assert main(argv) == 0
    assert skipped() == ["False", "False"]
