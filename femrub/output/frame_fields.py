"""Mesh fields of many output frames at once, from a batch of (reduced) states.

:class:`FrameFields` is built once per output series. A frame needs the displacement and
velocity at the vertices, the temperature at the vertices and the von Mises stress at the
centroid of every element. Each is linear in the state ``X`` (but the last, a norm of a
linear function), so the class stacks, once, the rows of the model's map to the full mesh
``to_full`` that give them, restricted to the columns of ``X`` they depend on (a reduced
model's displacement rows depend on its displacement coordinates only): a batch of ``B``
states is then a few products ``X_c M_cᵀ`` (GEMMs for a reduced model, whose ``to_full`` is
dense, in the files' precision; sparse products for a full model).

The centroid strain is linear in the displacement, ``ε_e = G_e u`` (``G`` sparse: the
symmetric gradient of each element's shape functions averaged over its quadrature points).
The von Mises stress only needs the deviator of ``ε``, and

.. math:: σ_{vM} = 2 μ \\sqrt{\\tfrac32\\, \\operatorname{dev} ε : \\operatorname{dev} ε}
          = \\lVert Q ε \\rVert ,

with ``Q`` (``k × n_pairs``: ``k = 5`` in 3D) the square root of that quadratic form,
``Qᵀ Q = 6 μ² D`` (``D``: ``dev ε : dev ε`` on the independent components ``ε_ab``,
``a ≤ b``), the isotropic (``λ tr ε`` and thermal) part of the stress having no deviator.
For a reduced model ``Q G Φ_u`` (``Φ_u``: the displacement rows of ``to_full``) is a dense
``k n_e × r_u`` matrix computed once, so the stress of a batch is one GEMM and a norm over
``k`` rows. Contact and friction impulses become vertex forces through a sparse scatter
matrix built once.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..model.rub import FieldMap
from ..reduction.truncation import columns_of

__all__ = ["FrameFields", "deviator_root"]


def deviator_root(pairs: list[tuple[int, int]], mu: float) -> np.ndarray:
    """``Q`` (k × n_pairs) with ``‖Q ε‖² = 6 μ² (Σ_a (ε_aa − tr ε / 3)² + 2 Σ_{a<b} ε_ab²)``,
    i.e. ``‖Q ε‖ = σ_vM``, on the components ``ε_ab`` of ``pairs`` (``tr ε`` as a sum over
    the diagonal pairs); ``k`` is the rank of the form (5 in 3D)."""
    diag = [c for c, (a, b) in enumerate(pairs) if a == b]
    P = np.zeros((len(pairs), len(pairs)))
    Dd = np.eye(len(diag)) - 1.0 / 3.0  # ε_aa − tr ε / 3 on the diagonal pairs
    P[np.ix_(diag, diag)] = Dd.T @ Dd
    for c, (a, b) in enumerate(pairs):
        if a != b:
            P[c, c] = 2.0
    w, V = np.linalg.eigh(6.0 * mu**2 * P)
    keep = w > 1e-12 * w.max()
    return np.sqrt(w[keep])[:, None] * V[:, keep].T


class FrameFields:
    """Point and cell data of a batch of frames of ``model`` on the mesh of ``fields``.

    Parameters
    ----------
    model : the (full or reduced) model; needs ``model.to_full``.
    fields : the :class:`~femrub.model.rub.FieldMap` of the full model.
    h : the run's time step (s), to turn contact impulses into forces.
    dtype : precision of the reconstruction of a reduced model's fields (``float32``
        halves the products' cost and memory; for files written in single precision).
    """

    def __init__(self, model, fields: FieldMap, h: float, dtype=np.float64):
        T = model.to_full
        nu, du = fields.n_u, fields.vertex_dofs_u
        vd = du.T.ravel()  # vertex-major: (n_vertices, dim) flattened
        self.n_points, self.dim = du.shape[1], du.shape[0]
        self.n_cells = fields.mesh.t.shape[1]
        self._has_t, self._nt_points = model.layout.n_t > 0, fields.vertex_dofs_t.size
        G, self.pairs = fields.strain, list(fields.pairs)
        Q = deviator_root(self.pairs, float(fields.mu))
        n_e = self.n_cells
        # ‖Q ε_e‖ for every element: rows (i n_e + e) of the k n_e × n_u operator Q ⊗ G
        QG = sp.vstack(
            [
                sum(
                    Q[i, c] * G[c * n_e : (c + 1) * n_e]
                    for c in range(len(self.pairs))
                    if Q[i, c] != 0.0
                )
                for i in range(Q.shape[0])
            ]
        ).tocsr()
        self._k = Q.shape[0]
        # blocks (name, rows of to_full or None for the stress, columns of X they need)
        blocks = [("displacement", vd), ("velocity", nu + vd)]
        if self._has_t:
            blocks.append(("temperature", 2 * nu + fields.vertex_dofs_t))
        self._sparse = sp.issparse(T)
        self._ops = []  # (names, sizes, columns of X or None, operator)
        if self._sparse:
            T = sp.csr_matrix(T)
            for name, rows in blocks:
                self._ops.append(((name,), (rows.size,), None, T[rows]))
            self._ops.append((("von_mises",), (QG.shape[0],), None, (QG @ T[:nu]).tocsr()))
        else:
            self._ops += _dense_ops(T, QG, blocks, nu, dtype)
        c = fields.contacts
        #: the vertices that carry a contact (sorted, unique); forces are zero elsewhere
        self.contact_vertices, which = np.unique(np.asarray(c.vertices), return_inverse=True)
        nc = c.vertices.size
        self._scatter = sp.csr_matrix(
            (np.ones(nc), (which.ravel(), np.arange(nc))), shape=(self.contact_vertices.size, nc)
        )
        self._normals = np.asarray(c.normals)  # (dim, n_contacts)
        self._contact = model.contact
        self.h = float(h)

    def compact(self, X, impulse, friction=None, times=None) -> dict[str, np.ndarray | None]:
        """Fields of ``B`` frames as computed: states ``X`` (B × N), impulses (B × n_c),
        friction impulses (B × n_c × 2, or ``None``); ``times`` (s) of the frames is not
        needed (a blade's fields are those of its state).

        Returns ``displacement`` and ``velocity`` (B × n_points × dim), ``temperature``
        (B × n_points, ``None`` without a thermal part), ``von_mises`` (B × n_cells) and
        ``contact_force``, ``friction_force`` (B × n_contact_vertices × dim, at
        :attr:`contact_vertices`; the latter ``None`` without friction).
        """
        X = np.atleast_2d(np.asarray(X, dtype=float))
        B, npt, d = X.shape[0], self.n_points, self.dim
        raw = {}
        for names, sizes, cols, M in self._ops:
            if cols is None:
                full = (M @ X.T).T
            else:
                full = X[:, cols].astype(M.dtype) @ M  # (B, rows)
            start = 0
            for name, n in zip(names, sizes):
                raw[name] = full[:, start : start + n]
                start += n
        return {
            "displacement": raw["displacement"].reshape(B, npt, d),
            "velocity": raw["velocity"].reshape(B, npt, d),
            "temperature": raw["temperature"] if self._has_t else None,
            "von_mises": self._norm(raw["von_mises"].reshape(B, self._k, self.n_cells)),
            "contact_force": self._forces(impulse, B),
            "friction_force": self._friction(friction, B),
        }

    def compute(self, X, impulse, friction=None) -> dict[str, np.ndarray]:
        """Fields of ``B`` frames (arguments as :meth:`compact`) on the whole mesh.

        Returns point data ``displacement``, ``velocity``, ``contact_force``,
        ``friction_force`` (B × n_points × 3), ``temperature`` (B × n_points) and cell data
        ``von_mises`` (B × n_cells).
        """
        c = self.compact(X, impulse, friction)
        B = c["von_mises"].shape[0]
        out = {k: np.zeros((B, self.n_points, 3)) for k in _VECTORS}
        out["temperature"] = np.zeros((B, self._nt_points))
        out["von_mises"] = c["von_mises"]
        for b in range(B):
            self.store(c, b, {k: v[b] for k, v in out.items()})
        return out

    def store(self, compact: dict, b: int, data: dict[str, np.ndarray]) -> None:
        """Write frame ``b`` of ``compact`` into the arrays ``data`` (by field name: vectors
        n_points × 3, temperature n_points, von_mises n_cells, e.g. the views of a
        :class:`~femrub.output.vtu_file.VTUWriter`). Entries no frame sets (the third
        component in 2D, the temperature of a model without one, the forces away from
        :attr:`contact_vertices`) are left as they are (zero in a fresh file buffer and
        in :meth:`compute`)."""
        d, cv = self.dim, self.contact_vertices
        for k in ("displacement", "velocity"):
            data[k][:, :d] = compact[k][b]
        if compact["temperature"] is not None:
            data["temperature"][:] = compact["temperature"][b]
        data["von_mises"][:] = compact["von_mises"][b]
        for k in ("contact_force", "friction_force"):
            if cv.size:
                data[k][cv, :d] = 0.0 if compact[k] is None else compact[k][b]

    @staticmethod
    def _norm(s: np.ndarray) -> np.ndarray:
        """``‖s[:, :, e]‖`` over the ``k`` deviator components (B × k × n_e -> B × n_e)."""
        acc = np.square(s[:, 0])
        for i in range(1, s.shape[1]):
            acc += np.square(s[:, i])
        return np.sqrt(acc, out=acc)

    def _forces(self, impulse, B: int) -> np.ndarray:
        """Normal contact force (N) at the contact vertices, ``-λ n / h`` summed per vertex."""
        lam = np.asarray(impulse, dtype=float).reshape(B, -1)
        if not lam.shape[1]:
            return np.zeros((B, 0, self.dim))
        per = -(lam[:, :, None] / self.h) * self._normals.T[None]  # (B, n_c, dim)
        return _scatter(self._scatter, per)

    def _friction(self, friction, B: int) -> np.ndarray | None:
        """Friction force (N) at the contact vertices, in global axes (``None``: none)."""
        c = self._contact
        if friction is None or c is None or c.frames is None or not np.size(friction):
            return None
        g = c.to_global(np.asarray(friction, dtype=float) / self.h)[..., : self.dim]
        return _scatter(self._scatter, g)


_VECTORS = ("displacement", "velocity", "contact_force", "friction_force")

#: columns of a dense map read at once while the operators are built (bounds the copies)
COLUMN_BLOCK = 32


def _dense_ops(T, QG, blocks, nu: int, dtype) -> list:
    """The operators of :class:`FrameFields` for a dense map ``T`` (an array or a
    :class:`~femrub.reduction.truncation.ColumnMap`), each the transposed rows of ``T`` a
    field needs restricted to the columns they use, built :data:`COLUMN_BLOCK` columns at
    a time (never a copy of ``T``): the displacement and stress ``[T[vd]; QG T[:nu]]``
    (one GEMM for both), then the velocity and temperature rows."""
    (_, vd), rest = blocks[0], blocks[1:]
    u = slice(0, nu)
    cu = _used(T, u)
    k_rows = QG.shape[0]
    U = np.empty((cu.size, vd.size + k_rows), dtype=dtype)
    for j in range(0, cu.size, COLUMN_BLOCK):
        c = cu[j : j + COLUMN_BLOCK]
        U[j : j + COLUMN_BLOCK, : vd.size] = _block(T, vd, c).T
        U[j : j + COLUMN_BLOCK, vd.size :] = np.asarray(QG @ _block(T, u, c)).T
    ops = [(("displacement", "von_mises"), (vd.size, k_rows), cu, U)]
    for name, rows in rest:
        c = _used(T, rows)
        block = np.ascontiguousarray(_block(T, rows, c).T, dtype=dtype)
        ops.append(((name,), (rows.size,), c, block))
    return ops


def _block(T, rows, cols) -> np.ndarray:
    """``T[rows][:, cols]`` (``rows`` a slice or indices) of a dense map, copying only that
    block (:meth:`~femrub.reduction.truncation.ColumnMap.__getitem__`)."""
    return columns_of(T, cols)[rows]


def _used(T, rows) -> np.ndarray:
    """The columns of ``T`` with a nonzero in ``rows``, read :data:`COLUMN_BLOCK` at a time."""
    n, out = T.shape[1], [np.zeros(0, dtype=np.intp)]
    for j in range(0, n, COLUMN_BLOCK):
        c = np.arange(j, min(j + COLUMN_BLOCK, n))
        out.append(c[np.any(_block(T, rows, c) != 0.0, axis=0)])
    return np.concatenate(out)


def _scatter(S: sp.csr_matrix, per: np.ndarray) -> np.ndarray:
    """Sum per-contact vectors ``per`` (B × n_c × k) onto their vertices (B × n_v × k)."""
    B, nc, k = per.shape
    out = S @ per.transpose(1, 0, 2).reshape(nc, B * k)
    return out.reshape(S.shape[0], B, k).transpose(1, 0, 2)
