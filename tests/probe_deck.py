"""A small CalculiX deck of a blade-like beam of quadratic tetrahedra, for probe tests."""

from __future__ import annotations

from itertools import product
from pathlib import Path

import numpy as np

#: cells along the span (x, radial), the chord (y) and the thickness (z); cell sizes (mm)
CELLS, SIZE = (4, 2, 1), (15.0, 10.0, 4.0)
#: radius of the root face (mm); the machine axis is z
HUB = 100.0
#: the six tetrahedra of a cube along its main diagonal (conforming between cubes)
_KUHN = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]
_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


def write_deck(folder: Path) -> dict:
    """Write ``blade.inp`` (C3D10, mm) into ``folder``; return its path and node numbers:
    ``corner[(i, j, k)]`` (grid indices) and ``mid[(a, b)]`` (the node on edge a–b)."""
    nx, ny, nz = CELLS
    corner, xyz = {}, {}
    for i, j, k in product(range(nx + 1), range(ny + 1), range(nz + 1)):
        corner[i, j, k] = 1 + len(corner)
        xyz[corner[i, j, k]] = (HUB + i * SIZE[0], j * SIZE[1], k * SIZE[2])
    mid, elements = {}, []
    for i, j, k in product(range(nx), range(ny), range(nz)):
        cube = [corner[i + a, j + b, k + c] for a, b, c in product((0, 1), repeat=3)]
        for tet in _KUHN:
            nodes = [cube[q] for q in tet]
            conn = list(nodes)
            for a, b in _EDGES:
                edge = tuple(sorted((nodes[a], nodes[b])))
                if edge not in mid:
                    mid[edge] = 1000 + len(mid)
                    xyz[mid[edge]] = tuple(0.5 * (np.add(xyz[edge[0]], xyz[edge[1]])))
                conn.append(mid[edge])
            elements.append(", ".join(map(str, [len(elements) + 1, *conn])))
    root = [n for n, p in xyz.items() if p[0] == HUB]
    lines = ["*NODE"] + [f"{n}, {x:.9g}, {y:.9g}, {z:.9g}" for n, (x, y, z) in xyz.items()]
    lines += ["*ELEMENT, TYPE=C3D10, ELSET=ALL", *elements]
    lines += ["*NSET, NSET=ROOT", *(str(n) for n in root), "*BOUNDARY", "ROOT, 1, 3"]
    path = Path(folder) / "blade.inp"
    path.write_text("\n".join(lines) + "\n")
    return {"path": path, "corner": corner, "mid": mid, "xyz": xyz}
