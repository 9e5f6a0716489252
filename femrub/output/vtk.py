"""ParaView output: a ``.pvd`` collection of ``.vtu`` files, written as the run goes.

:class:`VTKSeries` is a callback for ``Stepper.run(on_state=...)``: every ``stride`` steps it
maps the state to the full mesh (``model.to_full``, which a reduced model composes with its
reduction basis) and writes one ``.vtu`` with point data ``displacement`` (m, vector),
``velocity`` (m/s), ``temperature`` (K above ambient), ``contact_force`` (N, vector, at the
contact vertices) and cell data ``von_mises`` (Pa, at the tetrahedron centroid). The
``.pvd`` index is rewritten (atomically) after every file, and every ``.vtu`` is written to
a temporary name and renamed when complete, so a run that crashes or is interrupted stays
viewable up to its last frame and never leaves a half-written frame. Frames of an earlier
run in the same folder are removed when a series starts. Both files state the units of
their fields (an XML comment ``femrub units: ...``; :data:`FIELD_UNITS`).
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

from ..model.rub import FieldMap

__all__ = ["FIELD_UNITS", "VTKSeries", "von_mises", "snapshot_png"]

#: SI units of the point and cell data of every frame
FIELD_UNITS = {
    "displacement": "m",
    "velocity": "m/s",
    "temperature": "K above ambient",
    "contact_force": "N",
    "von_mises": "Pa",
}
_UNITS_COMMENT = (
    "<!-- femrub units: "
    + ", ".join(f"{k} [{v}]" for k, v in FIELD_UNITS.items())
    + " ; time in s -->"
)


def von_mises(fields: FieldMap, u_all: np.ndarray) -> np.ndarray:
    """Von Mises stress (Pa) per tetrahedron, from the displacement at the centroid.

    The isotropic thermal part of the stress does not change the deviator, so it is
    omitted; ``σ = 2 μ ε + λ tr(ε) I``.
    """
    ui = fields.basis_u.interpolate(u_all)
    grad = ui.grad.mean(axis=-1)  # (3, 3, n_elements), mean over quadrature points
    eps = 0.5 * (grad + grad.transpose(1, 0, 2))
    tr = np.einsum("iie->e", eps)
    sig = 2.0 * fields.mu * eps
    sig[[0, 1, 2], [0, 1, 2]] += fields.lam * tr
    dev = sig.copy()
    dev[[0, 1, 2], [0, 1, 2]] -= np.einsum("iie->e", sig) / 3.0
    return np.sqrt(1.5 * np.einsum("ije,ije->e", dev, dev))


class VTKSeries:
    """Stream a run to ``directory/name_XXXXXX.vtu`` plus ``directory/name.pvd``.

    Parameters
    ----------
    directory : output folder (created).
    model : the (full or reduced) model run; needs ``model.to_full``.
    fields : the :class:`~femrub.model.rub.FieldMap` of the full model.
    h : the run's time step (s), to turn contact impulses into forces.
    stride : write every ``stride``-th step (the initial state is always written).
    """

    def __init__(
        self, directory, model, fields: FieldMap, *, h: float, stride: int = 10, name="rub"
    ):
        if model.to_full is None:
            raise ValueError("this model has no map to the full mesh (model.to_full)")
        if int(stride) < 1:
            raise ValueError(f"VTK output stride must be >= 1, got {stride!r}")
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.model, self.fields, self.stride, self.name = model, fields, int(stride), name
        for stale in [*self.dir.glob(f"{name}_*.vtu"), *self.dir.glob("*.tmp"), self.pvd_path]:
            stale.unlink(missing_ok=True)  # frames of an earlier run: not this run's
        self.h = float(h)
        self.frames: list[tuple[float, str]] = []
        self.seconds = self.cpu_seconds = 0.0
        mesh = fields.mesh
        self._points = mesh.p.T.copy()
        self._cells = [("tetra", mesh.t.T.copy())]
        bu, bt = fields.basis_u, fields.basis_t
        self._n_u, self._n_t = bu.N, bt.N
        self._vdofs = bu.nodal_dofs  # (3, n_vertices)
        self._tdofs = bt.nodal_dofs[0]
        self._has_t = model.layout.n_t > 0
        c = fields.contacts
        self._contact_vertex = c.vertices
        self._normals = c.normals

    @property
    def pvd_path(self) -> Path:
        return self.dir / f"{self.name}.pvd"

    def __call__(self, state) -> None:
        if state.k % self.stride == 0:
            self.write(state)

    def write(self, state) -> Path:
        """Write one frame for ``state`` (t, X, impulse) and update the ``.pvd``.

        ``seconds`` and ``cpu_seconds`` accumulate the wall and CPU time spent here, so a
        run can report its stepping time without the output it streamed.
        """
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            return self._write(state)
        finally:
            self.seconds += time.perf_counter() - t0
            self.cpu_seconds += time.process_time() - c0

    def _write(self, state) -> Path:
        full = np.asarray(self.model.to_full @ state.X).ravel()
        nu = self._n_u
        u, v = full[:nu], full[nu : 2 * nu]
        point_data = {
            "displacement": u[self._vdofs].T,
            "velocity": v[self._vdofs].T,
        }
        theta = full[2 * nu : 2 * nu + self._n_t] if self._has_t else np.zeros(self._n_t)
        point_data["temperature"] = theta[self._tdofs]
        force = np.zeros_like(self._points)
        if state.impulse.size:
            lam = state.impulse / self.h
            np.add.at(force, self._contact_vertex, -(lam * self._normals).T)
        point_data["contact_force"] = force
        friction = np.zeros_like(self._points)
        c = self.model.contact
        fi = getattr(state, "friction_impulse", None)
        if fi is not None and c is not None and c.frames is not None and fi.size:
            f = c.to_global(fi / self.h)[:, : self._points.shape[1]]
            np.add.at(friction, self._contact_vertex, f)
        point_data["friction_force"] = friction
        cell_data = {"von_mises": [von_mises(self.fields, u)]}
        fname = f"{self.name}_{len(self.frames):06d}.vtu"
        tmp = self.dir / f"{fname}.tmp"
        meshio.write(
            tmp,
            meshio.Mesh(self._points, self._cells, point_data=point_data, cell_data=cell_data),
            file_format="vtu",
            binary=True,
        )
        _add_units_comment(tmp)
        os.replace(tmp, self.dir / fname)
        self.frames.append((float(state.t), fname))
        self._write_pvd()
        return self.dir / fname

    def _write_pvd(self) -> None:
        lines = [
            '<?xml version="1.0"?>',
            '<VTKFile type="Collection" version="0.1">',
            _UNITS_COMMENT,
            "<Collection>",
        ]
        for t, f in self.frames:
            lines.append(f'<DataSet timestep="{t:.9g}" part="0" file={quoteattr(f)}/>')
        lines += ["</Collection>", "</VTKFile>", ""]
        tmp = self.pvd_path.with_suffix(".pvd.tmp")
        tmp.write_text("\n".join(lines))
        os.replace(tmp, self.pvd_path)


def _add_units_comment(path: Path) -> None:
    """Insert :data:`_UNITS_COMMENT` after the XML declaration of a ``.vtu`` file."""
    data = path.read_bytes()
    end = data.find(b"?>") + 2 if data.startswith(b"<?xml") else 0
    path.write_bytes(data[:end] + b"\n" + _UNITS_COMMENT.encode() + data[end:])


def snapshot_png(vtu_path, png_path, *, scalars: str = "temperature", warp: float | None = None):
    """PNG of one ``.vtu`` frame coloured by ``scalars`` on the deformed blade (off-screen).

    ``warp`` scales the displacement (default: so that the largest displacement is 5 % of the
    blade size). Renders without a display (VTK falls back to EGL/OSMesa); VTK's console
    warnings (e.g. "bad X server connection") are silenced, errors are raised.
    """
    import pyvista as pv
    import vtk

    vtk.vtkLogger.SetStderrVerbosity(vtk.vtkLogger.VERBOSITY_OFF)
    vtk.vtkObject.GlobalWarningDisplayOff()

    grid = pv.read(str(vtu_path))
    disp = np.asarray(grid.point_data["displacement"])
    size = float(np.ptp(grid.points, axis=0).max())
    umax = float(np.abs(disp).max())
    if warp is None:
        warp = 0.05 * size / umax if umax > 0 else 0.0
    shown = grid.warp_by_vector("displacement", factor=warp) if warp else grid
    plotter = pv.Plotter(off_screen=True, window_size=(900, 700))
    plotter.add_mesh(shown, scalars=scalars, cmap="inferno", show_edges=False)
    plotter.add_text(f"{scalars}, displacement ×{warp:.3g}", font_size=10)
    plotter.view_isometric()
    plotter.screenshot(str(png_path))
    plotter.close()
    return Path(png_path)
