"""Batched VTK frames (femrub.output.vtk, frame_fields, vtu_file): same fields as one
frame at a time, a series ParaView's reader opens, interruption, a writer behind or idle,
writer errors."""

import dataclasses
import time
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest
import pyvista as pv

import femrub as fr
from femrub.contact.casing import Lobed
from femrub.geometry import box_blade
from femrub.model.builder import build_rub
from femrub.model.config import ContactConfig, RubConfig
from femrub.output.vtk import VTKSeries

H, STRIDE = 1e-5, 20


@pytest.fixture(scope="module")
def rub():
    blade = box_blade(span=0.1, chord=0.03, thickness=0.003, h=0.006, hub_radius=0.3, n_contact=5)
    mat = fr.Material(young=110e9, rho=4500.0, rho_c=4500 * 585.0, conductivity=7.0)
    # frictionless contacts heating the tip (α = 20 m/s): the fields these tests compare
    config = RubConfig(
        mat,
        ContactConfig(
            casing=Lobed(clearance=2e-6, depth=3e-6, lobes=2),
            heat_law="alpha",
            heat_coefficient=20.0,
        ),
        rotation_speed=1000.0,
    )
    built = build_rub(blade, config)
    return built.model, built.fields, built.disc


def von_mises(fields, disc, u_all):
    """Von Mises stress (Pa) per tetrahedron from the displacement at the centroid, through
    scikit-fem's interpolation (the way the per-frame writer computed it)."""
    ui = disc.basis_u.interpolate(u_all)
    grad = ui.grad.mean(axis=-1)  # (3, 3, n_elements), mean over quadrature points
    eps = 0.5 * (grad + grad.transpose(1, 0, 2))
    tr = np.einsum("iie->e", eps)
    sig = 2.0 * fields.mu * eps
    sig[[0, 1, 2], [0, 1, 2]] += fields.lam * tr
    dev = sig.copy()
    dev[[0, 1, 2], [0, 1, 2]] -= np.einsum("iie->e", sig) / 3.0
    return np.sqrt(1.5 * np.einsum("ije,ije->e", dev, dev))


def _reference(model, fields, disc, X, impulse):
    """The fields of one frame computed the way the per-frame writer did."""
    full = np.asarray(model.to_full @ X).ravel()
    bu, bt = disc.basis_u, disc.basis_t
    nu, vd = bu.N, bu.nodal_dofs
    u, v = full[:nu], full[nu : 2 * nu]
    c = fields.contacts
    force = np.zeros((vd.shape[1], 3))
    np.add.at(force, c.vertices, -(impulse / H * c.normals).T)
    return {
        "displacement": u[vd].T,
        "velocity": v[vd].T,
        "temperature": full[2 * nu : 2 * nu + bt.N][bt.nodal_dofs[0]],
        "contact_force": force,
        "von_mises": von_mises(fields, disc, u),
    }


def _run(model, series, **kw):
    """A run of 0.003 s feeding ``series``, with the states of its frames kept."""
    res = fr.ThetaMethod(model, H).run(0.003, on_state=series, store_every=STRIDE, **kw)
    series.close()
    return res


def _frames(series):
    root = ET.parse(series.pvd_path).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


@pytest.mark.parametrize("dense", [False, True])
def test_batched_frames_equal_the_per_frame_fields(rub, tmp_path, dense):
    model, fields, disc = rub
    if dense:  # a reduced model's map to the mesh is a dense matrix (float32 product)
        model = dataclasses.replace(model, to_full=model.to_full.toarray())
    series = VTKSeries(tmp_path, model, fields, h=H, stride=STRIDE, batch=4, dtype=np.float64)
    res = fr.ThetaMethod(model, H).run(0.003, on_state=series, store_every=STRIDE)
    series.close()
    assert res.status == "ok" and res.impulse.max() > 0
    frames = _frames(series)
    assert len(frames) == len(res.state_times) == 16
    rows = np.rint(res.state_times / H).astype(int)
    hits = 0
    for (t, f), X, r in zip(frames, res.states, rows):
        assert t == pytest.approx(res.t[r])
        ref = _reference(model, fields, disc, X, res.impulse[r])
        m = meshio.read(tmp_path / f)
        for k, a in ref.items():
            got = m.cell_data[k][0] if k == "von_mises" else m.point_data[k]
            scale = max(np.abs(a).max(), 1e-300)
            assert np.abs(got.reshape(a.shape) - a).max() <= 1e-12 * scale, k
        hits += int(np.abs(m.point_data["contact_force"]).max() > 0)
        fric = np.zeros((m.points.shape[0], 3))
        np.add.at(fric, fields.contacts.vertices, res.friction_force[r])
        assert np.abs(m.point_data["friction_force"] - fric).max() <= 1e-9 * max(
            np.abs(fric).max(), 1e-12
        )
    assert hits > 0
    # the default float32 files hold the same fields to single precision
    s32 = VTKSeries(tmp_path / "f32", model, fields, h=H, stride=STRIDE)
    fr.ThetaMethod(model, H).run(0.003, on_state=s32)
    s32.close()
    a = meshio.read(tmp_path / frames[-1][1])
    b = meshio.read(tmp_path / "f32" / frames[-1][1])
    pairs = [(a.point_data[k], b.point_data[k]) for k in ("displacement", "velocity")]
    pairs.append((a.cell_data["von_mises"][0], b.cell_data["von_mises"][0]))
    for x, y in pairs:  # reconstructed in single precision too
        assert y.dtype == np.float32
        assert np.abs(x - y).max() <= 1e-5 * np.abs(x).max()
    assert b"femrub units:" in (tmp_path / "f32" / frames[-1][1]).read_bytes()[:400]


