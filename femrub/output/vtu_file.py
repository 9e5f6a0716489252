"""Binary ``.vtu`` files of one mesh with changing fields, the mesh encoded once.

:class:`VTUWriter` writes VTK XML UnstructuredGrid files with every array in the
``AppendedData`` section as raw binary (``encoding="raw"``, ``header_type="UInt64"``, little
endian), which ParaView, VTK and meshio read. The XML header and the bytes of the
geometry (points, connectivity, offsets, cell types) are built once; a frame only encodes
its fields (float32 by default) and writes header, fields and geometry in one call. Each
file is written to ``name.tmp`` and renamed when complete, so a reader never sees half a
frame. The units comment is placed right after the XML declaration.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

__all__ = ["VTUWriter", "VTK_TETRA"]

#: VTK cell type of a linear tetrahedron
VTK_TETRA = 10
_VTK_TYPES = {
    "float32": "Float32", "float64": "Float64", "int32": "Int32", "int64": "Int64",
    "uint8": "UInt8",
}  # fmt: skip


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
        self, points, cells, cell_type: int, point_fields: dict[str, int],
        cell_fields: list[str], comment: str = "", dtype=np.float32,
    ):  # fmt: skip
        pts = np.asarray(points, dtype=np.float64)
        if pts.shape[1] < 3:
            pts = np.hstack([pts, np.zeros((pts.shape[0], 3 - pts.shape[1]))])
        cells = np.asarray(cells)
        small = max(pts.shape[0], cells.size) < 2**31
        index = np.int32 if small else np.int64  # fewer bytes per frame
        cells = cells.astype(index)
        self.n_points, self.n_cells = pts.shape[0], cells.shape[0]
        self.dtype = np.dtype(dtype)
        self.point_fields, self.cell_fields = dict(point_fields), list(cell_fields)
        item = self.dtype.itemsize
        tags, offset = {"point": [], "cell": []}, 0
        for name, comps in self.point_fields.items():
            shape = (self.n_points, comps) if comps > 1 else (self.n_points,)
            tags["point"].append(_array_tag(name, np.empty(shape, self.dtype)[:0], offset))
            offset += 8 + item * int(np.prod(shape))
        for name in self.cell_fields:
            tags["cell"].append(_array_tag(name, np.empty(0, self.dtype), offset))
            offset += 8 + item * self.n_cells
        geometry = [
            ("Points", "", pts),
            ("Cells", "connectivity", cells.ravel()),
            ("Cells", "offsets", np.arange(1, self.n_cells + 1, dtype=index) * cells.shape[1]),
            ("Cells", "types", np.full(self.n_cells, cell_type, dtype=np.uint8)),
        ]
        geo_tags, blobs = {"Points": [], "Cells": []}, []
        for section, name, a in geometry:
            geo_tags[section].append(_array_tag(name, a, offset))
            blob = _block(a)
            blobs.append(blob)
            offset += len(blob)
        self._geometry = b"".join(blobs)
        xml = [
            '<?xml version="1.0"?>',
            comment,
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64">',
            "<UnstructuredGrid>",
            f'<Piece NumberOfPoints="{self.n_points}" NumberOfCells="{self.n_cells}">',
            "<PointData>", *tags["point"], "</PointData>",
            "<CellData>", *tags["cell"], "</CellData>",
            "<Points>", *geo_tags["Points"], "</Points>",
            "<Cells>", *geo_tags["Cells"], "</Cells>",
            "</Piece>",
            "</UnstructuredGrid>",
            '<AppendedData encoding="raw">',
            "_",
        ]  # fmt: skip
        self._head = "\n".join(line for line in xml if line).encode()
        self._tail = b"\n</AppendedData>\n</VTKFile>\n"

    def encode(self, point_data: dict, cell_data: dict) -> list[bytes]:
        """The byte chunks of one file with these fields (every declared one)."""
        chunks = [self._head]
        for name, comps in self.point_fields.items():
            a = np.asarray(point_data[name], dtype=self.dtype)
            if a.shape != ((self.n_points, comps) if comps > 1 else (self.n_points,)):
                raise ValueError(f"point field {name!r} has shape {a.shape}")
            chunks.append(_block(a))
        for name in self.cell_fields:
            a = np.asarray(cell_data[name], dtype=self.dtype)
            if a.shape != (self.n_cells,):
                raise ValueError(f"cell field {name!r} has shape {a.shape}")
            chunks.append(_block(a))
        chunks += [self._geometry, self._tail]
        return chunks

    def write(self, path, point_data: dict, cell_data: dict) -> Path:
        """Write ``path`` (via ``path.tmp`` and an atomic rename) and return it."""
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "wb") as f:
            f.writelines(self.encode(point_data, cell_data))
        os.replace(tmp, path)
        return path
