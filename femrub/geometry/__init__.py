"""Blade geometries and meshes for rub simulations.

Builders (gmsh/OpenCASCADE) and readers all return a :class:`BladeMesh`: linear
tetrahedra (``skfem.MeshTet1``) in metres, with node sets ``root`` (clamped)
and ``tip`` (contact face), contact-point coordinates and the machine axis.

Builders: :func:`box_blade`, :func:`naca_blade`, :func:`sections_blade`,
:func:`loft_blade`. Readers: :func:`read_mesh` (dispatch), :func:`read_abaqus`,
:func:`read_gmsh`, :func:`read_meshio`, :func:`read_rotor37_mesh`.
"""

from .abaqus_reader import read_abaqus
from .blade_mesh import BladeMesh
from .box_blade import box_blade
from .errors import GeometryError
from .gmsh_reader import read_gmsh
from .loft import loft_blade
from .mesh_size import MeshSize
from .meshio_reader import read_meshio
from .naca_blade import naca_blade, naca_sections
from .readers import read_mesh
from .rotor37 import (
    ROTOR37_CONTACT_NODES,
    read_rotor37_mesh,
    rotor37_sections_blade,
    shared_data_dir,
)
from .section_blade import sections_blade
from .units import length_scale

__all__ = [
    "ROTOR37_CONTACT_NODES",
    "BladeMesh",
    "GeometryError",
    "MeshSize",
    "box_blade",
    "length_scale",
    "loft_blade",
    "naca_blade",
    "naca_sections",
    "read_abaqus",
    "read_gmsh",
    "read_mesh",
    "read_meshio",
    "read_rotor37_mesh",
    "rotor37_sections_blade",
    "sections_blade",
    "shared_data_dir",
]
