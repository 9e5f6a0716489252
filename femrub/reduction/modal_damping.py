"""Modal Rayleigh damping through the Craig–Bampton reduction's interior factorisation.

A scene's ``physics.damping_ratio`` ζ asks for ``C = a M + b K`` with ratio ζ at two modes
``(i, j)`` of the full (clamped) blade, contacts free (:mod:`femrub.fem.damping`). Those
frequencies need a shift-invert solve with the whole stiffness ``K``; the reduction then
factorises ``K_ii``, the stiffness without the contact (boundary) dofs. :func:`modal_rayleigh`
does the latter first and takes the frequencies through it by static condensation
(:func:`~femrub.reduction.interior.condensed_solve`: one ``K_ii`` solve per right-hand
side), so the full ``K`` is never factorised; the :class:`~.interior.InteriorStiffness` it
returns is handed to the reductor
(:class:`~femrub.reduction.craig_bampton.ThermoelasticCraigBampton`, ``stiffness``), which
does not factorise ``K_ii`` again. The eigenproblem solved is the same (``K φ = ω² M φ`` on
all free dofs), to the eigen-solver's tolerance; ``docs/performance.md`` compares the
frequencies with those of a factorisation of ``K``.

The boundary is the model's (:func:`~femrub.model.build.contact_boundary`), in the
reduction's boundary coordinates when the contacts are patch means
(:mod:`femrub.reduction.boundary_coordinates`).
"""

from __future__ import annotations

from dataclasses import replace

from ..fem.damping import rayleigh_coefficients
from ..fem.eigen import angular_frequencies
from .boundary_coordinates import boundary_coordinates, boundary_dofs
from .interior import InteriorStiffness, condensed_solve

__all__ = ["modal_rayleigh"]


def modal_rayleigh(mats, zeta: float, modes: tuple[int, int], boundary: dict, at_least=0):
    """``(mats with C = a M + b K, interior stiffness, ω)`` for ratio ``zeta`` at ``modes``.

    Parameters
    ----------
    mats : :class:`~femrub.fem.assembly.ThermoelasticMatrices` (their ``C`` is replaced).
    zeta : damping ratio ζ in [0, 1); modes : the two modes ``(i, j)``, 1-based.
    boundary : ``{"u": boundary dofs, optional "u_rows": patch rows}`` of the model.
    at_least : how many of the lowest frequencies the eigen-solve finds at least (the
        natural frequencies a build reports: one solve instead of two).

    Returns
    -------
    mats : the blocks with ``C`` set and ``info["rayleigh"] = (a, b)``.
    stiffness : the :class:`~.interior.InteriorStiffness` of ``K_ii`` (for the reductor).
    omega : (max(i, j, at_least),) lowest angular frequencies (rad/s) of the full model.
    """
    i, j = modes
    n_u = mats.n_u
    coords = boundary_coordinates(boundary, n_u)
    K_prime = mats.K if coords is None else coords.congruent(mats.K)
    mb, _ = boundary_dofs(boundary, n_u, 0)
    stiffness = InteriorStiffness(K_prime, mb)
    solve = condensed_solve(K_prime, mb, stiffness)
    if coords is not None:
        solve = coords.solve(solve)
    omega = angular_frequencies(mats.K, mats.M, max(i, j, at_least), solve)
    a, b = rayleigh_coefficients(float(zeta), omega[i - 1], omega[j - 1])
    damped = replace(mats, C=(a * mats.M + b * mats.K).tocsr(), info=dict(mats.info))
    damped.info["rayleigh"] = (float(a), float(b))
    return damped, stiffness, omega