@pytest.mark.parametrize("dense", [False, True])
def test_default_series_reads_in_pyvista_and_equals_the_direct_fields(rub, tmp_path, dense):
    """The series as ``femrub run`` writes it (float32, background writer, default
    batches): VTK's own reader opens the .pvd with every frame at its time, and every field
    of every frame equals the direct reconstruction to float32 round-off."""
    model, fields, disc = rub
    if dense:
        model = dataclasses.replace(model, to_full=model.to_full.toarray())
    series = VTKSeries(tmp_path, model, fields, h=H, stride=STRIDE)
    res = _run(model, series)
    assert res.status == "ok" and res.impulse.max() > 0
    frames = _frames(series)
    rows = np.rint(res.state_times / H).astype(int)
    assert [f for _, f in frames] == [f"rub_{i:06d}.vtu" for i in range(len(rows))] != []
    assert [t for t, _ in frames] == pytest.approx(res.t[rows], rel=1e-9)
    reader = pv.get_reader(str(series.pvd_path))
    assert reader.number_time_points == len(frames)
    assert np.asarray(reader.time_values) == pytest.approx(res.t[rows], rel=1e-9)
    eps = np.finfo(np.float32).eps
    for i, (X, r) in enumerate(zip(res.states, rows)):
        reader.set_active_time_point(i)
        grid = reader.read()[0]
        assert grid.n_points == fields.mesh.p.shape[1] and grid.n_cells == fields.mesh.t.shape[1]
        ref = _reference(model, fields, disc, X, res.impulse[r])
        fric = np.zeros((grid.n_points, 3))
        np.add.at(fric, fields.contacts.vertices, res.friction_force[r])
        ref["friction_force"] = fric
        m = meshio.read(tmp_path / frames[i][1])
        for k, a in ref.items():
            got = m.cell_data[k][0] if k == "von_mises" else m.point_data[k]
            vtk_got = grid.cell_data[k] if k == "von_mises" else grid.point_data[k]
            assert got.dtype == np.float32 and np.array_equal(vtk_got, got), k
            scale = max(np.abs(a).max(), 1e-300)
            assert np.abs(got.reshape(a.shape) - a).max() <= 50 * eps * scale, k


class _Slow(VTKSeries):
    """A series whose every frame file takes ``delay`` seconds more to write."""

    delay = 0.004

    def _write_frames(self, frames, vtu):
        time.sleep(self.delay * len(frames))
        super()._write_frames(frames, vtu)


def test_a_writer_behind_the_stepping_holds_it_back_and_loses_nothing(rub, tmp_path):
    model, fields, disc = rub
    series = _Slow(tmp_path, model, fields, h=H, stride=STRIDE, batch=3, min_batch=2)
    res = _run(model, series)
    assert res.status == "ok"
    frames = _frames(series)
    rows = np.rint(res.state_times / H).astype(int)
    assert [f for _, f in frames] == [f"rub_{i:06d}.vtu" for i in range(len(rows))]
    assert [t for t, _ in frames] == pytest.approx(res.t[rows], rel=1e-9)
    for (_, f), X in zip(frames, res.states):
        u = meshio.read(tmp_path / f).point_data["displacement"]
        ref = _reference(model, fields, disc, X, np.zeros(model.n_contacts))["displacement"]
        assert np.abs(u - ref).max() <= 1e-5 * max(np.abs(ref).max(), 1e-300)


