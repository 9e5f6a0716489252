"""ParaView output: a ``.pvd`` collection of ``.vtu`` files, written as the run goes.

:class:`VTKSeries` is a callback for ``Stepper.run(on_state=...)``: every ``stride`` steps it
keeps the (reduced) state; batches of frames are mapped to the full mesh at once and
written, in a background thread by default, as ``.vtu`` files with point data
``displacement`` (m, vector), ``velocity`` (m/s), ``temperature`` (K above ambient),
``contact_force`` and ``friction_force`` (N, vector, at the contact vertices) and cell data
``von_mises`` (Pa, at the tetrahedron centroid). The ``.pvd`` index is rewritten
(atomically) after every batch of files, and every ``.vtu`` is written to a temporary name and
renamed when complete, so a run that crashes or is interrupted stays viewable up to its
last written frame and never leaves a half-written frame; the recorder flushes the series
at the end of every run, interrupted or failed ones included. Frames of an earlier run in
the same folder are removed when a series starts. Both files state the units of their
fields (an XML comment ``femrub units: ...``; :data:`FIELD_UNITS`).
"""

from __future__ import annotations

import os
import queue
import threading
import time
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..model.rub import FieldMap
from .frame_fields import FrameFields
from .vtu_file import VTK_TETRA, VTUWriter

__all__ = ["FIELD_UNITS", "VTKSeries", "snapshot_png"]

#: SI units of the point and cell data of every frame
FIELD_UNITS = {
    "displacement": "m",
    "velocity": "m/s",
    "temperature": "K above ambient",
    "contact_force": "N",
    "friction_force": "N",
    "von_mises": "Pa",
}
_UNITS_COMMENT = (
    "<!-- femrub units: "
    + ", ".join(f"{k} [{v}]" for k, v in FIELD_UNITS.items())
    + " ; time in s -->"
)


