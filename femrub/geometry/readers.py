"""Read any supported blade mesh file, choosing the reader from its content."""

from __future__ import annotations

from pathlib import Path

from .abaqus_reader import read_abaqus
from .blade_mesh import BladeMesh
from .errors import GeometryError
from .gmsh_reader import read_gmsh
from .meshio_reader import read_meshio

__all__ = ["detect_format", "read_mesh"]


def detect_format(path: str | Path) -> str:
    """Return ``"gmsh"``, ``"abaqus"`` or ``"meshio"`` for a mesh file.

    gmsh files start with ``$MeshFormat``; Abaqus/CalculiX decks with a
    ``*KEYWORD`` line (whatever their suffix, e.g. CalculiX ``blade.msh``);
    anything else is left to meshio.

    Raises
    ------
    GeometryError
        If the file does not exist or cannot be opened.
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096).lstrip(b"\xef\xbb\xbf \t\r\n")
    except OSError as exc:
        raise GeometryError(
            f"Cannot read mesh file {str(path)!r}: {exc.strerror or exc}; check the path."
        ) from exc
    if head.startswith(b"$MeshFormat"):
        return "gmsh"
    if head.startswith(b"*"):
        return "abaqus"
    return "meshio"


def read_mesh(path: str | Path, length_unit: str | None = None, **kwargs) -> BladeMesh:
    """Read a blade mesh file with the matching reader.

    Parameters
    ----------
    path : str or pathlib.Path
        gmsh ``.msh``, Abaqus/CalculiX ``.inp`` (or included ``.msh``) or a meshio format.
    length_unit : str, optional
        Unit of the file coordinates. Required for Abaqus/CalculiX decks;
        default ``"m"`` for other formats.
    **kwargs
        Passed on to :func:`read_gmsh`, :func:`read_abaqus` or :func:`read_meshio`.

    Returns
    -------
    BladeMesh
        Mesh in metres.
    """
    fmt = detect_format(path)
    if fmt == "abaqus":
        if length_unit is None:
            raise GeometryError(
                f"{str(path)!r} is an Abaqus/CalculiX deck without unit information;"
                " pass length_unit (CLI: --unit): 'mm' for N-mm-t-s models, 'm' or 'cm'."
            )
        return read_abaqus(path, length_unit, **kwargs)
    unit = "m" if length_unit is None else length_unit
    return (read_gmsh if fmt == "gmsh" else read_meshio)(path, unit, **kwargs)
