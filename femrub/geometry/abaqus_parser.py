"""Minimal parser of Abaqus/CalculiX input decks: nodes, solid elements, sets, boundary."""

from __future__ import annotations

import re
import stat
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import GeometryError

__all__ = ["SOLID_TYPES", "AbaqusModel", "ElementBlock", "parse_abaqus"]

#: Supported solid element families: node count -> (cell kind, corner count).
SOLID_TYPES = {
    4: ("tetra", 4),
    10: ("tetra", 4),
    6: ("wedge", 6),
    15: ("wedge", 6),
    8: ("hexahedron", 8),
    20: ("hexahedron", 8),
}
_TYPE_RE = re.compile(r"^C3D(\d+)[A-Z]*$")
#: material keywords read, and the quantities of their first data line (Abaqus order)
_MATERIAL_KEYS = {
    "ELASTIC": ("young", "poisson"),
    "DENSITY": ("density",),
    "EXPANSION": ("expansion",),
    "CONDUCTIVITY": ("conductivity",),
    "SPECIFIC HEAT": ("specific_heat",),
}
_SUPPORTED = "C3D4, C3D10, C3D6, C3D15, C3D8, C3D20 (suffixes such as R, H, M allowed)"


@dataclass
class ElementBlock:
    """One ``*ELEMENT`` block: type, element numbers and node numbers ``(n_nodes, n)``."""

    etype: str
    ids: np.ndarray
    nodes: np.ndarray


@dataclass
class AbaqusModel:
    """Mesh content of an input deck, with node and element numbers as in the file."""

    node_ids: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    coords: np.ndarray = field(default_factory=lambda: np.zeros((3, 0)))
    blocks: list[ElementBlock] = field(default_factory=list)
    nsets: dict[str, list[int]] = field(default_factory=dict)
    elsets: dict[str, list[int]] = field(default_factory=dict)
    boundary: list[int] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    #: ``*MATERIAL`` blocks by name: ``{"young", "poisson", "density", "expansion",
    #: "conductivity", "specific_heat"}`` in the deck's units (first temperature row)
    materials: dict[str, dict[str, float]] = field(default_factory=dict)
    #: ``*SOLID SECTION``: ELSET name -> MATERIAL name
    sections: dict[str, str] = field(default_factory=dict)

    def find_set(self, sets: dict[str, list[int]], name: str) -> list[int] | None:
        """Case-insensitive set lookup (Abaqus names are case-insensitive)."""
        for key, value in sets.items():
            if key.upper() == name.upper():
                return value
        return None


def _params(line: str) -> tuple[str, dict[str, str]]:
    parts = [s.strip() for s in line[1:].split(",")]
    params = {}
    for part in parts[1:]:
        if part:
            key, _, value = part.partition("=")
            params[key.strip().upper()] = value.strip()
    return parts[0].upper(), params


#: most members one GENERATE line may give (a deck's node count is far below)
MAX_GENERATED = 100_000_000


