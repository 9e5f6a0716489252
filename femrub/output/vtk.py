"""ParaView output: a ``.pvd`` collection of ``.vtu`` files, written as the run goes.

:class:`VTKSeries` is a callback for ``stepper.run(t_end, on_state=...)``: every ``stride``
steps it keeps the (reduced) state; batches of frames are mapped to the full mesh at once and
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
import threading
import time
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..blas import one_blas_thread
from ..model.rub import FieldMap
from .frame_fields import FrameFields
from .vtu_file import VTK_TETRA, VTUWriter

__all__ = ["FIELD_UNITS", "FrameSink", "VTKSeries", "snapshot_png"]

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


class FrameSink:
    """A run's ``on_state`` callback that takes every ``stride``-th state (``take``) and is
    closed (``close``) on leaving a ``with`` block."""

    stride: int

    def __call__(self, state) -> None:
        if state.k % self.stride == 0:
            self.take(state)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class VTKSeries(FrameSink):
    """Stream a run to ``directory/name_XXXXXX.vtu`` plus ``directory/name.pvd``.

    A frame is taken every ``stride`` steps (the initial state included): the call only
    copies the (reduced) state, impulses and time. With ``background`` (the default) a
    writer thread takes every frame waiting as soon as it is free and there are at least
    ``min_batch`` of them (or the oldest waited ``flush_seconds``): it reconstructs them
    at once (:class:`~femrub.output.frame_fields.FrameFields`; its products and the file
    writes release the GIL, so it runs beside the stepping on a second core), writes
    their files (:class:`~femrub.output.vtu_file.VTUWriter`), each renamed when complete,
    then rewrites the ``.pvd`` atomically; the stepping thread waits only when ``batch``
    frames are waiting (the writer is slower than the stepping). The writer's error is
    raised in the stepping thread at the next frame or at :meth:`flush`. Without
    ``background`` the frames are written in the calling thread, ``batch`` at a time.
    :meth:`flush` (called by the recorder at the end of a run, also an interrupted or
    failed one) writes every frame taken; a killed process loses at most the frames not
    yet written: those waiting and those being written.

    Parameters
    ----------
    directory : output folder (created).
    model : the (full or reduced) model run; with a ``FieldMap``, needs ``model.to_full``.
    fields : the :class:`~femrub.model.rub.FieldMap` of the full model, or a frame source of
        another mesh: ``fields.frame_fields(model, h, dtype)`` gives an object with
        ``compact(X, impulse, friction, times=...)``, ``store(compact, b, data)`` and its
        ``writer`` (:class:`~femrub.output.vtu_file.VTUWriter`), and ``fields.snapshot_scalars``
        names the field ``snapshot.png`` is coloured by (:mod:`femrub.output.wheel_vtk`).
    h : the run's time step (s), to turn contact impulses into forces.
    stride : write every ``stride``-th step (the initial state is always written).
    batch : most frames waiting (then the stepping waits for the writer) and most frames
        reconstructed together.
    min_batch : fewest frames the background writer takes at once (the products cost
        less per frame in larger batches), but at :meth:`flush` or after ``flush_seconds``;
        at most ``batch``.
    background : write the frames in a background thread.
    flush_seconds : a frame waits at most this wall time for ``min_batch - 1`` others.
    dtype : type of the field data in the files (``float32`` or ``float64``).
    """

    def __init__(
        self,
        directory,
        model,
        fields: FieldMap,
        *,
        h: float,
        stride: int = 10,
        name="rub",
        batch: int = 32,
        min_batch: int = 8,
        background: bool = True,
        flush_seconds: float = 10.0,
        dtype=np.float32,
    ):
        if isinstance(fields, FieldMap) and model.to_full is None:
            raise ValueError("this model has no map to the full mesh (model.to_full)")
        if int(stride) < 1:
            raise ValueError(f"VTK output stride must be >= 1, got {stride!r}")
        if min(int(batch), int(min_batch)) < 1:
            raise ValueError(
                f"VTK output batch and min_batch must be >= 1, got {batch!r}, {min_batch!r}"
            )
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.model, self.fields, self.stride, self.name = model, fields, int(stride), name
        for stale in [*self.dir.glob(f"{name}_*.vtu"), *self.dir.glob("*.tmp"), self.pvd_path]:
            stale.unlink(missing_ok=True)  # frames of an earlier run: not this run's
        self.h = float(h)
        self.frames: list[tuple[float, str]] = []
        self.seconds = self._main_cpu = self._writer_cpu = 0.0
        self._comment, self.snapshot_scalars = _UNITS_COMMENT, "temperature"
        if isinstance(fields, FieldMap):
            self._fields = FrameFields(model, fields, self.h, dtype)
            point = {"displacement": 3, "velocity": 3, "temperature": 1}
            point |= {"contact_force": 3, "friction_force": 3}
            self._vtu = VTUWriter(
                fields.mesh.p.T,
                fields.mesh.t.T,
                VTK_TETRA,
                point,
                ["von_mises"],
                _UNITS_COMMENT,
                dtype,
            )
        else:  # a frame source of its own (a part of a bladed disk, :mod:`.wheel_vtk`)
            self._fields = fields.frame_fields(model, self.h, dtype)
            self._vtu = self._fields.writer
            self._comment, self.snapshot_scalars = self._vtu.comment, fields.snapshot_scalars
        self.batch, self.min_batch = int(batch), min(int(min_batch), int(batch))
        self.flush_seconds = float(flush_seconds)
        self._vtu_main: VTUWriter | None = None
        self._waiting: list[tuple] = []  # frames taken, not handed to the writer yet
        self._taken = 0  # frames taken: the index of the next
        self._pvd_lock = threading.Lock()
        self._error: BaseException | None = None
        self._reported = self._busy = self._draining = self._closing = False
        self._cond = threading.Condition()
        self._thread: threading.Thread | None = None
        if background:
            self._thread = threading.Thread(target=self._work, name="femrub-vtk", daemon=True)
            self._thread.start()

    @property
    def cpu_seconds(self) -> float:
        """CPU seconds of the output, in the stepping thread and the writer thread."""
        return self._main_cpu + self._writer_cpu

    @property
    def pvd_path(self) -> Path:
        return self.dir / f"{self.name}.pvd"

    def take(self, state) -> None:
        """Copy the frame of ``state`` (t, X, impulse, friction impulse) for the writer."""
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            self._raise_error()
            fi = getattr(state, "friction_impulse", None)
            frame = (
                self._taken,
                float(state.t),
                np.array(state.X, dtype=float),
                np.array(state.impulse, dtype=float),
                None if fi is None or not np.size(fi) else np.array(fi, dtype=float),
                t0,
            )
            self._taken += 1
            if self._thread is None:
                self._waiting.append(frame)
                if len(self._waiting) >= self.batch or t0 - self._waiting[0][-1] > (
                    self.flush_seconds
                ):
                    self._write_waiting()
                return
            with self._cond:
                self._waiting.append(frame)
                if len(self._waiting) in (1, self.min_batch):  # its deadline, or ready
                    self._cond.notify_all()
                while len(self._waiting) >= self.batch and self._error is None:
                    self._cond.wait()  # the writer is behind: wait for it
            self._raise_error()
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
            if self._thread is None:
                self._write_waiting()
            else:
                with self._cond:
                    self._draining = True
                    # the frames waiting are split with the writer (all of them if it is
                    # busy): the end of a run waits for half as many frames
                    keep = 0 if self._busy else (len(self._waiting) + 1) // 2
                    mine, self._waiting = self._waiting[keep:], self._waiting[:keep]
                    self._cond.notify_all()
                try:
                    if mine and self._error is None:
                        with one_blas_thread:  # the other core is the writer's
                            self._write_frames(mine, self._own_vtu())
                    with self._cond:
                        while (self._waiting or self._busy) and self._error is None:
                            self._cond.wait()
                finally:
                    self._draining = False
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
                with self._cond:
                    self._closing = True
                    self._cond.notify_all()
                self._thread.join()
                self._thread = None

    # -- the writer --------------------------------------------------------------------
    def _ready(self) -> float | None:
        """Under the lock: 0 if the writer should take the waiting frames now, else the
        seconds until the oldest one has waited ``flush_seconds`` (``None``: no frame)."""
        if not self._waiting:
            return None
        if self._draining or len(self._waiting) >= self.min_batch:
            return 0.0
        return max(0.0, self._waiting[0][-1] + self.flush_seconds - time.perf_counter())

    def _work(self) -> None:
        """The writer thread: take the waiting frames when ready, until closed."""
        while True:
            with self._cond:
                while (wait := self._ready()) != 0.0 and not self._closing:
                    self._cond.wait(wait)
                if self._closing and not self._waiting:
                    return
                frames, self._waiting, self._busy = self._waiting, [], True
                self._cond.notify_all()  # a stepping thread waiting for room goes on
            c0 = time.thread_time()
            try:
                if self._error is None:
                    with one_blas_thread:  # the other core is the stepping's
                        self._write_frames(frames, self._vtu)
            except BaseException as exc:  # raised in the stepping thread
                self._error = exc
            finally:
                self._writer_cpu += time.thread_time() - c0
                with self._cond:
                    self._busy = False
                    self._cond.notify_all()

    def _write_waiting(self) -> None:
        """Write the frames waiting, in this thread (no background writer)."""
        frames, self._waiting = self._waiting, []
        self._write_frames(frames, self._vtu)

    def _own_vtu(self) -> VTUWriter:
        """The file buffer of the stepping thread when it writes beside the writer."""
        if self._vtu_main is None:
            self._vtu_main = self._vtu.copy()
        return self._vtu_main

    def _write_frames(self, frames: list[tuple], vtu: VTUWriter) -> None:
        """Reconstruct the frames, ``batch`` at once, write their files with ``vtu``, then
        the ``.pvd`` (the frames complete on disk, in order): ``frames`` lists a frame only
        once the ``.pvd`` names it."""
        for start in range(0, len(frames), self.batch):
            part = frames[start : start + self.batch]
            X, imp = np.stack([f[2] for f in part]), np.stack([f[3] for f in part])
            times = np.array([f[1] for f in part])
            fi = None
            if any(f[4] is not None for f in part):
                shape = next(f[4] for f in part if f[4] is not None).shape
                fi = np.stack([np.zeros(shape) if f[4] is None else f[4] for f in part])
            c = self._fields.compact(X, imp, fi, times=times)
            written = []
            for b, f in enumerate(part):
                fname = f"{self.name}_{f[0]:06d}.vtu"
                self._fields.store(c, b, vtu.data)
                vtu.write(self.dir / fname)
                written.append((f[1], fname))
            with self._pvd_lock:
                self.frames = sorted([*self.frames, *written], key=lambda tf: tf[1])
                self._write_pvd()

    def _raise_error(self) -> None:
        """Raise the writer's error here, once (the writer writes nothing after it)."""
        if self._error is not None and not self._reported:
            self._reported = True
            raise self._error

    def _write_pvd(self) -> None:
        lines = [
            '<?xml version="1.0"?>',
            '<VTKFile type="Collection" version="0.1">',
            self._comment,
            "<Collection>",
        ]
        for t, f in self.frames:
            lines.append(f'<DataSet timestep="{t!r}" part="0" file={quoteattr(f)}/>')
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
