"""Mesh fields of many output frames at once, from a batch of (reduced) states.

:class:`FrameFields` is built once per output series. It stacks the rows of the model's
map to the full mesh that a frame needs (every displacement dof, the velocity and
temperature at the vertices) into one operator ``R``, so that a batch of ``B`` states
``X`` (``B × N``) is reconstructed by one product ``X Rᵀ`` (a GEMM for a reduced model,
whose ``to_full`` is dense, instead of ``B`` matrix-vector products). The centroid strain
is linear in the displacement, ``ε_e = G_e u``, with ``G`` sparse (the symmetric gradient
of each element's shape functions averaged over its quadrature points), so the von Mises
stress of a batch is ``G U`` followed by the invariant

.. math:: σ_{vM} = 2 μ \\sqrt{\\tfrac32\\, \\operatorname{dev} ε : \\operatorname{dev} ε},

the isotropic (``λ tr ε`` and thermal) part of the stress having no deviator. Contact and
friction impulses become vertex forces through a sparse scatter matrix built once.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..model.rub import FieldMap

__all__ = ["FrameFields", "strain_operator"]


def strain_operator(fields: FieldMap) -> tuple[sp.csr_matrix, list[tuple[int, int]]]:
    """Sparse ``G`` with ``(G u)[c n_e + e] = ε_ab`` at the centroid of element ``e``.

    ``c`` runs over the pairs ``(a, b)``, ``a ≤ b`` (returned); ``ε_ab`` is the mean over
    the element's quadrature points of ``(∂_b u_a + ∂_a u_b) / 2``.
    """
    bu = fields.basis_u
    dim = fields.mesh.p.shape[0]
    pairs = [(a, b) for a in range(dim) for b in range(a, dim)]
    n_e = bu.element_dofs.shape[1]
    rows, cols, vals = [], [], []
    for i, phi in enumerate(bu.basis):
        g = phi[0].grad.mean(axis=-1)  # (dim, dim, n_e): ∂_b φ_a at the centroid
        for c, (a, b) in enumerate(pairs):
            v = 0.5 * (g[a, b] + g[b, a])
            keep = v != 0.0
            if keep.any():
                rows.append(c * n_e + np.flatnonzero(keep))
                cols.append(bu.element_dofs[i, keep])
                vals.append(v[keep])
    G = sp.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(len(pairs) * n_e, bu.N),
    ).tocsr()
    return G, pairs


class FrameFields:
    """Point and cell data of a batch of frames of ``model`` on the mesh of ``fields``.

    Parameters
    ----------
    model : the (full or reduced) model; needs ``model.to_full``.
    fields : the :class:`~femrub.model.rub.FieldMap` of the full model.
    h : the run's time step (s), to turn contact impulses into forces.
    dtype : precision of the reconstruction of a reduced model's fields (``float32``
        halves the product's cost and memory; for files written in single precision).
    """

    def __init__(self, model, fields: FieldMap, h: float, dtype=np.float64):
        T = model.to_full
        bu, bt = fields.basis_u, fields.basis_t
        nu = bu.N
        vd = bu.nodal_dofs.T.ravel()  # vertex-major: (n_vertices, dim) flattened
        self.n_points, self.dim = bu.nodal_dofs.shape[1], bu.nodal_dofs.shape[0]
        self.n_cells = fields.mesh.t.shape[1]
        rest = np.setdiff1d(np.arange(nu), vd)
        order_u = np.concatenate([vd, rest])  # vertex dofs first, then any others
        has_t = model.layout.n_t > 0
        rows = [order_u, nu + vd] + ([2 * nu + bt.nodal_dofs[0]] if has_t else [])
        rows = np.concatenate(rows)
        self._nu, self._nv = nu, vd.size
        self._has_t, self._nt_points = has_t, bt.nodal_dofs.shape[1]
        if sp.issparse(T):
            self._R = sp.csr_matrix(T)[rows]
            self._RT = None
        else:
            self._R = None
            self._RT = np.ascontiguousarray(np.asarray(T)[rows].T, dtype=dtype)  # (N, n_rows)
        G, self.pairs = strain_operator(fields)
        self._G = G[:, order_u].tocsr()
        self.mu = float(fields.mu)
        c = fields.contacts
        nc = c.vertices.size
        self._scatter = sp.csr_matrix(
            (np.ones(nc), (c.vertices, np.arange(nc))), shape=(self.n_points, nc)
        )
        self._normals = np.asarray(c.normals)  # (dim, n_contacts)
        self._contact = model.contact
        self.h = float(h)

    def compute(self, X, impulse, friction=None) -> dict[str, np.ndarray]:
        """Fields of ``B`` frames: states ``X`` (B × N), impulses (B × n_c), friction
        impulses (B × n_c × 2, or ``None``).

        Returns point data ``displacement``, ``velocity``, ``contact_force``,
        ``friction_force`` (B × n_points × 3), ``temperature`` (B × n_points) and cell data
        ``von_mises`` (B × n_cells).
        """
        X = np.atleast_2d(np.asarray(X, dtype=float))
        B = X.shape[0]
        if self._R is None:
            full = X.astype(self._RT.dtype) @ self._RT  # (B, n_rows)
        else:
            full = (self._R @ X.T).T
        nu, nv, npt, d = self._nu, self._nv, self.n_points, self.dim
        u = full[:, :nu]
        out = {
            "displacement": _pad3(u[:, :nv].reshape(B, npt, d)),
            "velocity": _pad3(full[:, nu : nu + nv].reshape(B, npt, d)),
        }
        if self._has_t:
            out["temperature"] = full[:, nu + nv : nu + nv + self._nt_points]
        else:
            out["temperature"] = np.zeros((B, self._nt_points))
        out["contact_force"] = self._forces(impulse, B)
        out["friction_force"] = self._friction(friction, B)
        out["von_mises"] = self.von_mises(u)
        return out

    def von_mises(self, u: np.ndarray) -> np.ndarray:
        """Von Mises stress (Pa) per element of displacements ``u`` (B × n_u, this
        object's dof order): ``ε = G u``, then the invariant of its deviator."""
        n_e = self.n_cells
        eps = (self._G @ u.T).reshape(len(self.pairs), n_e, u.shape[0])
        diag = [c for c, (a, b) in enumerate(self.pairs) if a == b]
        off = [c for c, (a, b) in enumerate(self.pairs) if a != b]
        tr = eps[diag].sum(axis=0) / 3.0
        dev2 = ((eps[diag] - tr) ** 2).sum(axis=0) + 2.0 * (eps[off] ** 2).sum(axis=0)
        return (2.0 * self.mu * np.sqrt(1.5 * dev2)).T

    def _forces(self, impulse, B: int) -> np.ndarray:
        """Normal contact force (N) at the contact vertices, ``-λ n / h`` summed per vertex."""
        lam = np.asarray(impulse, dtype=float).reshape(B, -1)
        f = np.zeros((B, self.n_points, 3))
        if lam.shape[1]:
            per = -(lam[:, :, None] / self.h) * self._normals.T[None]  # (B, n_c, dim)
            f[..., : self.dim] = _scatter(self._scatter, per)
        return f

    def _friction(self, friction, B: int) -> np.ndarray:
        """Friction force (N) at the contact vertices, in global axes."""
        f = np.zeros((B, self.n_points, 3))
        c = self._contact
        if friction is None or c is None or c.frames is None or not np.size(friction):
            return f
        g = c.to_global(np.asarray(friction, dtype=float) / self.h)[..., : self.dim]
        f[..., : self.dim] = _scatter(self._scatter, g)
        return f


def _scatter(S: sp.csr_matrix, per: np.ndarray) -> np.ndarray:
    """Sum per-contact vectors ``per`` (B × n_c × k) onto the vertices (B × n_v × k)."""
    B, nc, k = per.shape
    out = S @ per.transpose(1, 0, 2).reshape(nc, B * k)
    return out.reshape(S.shape[0], B, k).transpose(1, 0, 2)


def _pad3(a: np.ndarray) -> np.ndarray:
    """``(B, n, dim)`` vectors as ``(B, n, 3)`` (zeros after ``dim``), as ParaView wants."""
    if a.shape[-1] == 3:
        return a
    return np.concatenate([a, np.zeros((*a.shape[:-1], 3 - a.shape[-1]))], axis=-1)