def _generated(line: str, where: str) -> range:
    """The members of a ``first, last[, step]`` line of a GENERATE set."""
    try:
        v = [int(float(tok)) for tok in line.split(",") if tok.strip()]
    except (ValueError, OverflowError):
        v = []
    if len(v) not in (2, 3) or (len(v) == 3 and v[2] < 1):
        raise GeometryError(
            f"GENERATE set at {where} needs 'first, last[, step >= 1]' lines, got {line!r}."
        )
    first, last, step = (v + [1])[:3]
    count = max((last - first) // step + 1, 0)  # Python integers: no overflow
    if count > MAX_GENERATED:
        raise GeometryError(
            f"GENERATE set at {where} gives {count:.3g} members (at most "
            f"{MAX_GENERATED:.0e}): check the line {line!r}."
        )
    return range(first, last + 1, step)


def _set_members(model: AbaqusModel, sets, lines, generate, where) -> list[int]:
    out: list[int] = []
    if generate:
        for line in lines:
            out.extend(_generated(line, where))
        return out
    for tok in (tok.strip() for line in lines for tok in line.split(",")):
        if not tok:
            continue
        try:
            out.append(int(tok))
        except ValueError:
            members = model.find_set(sets, tok)
            if members is None:
                raise GeometryError(
                    f"Set {tok!r} used at {where} is not defined before its use."
                ) from None
            out.extend(members)
    return out


#: largest deck file read (bytes): a bigger one, or a device (``/dev/zero``), is refused
MAX_DECK_BYTES = 4 * 2**30


def _check_size(path: Path) -> None:
    """Refuse a deck file that is not a regular file or exceeds :data:`MAX_DECK_BYTES`."""
    try:
        st = path.stat()
    except OSError as exc:
        raise GeometryError(
            f"Cannot read Abaqus/CalculiX file {str(path)!r}: {exc.strerror}; check the path."
        ) from None
    if not stat.S_ISREG(st.st_mode):
        raise GeometryError(
            f"Abaqus/CalculiX file {str(path)!r} is not a regular file (a device or a folder); "
            "give the path of a deck file."
        )
    if st.st_size > MAX_DECK_BYTES:
        raise GeometryError(
            f"Abaqus/CalculiX file {str(path)!r} holds {st.st_size / 2**30:.1f} GiB, more than "
            f"the {MAX_DECK_BYTES / 2**30:.0f} GiB read; check the *INCLUDE or split the mesh."
        )


class _Parser:
    def __init__(self) -> None:
        self.model = AbaqusModel()
        self._node_ids: list[np.ndarray] = []
        self._coords: list[np.ndarray] = []

    def parse(self, path: Path, depth: int = 0) -> None:
        if depth > 10:
            raise GeometryError(f"*INCLUDE nesting deeper than 10 levels at {str(path)!r}.")
        _check_size(path)
        try:
            text = path.read_text(encoding="utf-8", errors="strict")
        except (OSError, UnicodeDecodeError) as exc:
            reason = getattr(exc, "strerror", None) or exc
            raise GeometryError(
                f"Cannot read Abaqus/CalculiX file {str(path)!r}: {reason}; check the path."
            ) from exc
        self.model.files.append(str(path))
        keyword, params, start, data = None, {}, 0, []
        lines = text.splitlines()
        for number, raw in enumerate(lines + ["*END OF FILE"], start=1):
            line = raw.strip()
            if not line or line.startswith("**"):
                continue
            if line.startswith("*"):
                if keyword is not None:
                    self._block(keyword, params, data, f"{path}:{start}", path, depth)
                keyword, params = _params(line)
                start, data = number, []
            elif keyword is not None:
                data.append(line)

    def _block(self, keyword, params, data, where, path, depth) -> None:
        if keyword in _MATERIAL_KEYS or keyword == "MATERIAL":
            self._material(keyword, params, data, where)
        elif keyword == "SOLID SECTION":
            self.model.sections[params.get("ELSET", "")] = params.get("MATERIAL", "")
        elif keyword == "INCLUDE":
            name = params.get("INPUT", "").strip("'\"")
            if not name:
                raise GeometryError(f"*INCLUDE without INPUT= at {where}.")
            self.parse((path.parent / name).resolve(), depth + 1)
        elif keyword == "NODE":
            self._nodes(params, data, where)
        elif keyword == "ELEMENT":
            self._elements(params, data, where)
        elif keyword in ("NSET", "ELSET"):
            self._set(keyword, params, data, where)
        elif keyword == "BOUNDARY":
            self._boundary(data, where)

    def _set(self, keyword, params, data, where) -> None:
        """``*NSET`` or ``*ELSET``: members appended to the named set."""
        sets = self.model.nsets if keyword == "NSET" else self.model.elsets
        name = params.get(keyword) or ""
        members = _set_members(self.model, sets, data, "GENERATE" in params, where)
        sets.setdefault(name, []).extend(members)

    def _boundary(self, data, where) -> None:
        """``*BOUNDARY``: the clamped nodes (numbers or node-set names)."""
        for line in data:
            first = line.split(",")[0].strip()
            try:
                self.model.boundary.append(int(first))
            except ValueError:
                members = self.model.find_set(self.model.nsets, first)
                if members is None:
                    raise GeometryError(
                        f"*BOUNDARY at {where} uses undefined node set {first!r}."
                    ) from None
                self.model.boundary.extend(members)

    def _material(self, keyword, params, data, where) -> None:
        if keyword == "MATERIAL":
            self._mat = params.get("NAME", "")
            self.model.materials[self._mat] = {}
            return
        if getattr(self, "_mat", None) is None:
            raise GeometryError(f"*{keyword} at {where} outside a *MATERIAL block.")
        try:
            first = [float(v) for v in data[0].split(",") if v.strip()] if data else []
        except ValueError as exc:
            raise GeometryError(f"Malformed *{keyword} data at {where}: {exc}.") from exc
        names = _MATERIAL_KEYS[keyword]
        if keyword == "ELASTIC" and params.get("TYPE", "ISOTROPIC")[:3] != "ISO":
            raise GeometryError(
                f"*ELASTIC, TYPE={params['TYPE']} at {where}: only isotropic elasticity is read;"
                " give material.young and material.poisson in the scene instead."
            )
        if len(first) < len(names):
            raise GeometryError(f"*{keyword} at {where} needs {len(names)} value(s), got {first}.")
        self.model.materials[self._mat].update(zip(names, first))

    def _nodes(self, params, data, where) -> None:
        try:
            rows = [[float(v) for v in line.split(",") if v.strip()] for line in data]
            ids = np.array([int(r[0]) for r in rows], dtype=np.int64)
            xyz = np.zeros((3, len(rows)))
            for k, r in enumerate(rows):
                xyz[: len(r) - 1, k] = r[1:4]
        except (ValueError, IndexError, OverflowError) as exc:
            raise GeometryError(f"Malformed *NODE line in block at {where}: {exc}.") from exc
        if not np.isfinite(xyz).all():
            k = int(np.flatnonzero(~np.isfinite(xyz).all(axis=0))[0])
            raise GeometryError(
                f"*NODE {ids[k]} in block at {where} has a non-finite coordinate; fix the deck."
            )
        self._node_ids.append(ids)
        self._coords.append(xyz)
        if params.get("NSET"):
            self.model.nsets.setdefault(params["NSET"], []).extend(ids.tolist())

    def _elements(self, params, data, where) -> None:
        etype = params.get("TYPE", "").upper()
        match = _TYPE_RE.match(etype)
        if not match or int(match.group(1)) not in SOLID_TYPES:
            raise GeometryError(
                f"Unsupported element type {etype!r} at {where}; supported: {_SUPPORTED}."
            )
        n_nodes = int(match.group(1))
        try:
            values = np.array(
                [int(v) for line in data for v in line.split(",") if v.strip()], dtype=np.int64
            )
        except (ValueError, OverflowError) as exc:
            raise GeometryError(f"Malformed *ELEMENT data in block at {where}: {exc}.") from exc
        if values.size % (n_nodes + 1):
            raise GeometryError(
                f"*ELEMENT block at {where} has {values.size} numbers, not a multiple of"
                f" {n_nodes + 1} (element id + {n_nodes} nodes for {etype})."
            )
        table = values.reshape(-1, n_nodes + 1)
        self.model.blocks.append(ElementBlock(etype, table[:, 0], table[:, 1:].T.copy()))
        if params.get("ELSET"):
            self.model.elsets.setdefault(params["ELSET"], []).extend(table[:, 0].tolist())

    def finish(self) -> AbaqusModel:
        if self._node_ids:
            self.model.node_ids = np.concatenate(self._node_ids)
            self.model.coords = np.hstack(self._coords)
        return self.model


def parse_abaqus(path: str | Path) -> AbaqusModel:
    """Parse nodes, solid elements, node/element sets and boundary nodes of a deck.

    Supports ``*NODE`` (with ``NSET=``), ``*ELEMENT`` (``TYPE=``, ``ELSET=``;
    continuation lines), ``*NSET``/``*ELSET`` (with ``GENERATE`` or set names),
    ``*BOUNDARY`` (node numbers or node-set names), ``*INCLUDE`` (relative to
    the including file), ``*MATERIAL`` with ``*ELASTIC`` (isotropic), ``*DENSITY``,
    ``*EXPANSION``, ``*CONDUCTIVITY``, ``*SPECIFIC HEAT`` (first line: values at the first
    temperature) and ``*SOLID SECTION`` (ELSET -> MATERIAL). Other keywords are skipped.
    Comments start with ``**``.

    Parameters
    ----------
    path : str or pathlib.Path
        ``.inp`` file (or an included mesh file such as CalculiX ``.msh``).

    Returns
    -------
    AbaqusModel
        Parsed content with file numbering.

    Raises
    ------
    GeometryError
        If a file cannot be read, an element type is unsupported or data are malformed.
    """
    parser = _Parser()
    parser.parse(Path(path))
    model = parser.finish()
    if model.node_ids.size == 0 or not model.blocks:
        raise GeometryError(
            f"No *NODE or solid *ELEMENT data found in {str(path)!r}; is this an Abaqus/CalculiX"
            " input deck (check *INCLUDE paths)?"
        )
    return model
