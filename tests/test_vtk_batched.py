"""Batched VTK frames (femrub.output.vtk, frame_fields, vtu_file): same fields as one
frame at a time, interruption and writer errors."""

import dataclasses
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

import femrub as fr
from femrub.contact.casing import Lobed
from femrub.geometry import box_blade
from femrub.model.rub import solid_model
from femrub.output.vtk import VTKSeries

H, STRIDE = 1e-5, 20


@pytest.fixture(scope="module")
def rub():
    blade = box_blade(span=0.1, chord=0.03, thickness=0.003, h=0.006, hub_radius=0.3, n_contact=5)
    mat = fr.Material(young=110e9, rho=4500.0, rho_c=4500 * 585.0, conductivity=7.0)
    model, fields = solid_model(
        blade, mat, casing=Lobed(clearance=2e-6, depth=3e-6, lobes=2), rotation_speed=1000.0,
        friction=0.05,
    )  # fmt: skip
    return model, fields


def von_mises(fields, u_all):
    """Von Mises stress (Pa) per tetrahedron from the displacement at the centroid, through
    scikit-fem's interpolation (the way the per-frame writer computed it)."""
    ui = fields.basis_u.interpolate(u_all)
    grad = ui.grad.mean(axis=-1)  # (3, 3, n_elements), mean over quadrature points
    eps = 0.5 * (grad + grad.transpose(1, 0, 2))
    tr = np.einsum("iie->e", eps)
    sig = 2.0 * fields.mu * eps
    sig[[0, 1, 2], [0, 1, 2]] += fields.lam * tr
    dev = sig.copy()
    dev[[0, 1, 2], [0, 1, 2]] -= np.einsum("iie->e", sig) / 3.0
    return np.sqrt(1.5 * np.einsum("ije,ije->e", dev, dev))


def _reference(model, fields, X, impulse):
    """The fields of one frame computed the way the per-frame writer did."""
    full = np.asarray(model.to_full @ X).ravel()
    bu, bt = fields.basis_u, fields.basis_t
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
        "von_mises": von_mises(fields, u),
    }


def _frames(series):
    root = ET.parse(series.pvd_path).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


@pytest.mark.parametrize("dense", [False, True])
def test_batched_frames_equal_the_per_frame_fields(rub, tmp_path, dense):
    model, fields = rub
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
        ref = _reference(model, fields, X, res.impulse[r])
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


class _Interrupted(VTKSeries):
    """A series whose run is interrupted (Ctrl-C) when the frame of step ``k_stop`` comes."""

    k_stop = 7 * STRIDE

    def take(self, state):
        if state.k >= self.k_stop:
            raise KeyboardInterrupt
        super().take(state)


@pytest.mark.parametrize("background", [True, False])
def test_interrupted_run_keeps_every_frame_taken(rub, tmp_path, background):
    model, fields = rub
    series = _Interrupted(tmp_path, model, fields, h=H, stride=STRIDE, batch=5,
                          background=background)  # fmt: skip
    res = fr.ThetaMethod(model, H).run(0.003, on_state=series)
    assert res.status == "interrupted"
    frames = _frames(series)  # written by the recorder's flush, before close
    assert [f for _, f in frames] == [f"rub_{i:06d}.vtu" for i in range(7)]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*dict(frames).values(), "rub.pvd"])
    for _, f in frames:
        assert meshio.read(tmp_path / f).point_data["displacement"].shape[1] == 3
    series.close()


def test_the_background_writers_error_surfaces(rub, tmp_path, monkeypatch):
    model, fields = rub
    series = VTKSeries(tmp_path, model, fields, h=H, stride=STRIDE, batch=3)

    def full_disk(path, point, cell):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(series._vtu, "write", full_disk)
    res = fr.ThetaMethod(model, H).run(0.003, on_state=series)
    assert res.status == "failed" and "No space left on device" in res.message
    assert series.frames == []
    series.close()  # reported once: closing does not raise it again
    with pytest.raises(ValueError, match="batch"):
        VTKSeries(tmp_path, model, fields, h=H, batch=0)
