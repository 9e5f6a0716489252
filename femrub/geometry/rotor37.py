"""NASA Rotor 37 reference data (read-only, outside the project): paths and readers."""

from __future__ import annotations

import os
from pathlib import Path

from .abaqus_reader import read_abaqus
from .blade_mesh import BladeMesh
from .errors import GeometryError
from .section_blade import sections_blade

__all__ = [
    "ROTOR37_CONTACT_NODES",
    "read_rotor37_mesh",
    "rotor37_sections_blade",
    "shared_data_dir",
]

#: Tip contact nodes of the CalculiX model (all are corner nodes of the C3D15 wedges).
ROTOR37_CONTACT_NODES = (
    188,
    190,
    192,
    194,
    196,
    198,
    200,
    203,
    253,
    255,
    257,
    259,
    261,
    263,
    265,
    267,
)


def shared_data_dir() -> Path:
    """Reference-data folder: ``$FEMRUB_SHARED_DATA`` or ``<project>/../shared/data``.

    The folder may not exist (fresh clones); callers must check.
    """
    env = os.environ.get("FEMRUB_SHARED_DATA")
    return Path(env) if env else Path(__file__).resolve().parents[2].parent / "shared" / "data"


def _require_dir(path: Path, what: str) -> Path:
    if not path.is_dir():
        raise GeometryError(
            f"{what} folder {str(path)!r} not found; set FEMRUB_SHARED_DATA or pass data_dir."
        )
    return path


def read_rotor37_mesh(data_dir: str | Path | None = None) -> BladeMesh:
    """Read the Rotor 37 CalculiX blade (mm) as tetrahedra in metres.

    Root = the ``*BOUNDARY`` nodes, tip detected from the rotation axis z,
    contact points = :data:`ROTOR37_CONTACT_NODES`.

    Parameters
    ----------
    data_dir : str or pathlib.Path, optional
        Folder holding ``rotor37-fe-mesh/`` (default :func:`shared_data_dir`).
    """
    base = Path(data_dir) if data_dir is not None else shared_data_dir()
    folder = _require_dir(base / "rotor37-fe-mesh", "Rotor 37 mesh")
    return read_abaqus(folder / "blade.inp", "mm", radial_axis="z", contact=ROTOR37_CONTACT_NODES)


def rotor37_sections_blade(data_dir: str | Path | None = None, **kwargs) -> BladeMesh:
    """Loft and mesh the six Rotor 37 profiles (cm, rotation axis x).

    Parameters
    ----------
    data_dir : str or pathlib.Path, optional
        Folder holding ``rotor37-sections/`` (default :func:`shared_data_dir`).
    **kwargs
        Passed to :func:`~femrub.geometry.section_blade.sections_blade` (``h``, ...).
    """
    base = Path(data_dir) if data_dir is not None else shared_data_dir()
    folder = _require_dir(base / "rotor37-sections", "Rotor 37 sections")
    return sections_blade(
        folder, length_unit="cm", pattern="R37_profile*.csv", radial_axis="x", **kwargs
    )
