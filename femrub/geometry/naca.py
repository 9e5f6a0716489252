"""NACA 4-digit airfoil coordinates (closed trailing edge), pure numpy."""

from __future__ import annotations

import numpy as np

from .errors import GeometryError

__all__ = ["naca4_parameters", "naca4_sides"]


def naca4_parameters(code: str) -> tuple[float, float, float]:
    """Decode a NACA 4-digit designation.

    Parameters
    ----------
    code : str
        Four digits ``MPTT``, e.g. ``"0012"`` or ``"2412"``.

    Returns
    -------
    m, p, t : float
        Maximum camber, its chordwise position and maximum thickness, as chord fractions.

    Raises
    ------
    GeometryError
        If ``code`` is not four digits, or is cambered with zero camber position.
    """
    code = str(code).strip().upper().removeprefix("NACA").strip()
    if len(code) != 4 or not code.isdigit():
        raise GeometryError(
            f"NACA code must be four digits such as '0012' or '2412', got {code!r}."
        )
    m, p, t = int(code[0]) / 100.0, int(code[1]) / 10.0, int(code[2:]) / 100.0
    if t <= 0 or (m > 0 and p == 0):
        raise GeometryError(
            f"NACA code {code!r} is degenerate; use non-zero thickness and camber position."
        )
    return m, p, t


def naca4_sides(code: str, n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower surface of a unit-chord NACA 4-digit section.

    The thickness law uses the closed-trailing-edge coefficient -0.1036 so the
    section ends in a sharp edge and has no tiny trailing-edge face to resolve.
    Points are cosine spaced; both sides run from the leading edge (0, 0) to the
    trailing edge (1, 0), and the midpoint of the k-th points of the two sides
    lies exactly on the camber line.

    Parameters
    ----------
    code : str
        NACA 4-digit designation.
    n : int, optional
        Points per side (>= 4), including both ends.

    Returns
    -------
    upper, lower : numpy.ndarray
        Coordinates ``(2, n)`` in chord units.
    """
    if n < 4:
        raise GeometryError(f"Need at least 4 points per NACA side, got {n}.")
    m, p, t = naca4_parameters(code)
    x = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, n)))
    yt = 5 * t * (0.2969 * np.sqrt(x) - 0.1260 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1036 * x**4)
    if m > 0:
        front = x < p
        yc = np.where(
            front, m / p**2 * (2 * p * x - x**2), m / (1 - p) ** 2 * (1 - 2 * p + 2 * p * x - x**2)
        )
        dyc = np.where(front, 2 * m / p**2 * (p - x), 2 * m / (1 - p) ** 2 * (p - x))
    else:
        yc, dyc = np.zeros_like(x), np.zeros_like(x)
    theta = np.arctan(dyc)
    upper = np.vstack([x - yt * np.sin(theta), yc + yt * np.cos(theta)])
    lower = np.vstack([x + yt * np.sin(theta), yc - yt * np.cos(theta)])
    upper[:, [0, -1]] = lower[:, [0, -1]] = [[0.0, 1.0], [0.0, 0.0]]
    return upper, lower
