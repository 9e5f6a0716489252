"""The whole bladed disk and its casing ring in ParaView, frame by frame.

A wheel's state holds the coordinates of cyclic bases (:mod:`femrub.model.wheel`), never the
dofs of a mesh of the whole wheel. A frame draws them on each whole structure, meshed as its
sector turned ``N`` times (:func:`~femrub.geometry.cyclic_sector.full_wheel`: copy ``s`` is
the sector turned by ``R(sα)``, ``α = 2π/N``; the nodes two neighbouring copies share are
merged, the field there taken from one of them: the cyclic condition makes both equal).

**The rotor** (``rub_XXXXXX.vtu``, ``rub.pvd``), in the rotor's frame: the point data
``displacement`` (m) and ``velocity`` (m/s) of the vibration about the centrifugal static
state, in global axes; at the vertex ``R(sα) p`` of copy ``s``, the sector field of Eq. (1)
of :mod:`femrub.reduction.cyclic_ritz` turned to global axes::

    u(R(sα) p) = R(sα) Σ_k c_k Re(e^{iksα} W_k(p) ξ_k)                                 (1)

(``c_k = √(2/N)`` for ``0 < k < N/2``, ``1/√N`` otherwise; ``ξ_k = a + i b`` from the real
coordinates); ``static_displacement`` (m): the centrifugal growth at Ω, the same in every
frame (the total displacement is the sum); ``contact_force`` and ``friction_force`` (N,
global axes) at the vertex of each tip contact of every blade, ``−λ n / h`` and the
friction impulse over ``h``; with the blades' temperature, ``temperature`` (K above
ambient), Eq. (1) of the temperature's coordinates with one component and no turn.

**The casing ring** (``casing_XXXXXX.vtu``, ``casing.pvd``; with a flexible ring only), in
the casing's fixed frame: the ring's coordinates are waves of the rotating frame,
``ζ = ξ e^{iβt}`` with ``β = k σ Ω`` (:mod:`femrub.model.casing_waves`), so the fixed-frame
coordinates at the frame's time ``t`` are::

    ξ = ζ e^{−iβt},        ξ̇ = (ζ̇ − iβζ) e^{−iβt}                                      (2)

and its ``displacement`` and ``velocity`` are (1) of ``ξ`` and ``ξ̇`` on the ring's mesh.
At ``t = 0`` both frames coincide; at ``t`` the rotor is turned by ``σΩt`` about ``+x``
relative to the casing (ParaView: a Transform filter of that angle puts it in place).

Each frame costs a few products per nodal diameter (the real and imaginary parts of the
vertex rows of ``W_k`` times the coordinates, for a batch of frames at once), one product
with the ``N × 2H`` phases ``cos(k s α)``, ``−sin(k s α)``, the turn of every copy and a
scatter onto the whole mesh: no loop over dofs, sectors or frames in Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..geometry.cyclic_sector import full_wheel, sector_turns
from ..model.wheel import WheelMap
from .frame_fields import _scatter
from .vtk import FrameSink, VTKSeries
from .vtu_file import VTK_TETRA, VTUWriter

__all__ = ["CasingFrames", "CyclicVertexField", "RotorFrames", "WheelFields", "WheelSeries"]

#: SI units of the point data of the rotor's and the casing's frames
WHEEL_FIELD_UNITS = {
    "displacement": "m",
    "velocity": "m/s",
    "static_displacement": "m",
    "contact_force": "N",
    "friction_force": "N",
    "temperature": "K",
}


def _comment(frame: str, names) -> str:
    units = ", ".join(f"{k} [{WHEEL_FIELD_UNITS[k]}]" for k in names)
    return f"<!-- femrub units: {units} ; time in s ; {frame} -->"


class CyclicVertexField:
    """Displacement (or a scalar field) at the vertices of a whole cyclic structure from its
    coordinates, Eq. (1).

    Parameters
    ----------
    structure : CyclicStructure
        The sector (its mesh, basis and free dofs): three components per vertex (a
        displacement, turned to global axes) or one (a scalar field: the temperature of
        :mod:`femrub.model.cyclic_thermal`, the same in every axes).
    basis : CyclicBasis
        The coordinates' harmonic bases on that sector.
    dtype : numpy dtype
        Precision of the products (``float32`` for files written in single precision).
    like : CyclicVertexField, optional
        A field of the same sector whose whole mesh is taken (not built again).

    Attributes
    ----------
    points : numpy.ndarray
        ``(n_points, 3)`` vertices of the whole structure (m).
    cells : numpy.ndarray
        ``(n_cells, 4)`` its tetrahedra.
    copies : numpy.ndarray
        ``(N, n_sector_vertices)``: the whole mesh's vertex of each sector vertex in each copy.
    """

    def __init__(self, structure, basis, dtype=np.float64, like=None):
        if like is None:
            mesh, self.copies = full_wheel(structure.sector)
            self.points = np.ascontiguousarray(mesh.mesh.p.T)
            self.cells = np.ascontiguousarray(mesh.mesh.t.T)
        else:
            self.copies, self.points, self.cells = like.copies, like.points, like.cells
        self.components = structure.left.shape[1]
        self.n_sectors = basis.n_sectors
        self.turns = sector_turns(self.n_sectors)
        self.vertex_rows = _vertex_rows(structure)
        self._blocks, ks = [], []
        for h, start, m, pair in basis.blocks():
            W = np.zeros((self.vertex_rows.size, m), dtype=complex)
            on = self.vertex_rows >= 0
            W[on] = h.shapes[self.vertex_rows[on]]
            Wr, Wi = W.real, W.imag
            if pair:  # ξ = a + i b: Re(Wξ) = Wr a − Wi b, Im(Wξ) = Wi a + Wr b
                re, im = np.hstack([Wr, -Wi]), np.hstack([Wi, Wr])
                scale = math.sqrt(2.0 / self.n_sectors)
            else:
                re, im, scale = Wr, Wi, 1.0 / math.sqrt(self.n_sectors)
            cols = np.arange(start, start + m * (2 if pair else 1))
            rows = scale * np.concatenate([re, im], axis=0).T  # (columns, 2 × c n_vertices)
            self._blocks.append((cols, np.ascontiguousarray(rows, dtype=dtype)))
            ks.append(h.k)
        angles = np.outer(np.arange(self.n_sectors), ks) * basis.angle  # (N, H)
        phases = np.empty((self.n_sectors, 2 * len(ks)))
        phases[:, 0::2], phases[:, 1::2] = np.cos(angles), -np.sin(angles)
        self._phases = phases.astype(dtype)
        self.dtype = np.dtype(dtype)

    @property
    def n_points(self) -> int:
        return self.points.shape[0]

    def sector_fields(self, x: np.ndarray) -> np.ndarray:
        """``(B, N, n_sector_vertices, c)``: the field of every copy in the sector's axes,
        ``Σ_k c_k Re(e^{iksα} W_k ξ_k)`` at the sector's vertices, for coordinates ``x``
        ``(B, size)``."""
        x = np.atleast_2d(np.asarray(x))
        B, n3, c = x.shape[0], self.vertex_rows.size, self.components
        parts = np.empty((B, 2 * len(self._blocks), n3), dtype=self.dtype)
        for j, (cols, rows) in enumerate(self._blocks):
            parts[:, 2 * j : 2 * j + 2] = (x[:, cols].astype(self.dtype) @ rows).reshape(B, 2, n3)
        return np.matmul(self._phases, parts).reshape(B, self.n_sectors, n3 // c, c)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """``(B, n_points, c)``: the whole structure's field for coordinates ``x``
        ``(B, size)``, Eq. (1): a displacement turned to global axes, a scalar as it is."""
        local = self.sector_fields(x)
        if self.components == 1:
            return self.place(local)
        return self.place(np.einsum("sij,bsvj->bsvi", self.turns.astype(self.dtype), local))

    def place(self, per_copy: np.ndarray) -> np.ndarray:
        """``(B, n_points, k)`` from values ``(B, N, n_sector_vertices, k)`` of every copy."""
        B, k = per_copy.shape[0], per_copy.shape[-1]
        out = np.empty((B, self.n_points, k), dtype=per_copy.dtype)
        out[:, self.copies.ravel()] = per_copy.reshape(B, -1, k)
        return out


def _vertex_rows(structure) -> np.ndarray:
    """``(c n_vertices,)`` vertex-major: the position in ``structure.free`` of each vertex's
    components (−1 where clamped or held)."""
    where = np.full(structure.basis.N, -1, dtype=np.int64)
    where[structure.free] = np.arange(structure.free.size)
    return where[structure.basis.nodal_dofs.T.ravel()]


class RotorFrames:
    """The rotor's point data of a batch of frames (module docstring).

    Parameters
    ----------
    fields : WheelFields
        The wheel's map and its sectors.
    model : FirstOrderModel
        The wheel's model (its layout, contact frames).
    h : float
        The run's time step (s), to turn impulses into forces.
    dtype : numpy dtype
        Precision of the products and the files.
    """

    snapshot_scalars = "displacement"
    names = ("displacement", "velocity", "static_displacement", "contact_force", "friction_force")

    def __init__(self, fields: WheelFields, model, h: float, dtype=np.float32):
        wheel = fields.wheel
        self.map = CyclicVertexField(fields.disk, wheel.disk, dtype)
        self._u = np.arange(wheel.n_disk)
        self._v = model.layout.n_u + self._u
        self.temperature = None  # the blades' temperature: its field and state slice
        if wheel.temperature is not None and fields.thermal is not None:
            tmap = CyclicVertexField(fields.thermal, wheel.temperature, dtype, like=self.map)
            self.temperature = (tmap, model.layout.t)
            self.names = (*self.names, "temperature")
        self.h = float(h)
        N, contacts = wheel.n_blades, wheel.contacts
        turns = self.map.turns
        # contact (s, p) of the model acts at the vertex of point p in copy s
        where = self.map.copies[:, np.asarray(contacts.vertices)].ravel()  # (N n_c,)
        self.contact_vertices, which = np.unique(where, return_inverse=True)
        self._scatter = sp.csr_matrix(
            (np.ones(where.size), (which.ravel(), np.arange(where.size))),
            shape=(self.contact_vertices.size, where.size),
        )
        self._normals = np.einsum("sab,bp->spa", turns, contacts.normals).reshape(-1, 3)
        self._contact = model.contact
        static = np.asarray(fields.disk.static)[fields.disk.basis.nodal_dofs.T.ravel()]
        local = np.broadcast_to(static.reshape(1, 1, -1, 3), (1, N, static.size // 3, 3))
        self.static = self.map.place(np.einsum("sij,bsvj->bsvi", turns, local))[0]
        point = {name: 1 if name == "temperature" else 3 for name in self.names}
        self.writer = _writer(self.map, point, _comment("rotor frame", point), dtype)
        self.writer.data["static_displacement"][:] = self.static

    def compact(self, X, impulse, friction=None, times=None) -> dict:
        """``displacement``, ``velocity`` ``(B, n_points, 3)`` and ``contact_force``,
        ``friction_force`` ``(B, n_contact_vertices, 3)`` (the latter ``None`` without
        friction) of states ``X`` ``(B, n)``, impulses ``(B, N n_c)`` and friction impulses
        ``(B, N n_c, 2)``; ``times`` is not needed (the rotor's frame)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        B = X.shape[0]
        both = self.map(np.concatenate([X[:, self._u], X[:, self._v]]))
        lam = np.asarray(impulse, dtype=float).reshape(B, -1)
        forces = -(lam[:, :, None] / self.h) * self._normals[None]
        out = {"displacement": both[:B], "velocity": both[B:], "friction_force": None}
        if self.temperature is not None:
            tmap, t = self.temperature
            out["temperature"] = tmap(X[:, t])
        out["contact_force"] = _scatter(self._scatter, forces)
        c = self._contact
        if friction is not None and np.size(friction) and c is not None and c.frames is not None:
            out["friction_force"] = _scatter(
                self._scatter, c.to_global(np.asarray(friction, dtype=float) / self.h)
            )
        return out

    def store(self, compact: dict, b: int, data: dict) -> None:
        """Write frame ``b`` of ``compact`` into the writer's arrays ``data``."""
        drawn = ("displacement", "velocity") + (("temperature",) if self.temperature else ())
        for k in drawn:
            data[k][:] = compact[k][b].reshape(data[k].shape)
        cv = self.contact_vertices
        for k in ("contact_force", "friction_force"):
            data[k][cv] = 0.0 if compact[k] is None else compact[k][b]


class CasingFrames:
    """The casing ring's point data of a batch of frames in its fixed frame, Eq. (2).

    Parameters as :class:`RotorFrames`.
    """

    snapshot_scalars = "displacement"
    names = ("displacement", "velocity")

    def __init__(self, fields: WheelFields, model, h: float, dtype=np.float32):
        wheel = fields.wheel
        basis = wheel.casing.basis
        self.map = CyclicVertexField(fields.ring, basis, dtype)
        self._u = wheel.n_disk + np.arange(wheel.n_casing)
        self._v = model.layout.n_u + self._u
        c, d, k = [], [], []
        for hb, start, m, pair in basis.blocks():
            if pair:
                c.append(np.arange(start, start + m))
                d.append(np.arange(start + m, start + 2 * m))
                k.append(np.full(m, hb.k))
        self._c = np.concatenate(c) if c else np.zeros(0, dtype=int)
        self._d = np.concatenate(d) if d else np.zeros(0, dtype=int)
        ks = np.concatenate(k) if k else np.zeros(0)
        self.beta = ks * fields.direction * fields.rotation_speed  # (pairs,) β = k σ Ω
        point = {name: 3 for name in self.names}
        self.writer = _writer(self.map, point, _comment("casing frame", point), dtype)

    def fixed(self, zeta, times, rate=None) -> np.ndarray:
        """Fixed-frame coordinates ``ξ`` ``(B, n_casing)`` of rotating ones ``ζ`` at ``times``
        ``(B,)`` s, Eq. (2); with ``rate`` (``ζ̇``), ``ξ̇`` instead."""
        zeta = np.atleast_2d(np.asarray(zeta, dtype=float))
        c, d = zeta[:, self._c], zeta[:, self._d]
        out = zeta.copy() if rate is None else np.atleast_2d(np.asarray(rate, dtype=float)).copy()
        if rate is not None:  # ζ̇ − iβζ
            c, d = out[:, self._c] + self.beta * d, out[:, self._d] - self.beta * c
        theta = np.outer(np.asarray(times, dtype=float), self.beta)
        cos, sin = np.cos(theta), np.sin(theta)
        out[:, self._c] = c * cos + d * sin  # (c + i d) e^{−iθ}
        out[:, self._d] = d * cos - c * sin
        return out

    def compact(self, X, impulse=None, friction=None, times=None) -> dict:
        """``displacement``, ``velocity`` ``(B, n_points, 3)`` of states ``X`` ``(B, n)`` at
        ``times`` ``(B,)`` s (needed: the ring's coordinates turn with the rotor)."""
        if times is None:
            raise ValueError("the casing's fixed-frame field needs the frames' times")
        X = np.atleast_2d(np.asarray(X, dtype=float))
        B = X.shape[0]
        zeta, rate = X[:, self._u], X[:, self._v]
        xi = np.concatenate([self.fixed(zeta, times), self.fixed(zeta, times, rate)])
        both = self.map(xi)
        return {"displacement": both[:B], "velocity": both[B:]}

    def store(self, compact: dict, b: int, data: dict) -> None:
        for k in self.names:
            data[k][:] = compact[k][b]


def _writer(field: CyclicVertexField, point: dict, comment: str, dtype) -> VTUWriter:
    """The :class:`~femrub.output.vtu_file.VTUWriter` of a whole cyclic structure's mesh."""
    return VTUWriter(field.points, field.cells, VTK_TETRA, point, [], comment, dtype)


@dataclass(frozen=True)
class WheelFields:
    """What output needs to draw a wheel's states on the whole rotor and casing.

    Attributes
    ----------
    wheel : WheelMap
        The wheel's coordinates (:func:`~femrub.model.wheel.wheel_model`).
    disk : CyclicStructure
        The disk's sector (its static growth at Ω).
    ring : CyclicStructure or None
        The casing ring's sector (``None``: a rigid casing, not drawn).
    rotation_speed : float
        Ω (rad/s).
    direction : float
        σ (+1 or −1).
    thermal : CyclicStructure or None
        The sector's temperature (:mod:`femrub.model.cyclic_thermal`) when the blades have
        temperature dofs: the rotor's frames then draw ``temperature`` (K above ambient).
    """

    wheel: WheelMap
    disk: object
    ring: object
    rotation_speed: float
    direction: float
    thermal: object = None

    def parts(self) -> dict:
        """``{series name: frame source class}``: ``rub`` (the rotor) and, with a flexible
        ring, ``casing``."""
        out = {"rub": RotorFrames}
        if self.ring is not None and self.wheel.casing is not None:
            out["casing"] = CasingFrames
        return out

    def vtk_series(self, directory, model, *, h: float, stride: int, **options) -> WheelSeries:
        """The :class:`WheelSeries` of a run of ``model`` (``options``: those of
        :class:`~femrub.output.vtk.VTKSeries`, e.g. ``dtype``, ``background``)."""
        return WheelSeries(directory, model, self, h=h, stride=stride, **options)


class _Source:
    """A frame source of :class:`~femrub.output.vtk.VTKSeries`: one part of the wheel."""

    def __init__(self, fields: WheelFields, kind):
        self.fields, self.kind = fields, kind
        self.snapshot_scalars = kind.snapshot_scalars

    def frame_fields(self, model, h: float, dtype):
        return self.kind(self.fields, model, h, dtype)


class WheelSeries(FrameSink):
    """The rotor's and the casing's :class:`~femrub.output.vtk.VTKSeries` of one run, fed
    together (the ``on_state`` callback of a run): ``rub.pvd`` and ``casing.pvd`` in
    ``directory``, a frame of each every ``stride`` steps at the same times."""

    def __init__(self, directory, model, fields: WheelFields, *, h: float, stride: int, **options):
        self.parts = {}
        try:
            for name, kind in fields.parts().items():
                source = _Source(fields, kind)
                self.parts[name] = VTKSeries(
                    directory, model, source, h=h, stride=stride, name=name, **options
                )
        except BaseException:  # stop the writers already started
            self.close()
            raise
        self.rotor = self.parts["rub"]
        self.stride = self.rotor.stride

    # the rotor's series stands for the run's (summary.json, the snapshot)
    dir = property(lambda self: self.rotor.dir)
    pvd_path = property(lambda self: self.rotor.pvd_path)
    frames = property(lambda self: self.rotor.frames)
    snapshot_scalars = property(lambda self: self.rotor.snapshot_scalars)
    seconds = property(lambda self: sum(p.seconds for p in self.parts.values()))
    cpu_seconds = property(lambda self: sum(p.cpu_seconds for p in self.parts.values()))

    def take(self, state) -> None:
        for part in self.parts.values():
            part.take(state)

    def flush(self) -> None:
        for part in self.parts.values():
            part.flush()

    def close(self) -> None:
        """Close every part (each flushed, its writer stopped), the first error raised."""
        error = None
        for part in self.parts.values():
            try:
                part.close()
            except BaseException as exc:  # close the others all the same
                error = error or exc
        if error is not None:
            raise error
