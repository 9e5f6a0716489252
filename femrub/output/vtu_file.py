"""Binary ``.vtu`` files of one mesh with changing fields, the mesh encoded once.

:class:`VTUWriter` writes VTK XML UnstructuredGrid files with every array in the
``AppendedData`` section as raw binary (``encoding="raw"``, ``header_type="UInt64"``, little
endian), which ParaView, VTK and meshio read. The whole file of a frame is one byte buffer
built once: the XML header, the fields' byte counts, the geometry (points, connectivity,
offsets, cell types) and the closing tags are in place, and the fields are writable numpy
views into it (:attr:`VTUWriter.data`, float32 by default). A frame fills the views and is
written with one system call, to ``name.tmp`` then renamed, so a reader never sees half a
frame. The units comment is placed right after the XML declaration.
"""

from __future__ import annotations

import copy
import os
from pathlib import Path

import numpy as np

__all__ = ["VTUWriter", "VTK_TETRA"]

#: VTK cell type of a linear tetrahedron
VTK_TETRA = 10
_VTK_TYPES = {
    "float32": "Float32",
    "float64": "Float64",
    "int32": "Int32",
    "int64": "Int64",
    "uint8": "UInt8",
}


def _block(a: np.ndarray) -> bytes:
    """One appended array: its byte count (UInt64) then its little-endian bytes."""
    a = np.ascontiguousarray(a)
    return np.uint64(a.nbytes).tobytes() + a.astype(a.dtype.newbyteorder("<")).tobytes()


def _array_tag(name: str, a: np.ndarray, offset: int) -> str:
    label = f' Name="{name}"' if name else ""
    comps = f' NumberOfComponents="{a.shape[1]}"' if a.ndim == 2 else ""  # scalars: none
    return (
        f'<DataArray type="{_VTK_TYPES[a.dtype.name]}"{label}{comps} '
        f'format="appended" offset="{offset}"/>'
    )


class VTUWriter:
    """Frames on a fixed mesh of ``points`` (n × 3) and cells (``cells``: n_c × k vertex
    indices, VTK type ``cell_type``).

    The fields of the next frame are :attr:`data` (writable views into the file's bytes; a
    value written there stays until overwritten, so fields that change in a few entries
    only, e.g. forces at the contact vertices, need only those entries rewritten). One
    writer's buffer serves one thread at a time.

    Parameters
    ----------
    points, cells, cell_type : the mesh (points are written as float64, the connectivity as
        int32 when it fits).
    point_fields : names and components (1 or 3) of the point data, in file order.
    cell_fields : names of the (scalar) cell data, in file order.
    comment : an XML comment written after the declaration (e.g. the units).
    dtype : the type of the field data (``float32`` or ``float64``).
    """

    def __init__(
        self,
        points,
        cells,
        cell_type: int,
        point_fields: dict[str, int],
        cell_fields: list[str],
        comment: str = "",
        dtype=np.float32,
    ):
        pts = np.asarray(points, dtype=np.float64)
        if pts.shape[1] < 3:
            pts = np.hstack([pts, np.zeros((pts.shape[0], 3 - pts.shape[1]))])
        cells = np.asarray(cells)
        small = max(pts.shape[0], cells.size) < 2**31
        index = np.int32 if small else np.int64  # fewer bytes per frame
        cells = cells.astype(index)
        self.n_points, self.n_cells = pts.shape[0], cells.shape[0]
        self.comment = comment
        self.dtype = np.dtype(dtype)
        self.point_fields, self.cell_fields = dict(point_fields), list(cell_fields)
        shapes = {
            n: (self.n_points, c) if c > 1 else (self.n_points,) for n, c in point_fields.items()
        }
        shapes |= {n: (self.n_cells,) for n in self.cell_fields}
        tags, offset, blobs, slots = {"point": [], "cell": []}, 0, [], {}
        for name, shape in shapes.items():
            a = np.zeros(shape, self.dtype)
            tags["point" if name in self.point_fields else "cell"].append(
                _array_tag(name, a[:0], offset)
            )
            slots[name] = offset + 8  # after the block's byte count
            blobs.append(_block(a))
            offset += len(blobs[-1])
        geometry = [
            ("Points", "", pts),
            ("Cells", "connectivity", cells.ravel()),
            ("Cells", "offsets", np.arange(1, self.n_cells + 1, dtype=index) * cells.shape[1]),
            ("Cells", "types", np.full(self.n_cells, cell_type, dtype=np.uint8)),
        ]
        geo_tags = {"Points": [], "Cells": []}
        for section, name, a in geometry:
            geo_tags[section].append(_array_tag(name, a, offset))
            blobs.append(_block(a))
            offset += len(blobs[-1])
        xml = [
            '<?xml version="1.0"?>',
            comment,
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64">',
            "<UnstructuredGrid>",
            f'<Piece NumberOfPoints="{self.n_points}" NumberOfCells="{self.n_cells}">',
            "<PointData>",
            *tags["point"],
            "</PointData>",
            "<CellData>",
            *tags["cell"],
            "</CellData>",
            "<Points>",
            *geo_tags["Points"],
            "</Points>",
            "<Cells>",
            *geo_tags["Cells"],
            "</Cells>",
            "</Piece>",
            "</UnstructuredGrid>",
            '<AppendedData encoding="raw">',
            "_",
        ]
        head = "\n".join(line for line in xml if line).encode()
        self._file = bytearray(b"".join([head, *blobs, b"\n</AppendedData>\n</VTKFile>\n"]))
        le = self.dtype.newbyteorder("<")
        self._offsets = {name: len(head) + slots[name] for name in shapes}
        #: the fields of the next frame: views into the file's bytes, by name
        self.data = {
            name: np.frombuffer(self._file, le, int(np.prod(shape)), self._offsets[name]).reshape(
                shape
            )
            for name, shape in shapes.items()
        }

    def copy(self) -> VTUWriter:
        """A writer of the same files with a buffer of its own (for another thread)."""
        twin = copy.copy(self)
        twin._file = bytearray(self._file)
        twin.data = {
            k: np.frombuffer(twin._file, v.dtype, v.size, self._offsets[k]).reshape(v.shape)
            for k, v in self.data.items()
        }
        return twin

    @property
    def nbytes(self) -> int:
        """Bytes of one file."""
        return len(self._file)

    def write(self, path, point_data: dict | None = None, cell_data: dict | None = None) -> Path:
        """Copy the given fields into :attr:`data` (each must have its declared shape),
        then write the frame to ``path`` (via ``path.tmp`` and an atomic rename)."""
        for name, a in {**(point_data or {}), **(cell_data or {})}.items():
            view = self.data[name]
            a = np.asarray(a)
            if a.shape != view.shape:
                kind = "point" if name in self.point_fields else "cell"
                raise ValueError(f"{kind} field {name!r} has shape {a.shape}")
            np.copyto(view, a, casting="same_kind")
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "wb") as f:  # large writes go straight to the file
            f.write(self._file)
        os.replace(tmp, path)
        return path