class VTKSeries:
    """Stream a run to ``directory/name_XXXXXX.vtu`` plus ``directory/name.pvd``.

    A frame is taken every ``stride`` steps (the initial state included): the call only
    copies the (reduced) state, impulses and time into a batch. A full batch of ``batch``
    frames, or one older than ``flush_seconds``, goes to the writer (a background thread
    when ``background``, which overlaps the stepping and whose error is raised here at the
    next frame or at :meth:`flush`), which reconstructs the whole batch at once
    (:class:`~femrub.output.frame_fields.FrameFields`) and writes its files
    (:class:`~femrub.output.vtu_file.VTUWriter`), each renamed when complete, then
    rewrites the ``.pvd`` atomically. :meth:`flush` (called by the recorder at the end
    of a run, also an interrupted or failed one) writes every frame taken; a killed
    process loses at most the frames not yet written: the batch being filled, one queued
    batch and the rest of the batch being written.

    Parameters
    ----------
    directory : output folder (created).
    model : the (full or reduced) model run; needs ``model.to_full``.
    fields : the :class:`~femrub.model.rub.FieldMap` of the full model.
    h : the run's time step (s), to turn contact impulses into forces.
    stride : write every ``stride``-th step (the initial state is always written).
    batch : frames reconstructed and written together.
    background : write the batches in a background thread.
    flush_seconds : a batch is handed to the writer after at most this wall time.
    dtype : type of the field data in the files (``float32`` or ``float64``).
    """

    def __init__(
        self, directory, model, fields: FieldMap, *, h: float, stride: int = 10, name="rub",
        batch: int = 32, background: bool = True, flush_seconds: float = 10.0,
        dtype=np.float32,
    ):  # fmt: skip
        if model.to_full is None:
            raise ValueError("this model has no map to the full mesh (model.to_full)")
        if int(stride) < 1:
            raise ValueError(f"VTK output stride must be >= 1, got {stride!r}")
        if int(batch) < 1:
            raise ValueError(f"VTK output batch must be >= 1, got {batch!r}")
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.model, self.fields, self.stride, self.name = model, fields, int(stride), name
        for stale in [*self.dir.glob(f"{name}_*.vtu"), *self.dir.glob("*.tmp"), self.pvd_path]:
            stale.unlink(missing_ok=True)  # frames of an earlier run: not this run's
        self.h = float(h)
        self.frames: list[tuple[float, str]] = []
        self.seconds = self._main_cpu = self._writer_cpu = 0.0
        self._fields = FrameFields(model, fields, self.h, dtype)
        point = {"displacement": 3, "velocity": 3, "temperature": 1}
        point |= {"contact_force": 3, "friction_force": 3}
        self._vtu = VTUWriter(fields.mesh.p.T, fields.mesh.t.T, VTK_TETRA, point,
                              ["von_mises"], _UNITS_COMMENT, dtype)  # fmt: skip
        self.batch, self.flush_seconds = int(batch), float(flush_seconds)
        self._taken = 0
        self._new_batch()
        self._error: BaseException | None = None
        self._reported = False
        self._queue: queue.Queue | None = None
        self._thread: threading.Thread | None = None
        if background:
            self._queue = queue.Queue(maxsize=1)
            self._thread = threading.Thread(target=self._work, name="femrub-vtk", daemon=True)
            self._thread.start()

    @property
    def cpu_seconds(self) -> float:
        """CPU seconds of the output, in the stepping thread and the writer thread."""
        return self._main_cpu + self._writer_cpu

    @property
    def pvd_path(self) -> Path:
        return self.dir / f"{self.name}.pvd"

    def __call__(self, state) -> None:
        if state.k % self.stride == 0:
            self.take(state)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def take(self, state) -> None:
        """Copy the frame of ``state`` (t, X, impulse, friction impulse) into the batch."""
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            self._raise_error()
            n = self._n
            self._X[n], self._t[n], self._imp[n] = state.X, state.t, state.impulse
            fi = getattr(state, "friction_impulse", None)
            if fi is not None and np.size(fi):
                self._fi = np.zeros((self.batch, *np.shape(fi))) if self._fi is None else self._fi
                self._fi[n] = fi
            self._n = n + 1
            if self._n == self.batch or t0 - self._since > self.flush_seconds:
                self._hand_over()
        finally:
            self.seconds += time.perf_counter() - t0
            self._main_cpu += time.thread_time() - c0

    def write(self, state) -> Path:
        """Write the frame of ``state`` now (and every frame taken before it)."""
        self.take(state)
        self.flush()
        return self.dir / self.frames[-1][1]

    def flush(self) -> None:
        """Write every frame taken so far and wait until they are on disk."""
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            self._raise_error()
            self._hand_over()
            if self._queue is not None:
                self._queue.join()
            self._raise_error()
        finally:
            self.seconds += time.perf_counter() - t0
            self._main_cpu += time.thread_time() - c0

    def close(self) -> None:
        """:meth:`flush`, then stop the writer thread."""
        try:
            self.flush()
        finally:
            if self._thread is not None:
                self._queue.put(None)
                self._thread.join()
                self._thread = None

    # -- the writer --------------------------------------------------------------------
    def _new_batch(self) -> None:
        N, nc = self.model.n_dofs, self.model.n_contacts
        self._X, self._t = np.empty((self.batch, N)), np.empty(self.batch)
        self._imp, self._fi, self._n = np.empty((self.batch, nc)), None, 0
        self._since = time.perf_counter()

    def _hand_over(self) -> None:
        """Send the frames taken to the writer (or write them here) and start a batch."""
        n = self._n
        if not n:
            return
        job = (self._taken, self._t[:n], self._X[:n], self._imp[:n],
               None if self._fi is None else self._fi[:n])  # fmt: skip
        self._taken += n
        self._new_batch()
        if self._queue is None:
            self._write_batch(*job)
        else:
            self._queue.put(job)

    def _work(self) -> None:
        """The writer thread: write the batches it receives until ``None``."""
        while True:
            job = self._queue.get()
            try:
                if job is not None and self._error is None:
                    c0 = time.thread_time()
                    try:
                        self._write_batch(*job)
                    finally:
                        self._writer_cpu += time.thread_time() - c0
            except BaseException as exc:  # raised in the stepping thread
                self._error = exc
            finally:
                self._queue.task_done()
            if job is None:
                return

    def _write_batch(self, first: int, t, X, impulse, friction) -> None:
        """Reconstruct a batch, write its frames, then the ``.pvd`` listing them."""
        data = self._fields.compute(X, impulse, friction)
        cells = ("von_mises",)
        for b in range(len(t)):
            fname = f"{self.name}_{first + b:06d}.vtu"
            point = {k: v[b] for k, v in data.items() if k not in cells}
            self._vtu.write(self.dir / fname, point, {k: data[k][b] for k in cells})
            self.frames.append((float(t[b]), fname))
        self._write_pvd()  # once per batch: every frame it lists is complete on disk

    def _raise_error(self) -> None:
        """Raise the writer's error here, once (the writer writes nothing after it)."""
        if self._error is not None and not self._reported:
            self._reported = True
            raise self._error

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
