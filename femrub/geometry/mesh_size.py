"""Mesh-size parameters for gmsh blade meshes, with a lower bound."""

from __future__ import annotations

from dataclasses import dataclass

from .errors import GeometryError
from .gmsh_session import GmshSession

__all__ = ["MeshSize"]


@dataclass(frozen=True)
class MeshSize:
    """Target and minimum element size of a gmsh tetrahedral mesh.

    Attributes
    ----------
    h : float
        Target (maximum) element size in metres.
    h_min : float or None
        Lower bound in metres on the size field, so that curvature refinement at
        thin leading/trailing edges cannot make the element count explode.
        Default ``h / 4``.
    curvature : int
        Elements per 2*pi of boundary curvature (0 disables curvature refinement).
    optimize : bool
        Run gmsh's Netgen optimiser on the tetrahedra.
    """

    h: float
    h_min: float | None = None
    curvature: int = 12
    optimize: bool = True

    def __post_init__(self) -> None:
        if not (isinstance(self.h, (int, float)) and self.h > 0):
            raise GeometryError(f"Mesh size h must be a positive length in metres, got {self.h!r}.")
        h_min = self.h / 4 if self.h_min is None else self.h_min
        if not (isinstance(h_min, (int, float)) and 0 < h_min <= self.h):
            raise GeometryError(
                f"Lower mesh-size bound h_min must satisfy 0 < h_min <= h = {self.h!r},"
                f" got {self.h_min!r}."
            )
        if self.curvature < 0:
            raise GeometryError(f"curvature must be >= 0 elements per 2*pi, got {self.curvature}.")
        object.__setattr__(self, "h_min", float(h_min))

    def apply(self, session: GmshSession) -> None:
        """Set the gmsh options for linear tetrahedra of this size."""
        session.set_option("Mesh.MeshSizeMax", self.h)
        session.set_option("Mesh.MeshSizeMin", self.h_min)
        session.set_option("Mesh.MeshSizeFromCurvature", int(self.curvature))
        session.set_option("Mesh.MeshSizeFromPoints", 1)
        session.set_option("Mesh.MeshSizeExtendFromBoundary", 1)
        session.set_option("Mesh.ElementOrder", 1)
        session.set_option("Mesh.Optimize", 1)
        session.set_option("Mesh.OptimizeNetgen", 1 if self.optimize else 0)
