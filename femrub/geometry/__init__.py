"""Blade geometries and meshes for rub simulations.

Builders (gmsh/OpenCASCADE) and readers all return a :class:`BladeMesh`: linear
tetrahedra (``skfem.MeshTet1``) in metres, with node sets ``root`` (clamped)
and ``tip`` (contact face), contact-point coordinates and the machine axis.

Builders: :func:`box_blade`, :func:`naca_blade`, :func:`sections_blade`,
:func:`loft_blade`. Readers: :func:`read_mesh` (dispatch), :func:`read_abaqus`,
:func:`read_gmsh`, :func:`read_meshio`, :func:`read_rotor37_mesh`.
"""

from .._lazy import lazy_attributes

# imported on first use (PEP 562): `femrub --help` stays fast
_LAZY = {
    "read_abaqus": ".abaqus_reader",
    "BladeMesh": ".blade_mesh",
    "box_blade": ".box_blade",
    "GeometryError": ".errors",
    "read_gmsh": ".gmsh_reader",
    "loft_blade": ".loft",
    "MeshSize": ".mesh_size",
    "read_meshio": ".meshio_reader",
    "naca_blade": ".naca_blade",
    "naca_sections": ".naca_blade",
    "read_mesh": ".readers",
    "ROTOR37_CONTACT_NODES": ".rotor37",
    "read_rotor37_mesh": ".rotor37",
    "rotor37_sections_blade": ".rotor37",
    "shared_data_dir": ".rotor37",
    "sections_blade": ".section_blade",
    "length_scale": ".units",
}

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


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, __all__)
