"""The isotropic stiffness matrix from batched element products (no per-pair form calls).

scikit-fem assembles a bilinear form by evaluating it once per pair of element basis
functions (900 pairs for a P2 vector tetrahedron), each on every element and quadrature
point; for the stiffness :func:`~femrub.fem.forms.stiffness` that is most of the assembly
time of a blade. Writing the vector basis function ``i`` as ``φ_a e_c`` (``a = i // d``,
``c = i % d``, scikit-fem's ``ElementVector`` order) gives::

    K_ij = ∫ A (λ ∂_c φ_a ∂_c' φ_b + μ δ_cc' ∇φ_a · ∇φ_b + μ ∂_c' φ_a ∂_c φ_b) dx

for ``j = (b, c')``, so every entry is a combination of the element products
``T_e[a k, b l] = Σ_q w_q ∂_k φ_a ∂_l φ_b`` (one batched matrix product per element block)
of the scalar gradients scikit-fem computed for the basis (same mapping, curved or not;
same quadrature). :func:`isotropic_stiffness` returns the matrix
``forms.stiffness.assemble(basis, lam=λ, mu=μ, area=A)`` returns, to round-off.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["isotropic_stiffness"]

#: Elements per batch (bounds the temporaries: a few (batch, d n, d n) arrays).
BATCH = 4096


def isotropic_stiffness(basis, lam: float, mu: float, area: float = 1.0) -> sp.csr_matrix:
    """``K^uu = ∫ A σ(u) : ε(v) dx`` on the vector ``basis`` (see the module docstring).

    Parameters
    ----------
    basis : scikit-fem ``Basis`` of an ``ElementVector`` (its quadrature is used).
    lam, mu : Lamé parameters (Pa); area : cross-section (1 for a solid).
    """
    d = basis.mesh.dim()
    nb = basis.Nbfun
    if nb % d or basis.basis[0][0].grad.ndim != 4:
        raise ValueError("isotropic_stiffness needs a vector (ElementVector) basis")
    ns = nb // d
    # scalar gradients ∂_k φ_a: component 0 of the vector function a d is φ_a e_0
    h = np.stack([basis.basis[a * d][0].grad[0] for a in range(ns)])  # (ns, d, nel, nq)
    nel = h.shape[2]
    dx = np.asarray(basis.dx) * float(area)  # (nel, nq): weights × |det J|
    a_i, c_i = np.arange(nb) // d, np.arange(nb) % d
    A, C = a_i[:, None], c_i[:, None]
    Bj, Cj = a_i[None, :], c_i[None, :]
    same = (C == Cj).astype(float)
    data = np.empty((nb, nb, nel))
    for e0 in range(0, nel, BATCH):
        e1 = min(e0 + BATCH, nel)
        H = np.ascontiguousarray(h[:, :, e0:e1].transpose(2, 0, 1, 3)).reshape(e1 - e0, nb, -1)
        T = np.matmul(H * dx[e0:e1, None, :], H.transpose(0, 2, 1)).reshape(e1 - e0, ns, d, ns, d)
        S = np.einsum("eakbk->eab", T)  # ∇φ_a · ∇φ_b
        Ke = lam * T[:, A, C, Bj, Cj] + mu * same * S[:, A, Bj] + mu * T[:, A, Cj, Bj, C]
        data[:, :, e0:e1] = Ke.transpose(1, 2, 0)
    dofs = np.asarray(basis.element_dofs, dtype=np.int32)  # (nb, nel)
    rows = np.broadcast_to(dofs[:, None, :], data.shape).ravel()
    cols = np.broadcast_to(dofs[None, :, :], data.shape).ravel()
    n = basis.N
    K = sp.coo_matrix((data.ravel(), (rows, cols)), shape=(n, n)).tocsr()
    K.eliminate_zeros()  # as scikit-fem: no stored zeros (e.g. P1 pairs without coupling)
    return K
