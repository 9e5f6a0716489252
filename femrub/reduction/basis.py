"""A Craig–Bampton basis assembled in the reduced state's order (paper Eqs. 12–13).

The reduced state is ``X̄ = [u_b, q_u | v_b, q_v | θ_b, q_θ]`` (the blocks the steppers
expect); the rows of a basis are the full state's ``[u | v | θ]``. :func:`assemble_basis`
puts each family of shapes in its place::

        u_b   q_u     v_b   q_v     θ_b   q_θ
    u_b [ I                                  ]
    u_i [ Ψ    Φ_u    Ψ             Ψ    Φ^uθ ]
    v_b [             I                      ]
    v_i [ Ψ           Ψ    Φ_v      Ψ        ]
    θ_b [                           I        ]
    θ_i [ Ψ           Ψ             Ψ    χ    ]

(``Ψ``: the columns of the static shapes of Eq. 11 on the interior rows, zero where the
projection has none). The same function assembles the right basis ``R`` and the left basis
``R̃`` from their own shapes.
"""

from __future__ import annotations

import numpy as np

__all__ = ["assemble_basis", "left_static_shapes", "velocity_static_shapes"]


def assemble_basis(
    index, interior, n_u: int, n_full: int, layout, psi, u_shapes, v_shapes, chi, chi_u
) -> np.ndarray:
    """The (n_full, layout.n) basis of the diagram above.

    Parameters
    ----------
    index : ``(mb, mi, tb, ti)``: boundary and interior positions in the u- and θ-blocks.
    interior : full-state rows of the interior dofs ``[mi, n_u + mi, 2 n_u + ti]``.
    n_u, n_full : size of the full u-block and of the full state.
    layout : the reduced :class:`~femrub.model.first_order.Layout`.
    psi : (interior, 2 n_b + n_θb) static shapes of the boundary dofs, or ``None`` (zero).
    u_shapes, v_shapes : displacement and velocity shapes on the mechanical interior.
    chi, chi_u : thermal shapes on the thermal interior and their displacement coupling
        correction on the mechanical interior.
    """
    mb, mi, tb, ti = index
    nb = mb.size
    V = np.zeros((n_full, layout.n))
    cu_b = np.arange(0, nb)
    cv_b = layout.v.start + np.arange(nb)
    ct_b = layout.t.start + np.arange(tb.size)
    for k, (rows, cols) in enumerate([(mb, cu_b), (n_u + mb, cv_b), (2 * n_u + tb, ct_b)]):
        V[rows, cols] = 1.0  # boundary dofs kept (Eq. 12) with their static shapes (Eq. 11)
        first = [0, nb, 2 * nb][k]
        if psi is not None:
            V[interior[:, None], cols[None, :]] = psi[:, first : first + cols.size]
    V[mi[:, None], np.arange(nb, nb + u_shapes.shape[1])[None, :]] = u_shapes
    V[(n_u + mi)[:, None], (layout.v.start + nb + np.arange(v_shapes.shape[1]))[None, :]] = v_shapes
    cq_t = layout.t.start + tb.size + np.arange(chi.shape[1])
    V[(2 * n_u + ti)[:, None], cq_t[None, :]] = chi
    V[mi[:, None], cq_t[None, :]] = chi_u
    return V


def velocity_static_shapes(psi, projection: str, n_i: int, nb: int) -> None:
    """Set, in place, the boundary velocities' static shapes the ``projection`` asks for.

    ``psi`` (interior rows ``[u_i, v_i, θ_i]``, columns ``[u_b, v_b, θ_b]``) holds Eq. (11)'s
    ``−B_ii⁻¹ B_ib``. ``"static-mass"``: ``v_i = Ψ_uu v_b`` (the static shapes' inertia);
    ``"second-order"``: the velocity shapes are the displacement ones, ``[I; Ψ_uu]``.
    """
    if projection in ("static-mass", "second-order"):
        psi[n_i : 2 * n_i, nb : 2 * nb] = psi[:n_i, :nb]
    if projection == "second-order":
        psi[:n_i, nb : 2 * nb] = 0.0


def left_static_shapes(psi, projection: str, n_i: int, nb: int, adjoint_shapes):
    """Static shapes of the left basis: the adjoint ones (``adjoint_shapes()``,
    ``"adjoint"``), the momentum rows of ``v_b`` on ``[1; Ψ_uu]`` (``"static-mass"``), or
    ``None`` (``"petrov-galerkin"``: the boundary equations kept as in the full model)."""
    if projection == "adjoint":
        return adjoint_shapes()
    if projection == "static-mass":
        psi_l = np.zeros_like(psi)
        psi_l[n_i : 2 * n_i, nb : 2 * nb] = psi[:n_i, :nb]
        return psi_l
    return None
