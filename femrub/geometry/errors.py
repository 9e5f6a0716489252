"""Error type raised by the geometry and mesh-input layer."""

from __future__ import annotations

__all__ = ["GeometryError"]


class GeometryError(ValueError):
    """Bad geometry parameters, unreadable mesh input or a missing node group.

    The message is always a single line that names the problem and how to fix
    it, so that command-line tools can print it verbatim.
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))
