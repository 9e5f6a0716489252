"""Error type raised by the geometry and mesh-input layer."""

from __future__ import annotations

__all__ = ["GeometryError", "check_positive"]


class GeometryError(ValueError):
    """Bad geometry parameters, unreadable mesh input or a missing node group.

    The message is always a single line that names the problem and how to fix
    it, so that command-line tools can print it verbatim.
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


def check_positive(what: str, **lengths: float) -> None:
    """Raise :class:`GeometryError` unless every given length is a positive finite number.

    Parameters
    ----------
    what : str
        Name of the object being built, used in the message (e.g. ``"Box blade"``).
    **lengths : float
        Named lengths in metres.
    """
    for name, value in lengths.items():
        if not (isinstance(value, (int, float)) and 0.0 < value < float("inf")):
            raise GeometryError(
                f"{what} {name} must be a positive length in metres, got {value!r}."
            )