def test_an_idle_writer_takes_a_few_frames_after_flush_seconds(rub, tmp_path):
    model, fields, disc = rub
    series = VTKSeries(tmp_path, model, fields, h=H, stride=1, min_batch=8, flush_seconds=0.05)
    states = iter(fr.ThetaMethod(model, H).iterate(0.001))
    for _ in range(2):
        series.take(next(states))
    for _ in range(200):  # no flush: the writer takes the two frames by itself
        if len(series.frames) == 2:
            break
        time.sleep(0.01)
    assert [f for _, f in _frames(series)] == ["rub_000000.vtu", "rub_000001.vtu"]
    series.take(next(states))
    series.close()
    assert len(_frames(series)) == 3


class _Interrupted(VTKSeries):
    """A series whose run is interrupted (Ctrl-C) when the frame of step ``k_stop`` comes."""

    k_stop = 7 * STRIDE

    def take(self, state):
        if state.k >= self.k_stop:
            raise KeyboardInterrupt
        super().take(state)


@pytest.mark.parametrize("background,batch", [(True, 5), (False, 5), (True, 32)])
def test_interrupted_run_keeps_every_frame_taken(rub, tmp_path, background, batch):
    """Also when the frames taken are fewer than the writer's ``min_batch`` (batch 32)."""
    model, fields, disc = rub
    series = _Interrupted(
        tmp_path, model, fields, h=H, stride=STRIDE, batch=batch, background=background
    )
    res = fr.ThetaMethod(model, H).run(0.003, on_state=series)
    assert res.status == "interrupted"
    frames = _frames(series)  # written by the recorder's flush, before close
    assert [f for _, f in frames] == [f"rub_{i:06d}.vtu" for i in range(7)]
    assert [t for t, _ in frames] == pytest.approx(res.t[: 7 * STRIDE : STRIDE], rel=1e-9)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*dict(frames).values(), "rub.pvd"])
    for _, f in frames:
        assert meshio.read(tmp_path / f).point_data["displacement"].shape[1] == 3
    series.close()


def test_the_background_writers_error_surfaces(rub, tmp_path, monkeypatch):
    model, fields, disc = rub
    series = VTKSeries(tmp_path, model, fields, h=H, stride=STRIDE, batch=3)

    def full_disk(path, *fields):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(series._vtu, "write", full_disk)
    res = fr.ThetaMethod(model, H).run(0.003, on_state=series)
    assert res.status == "failed" and "No space left on device" in res.message
    assert series.frames == []
    series.close()  # reported once: closing does not raise it again
    with pytest.raises(ValueError, match="batch"):
        VTKSeries(tmp_path, model, fields, h=H, batch=0)


def test_fields_of_a_shared_map_are_read_by_column_blocks(rub, monkeypatch):
    """A reduced model whose map is columns of a wider array with the mesh's constrained rows
    put back (a size of a larger reduction: ``ColumnMap`` of the basis) gives the fields of
    that map copied out, bit for bit, its operators read a few columns at a time (never the
    whole map copied)."""
    from femrub.output import frame_fields
    from femrub.reduction.truncation import prolonged

    model, fields, _ = rub
    P = model.to_full  # the full model's prolongation of its free dofs to the mesh
    rng = np.random.default_rng(3)
    n = model.n_dofs
    wide = rng.standard_normal((n, 9))
    shared = prolonged(P, wide).columns([7, 2, 4, 0, 5])
    assert np.array_equal(np.asarray(shared), (P @ wide)[:, [7, 2, 4, 0, 5]])
    sized = dataclasses.replace(model, to_full=shared)
    dense = dataclasses.replace(sized, to_full=np.asarray(shared))
    X = rng.standard_normal((3, 5))
    impulse = rng.random((3, model.n_contacts))
    want = frame_fields.FrameFields(dense, fields, H).compact(X, impulse)
    monkeypatch.setattr(frame_fields, "COLUMN_BLOCK", 2)
    block, taken = frame_fields._block, []

    def counted(T, r, c):
        taken.append((r.stop - r.start if isinstance(r, slice) else len(r), len(c)))
        return block(T, r, c)

    monkeypatch.setattr(frame_fields, "_block", counted)
    got = frame_fields.FrameFields(sized, fields, H).compact(X, impulse)
    # the displacement rows (all of them) are read two columns at a time
    assert max(c for r, c in taken if r == fields.n_u) == 2
    for k, a in want.items():
        assert (a is None and got[k] is None) or np.array_equal(a, got[k]), k
