"""Reduced models of smaller sizes as blocks of the largest projected one.

A reductor's bases of sizes ``(n_uv, n_θ)`` are the leading columns ``c`` of each block of
its largest bases ``R``, ``R̃`` (:class:`~femrub.reduction.craig_bampton.ThermoelasticCraigBampton`).
Every operator of a reduced model that is a projection is then a block of the largest
model's::

    R̃_cᵀ A R_c = (R̃ᵀ A R)[c, c],   R_cᵀ G = (Rᵀ G)[c],   O R_c = (O R)[:, c],   ...

(the same numbers up to the order of the floating-point sums), so a smaller model costs
slicing instead of a projection over the full state. The few quantities that are not
projections (the energy rates built from ``Ā⁻¹ B̄``, the least-squares initial state) are
recomputed on the small matrices by the reductor. The elastic-energy form is a block only
when the reduced kinematics integrates ``R`` itself (no displacement part in the boundary
velocity shapes, e.g. the ``"second-order"`` and ``"galerkin"`` projections, or an undamped
model); otherwise its basis depends on the number of modes and the reductor projects.

The map to the mesh of the largest model, ``to_full R``, is ``R`` itself with the mesh's
constrained rows put back (the full model's ``to_full`` is a prolongation:
:func:`prolonged`), and a smaller model's, ``to_full R_c``, the columns ``c`` of that
(:class:`ColumnMap`): a product with it pads the operand with zeros on the other columns
and places the rows instead of copying the basis (on Rotor 37 it is 194,276 × 369 dense,
0.6 GB, and a sweep point's error estimate steps several sizes).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from ..model.first_order import LoadTerm

__all__ = [
    "CONTACT_ROWS",
    "ColumnMap",
    "columns_of",
    "prolonged",
    "sliced_contact",
    "sliced_energy",
    "sliced_loads",
]

#: the fields of a :class:`~femrub.contact.gap.Contact` that a reduction projects
CONTACT_ROWS = ("G", "Gv", "Hm", "Ht", "Gvt", "Hmt")


class ColumnMap:
    """The columns ``cols`` of a dense (n, r) array ``full``, without copying them, with its
    rows placed by ``rows`` when given (a prolongation: row ``i`` is ``full[rows[i]]``, or
    zero where ``rows[i] < 0``).

    A reduced model's ``to_full``: the largest model's map to the mesh is its basis ``R``
    with the mesh's constrained rows put back (:func:`prolonged`: the full model's
    ``to_full`` is a prolongation), and a smaller size's the leading columns ``cols`` of that
    (module docstring). ``M @ X`` is ``full @ X̂`` with ``X̂`` the rows of ``X`` placed at
    ``cols`` and zeros elsewhere, ``Y @ M`` is ``(Y @ full)[:, cols]``, rows ``M[rows]`` are
    ``full[rows][:, cols]`` (through ``rows``); ``np.asarray(M)`` (or any other indexing)
    makes the copy.

    Parameters
    ----------
    full : (n, r) dense array (the largest model's basis or map, shared).
    cols : (c,) distinct column indices of ``full``.
    rows : (m,) row of ``full`` of each row of the map (``-1``: a zero row), or ``None``:
        the rows of ``full``.
    """

    __array_priority__ = 20.0  # ``Y @ M`` of an ndarray ``Y`` comes to :meth:`__rmatmul__`
    ndim = 2

    def __init__(self, full, cols, rows=None):
        self.full = np.asarray(full)
        self.cols = np.asarray(cols, dtype=np.intp)
        if self.full.ndim != 2 or self.cols.ndim != 1:
            raise ValueError("ColumnMap needs a 2D array and a 1D array of columns")
        if np.unique(self.cols).size != self.cols.size:
            raise ValueError("ColumnMap: the columns must be distinct")
        self.rows = None if rows is None else np.asarray(rows, dtype=np.intp)
        n = self.full.shape[0] if self.rows is None else self.rows.size
        self.shape = (n, self.cols.size)

    def columns(self, cols) -> ColumnMap:
        """The map of the columns ``cols`` of this one (shared, not copied)."""
        return ColumnMap(self.full, self.cols[np.asarray(cols, dtype=np.intp)], self.rows)

    @property
    def dtype(self):
        return self.full.dtype

    def __repr__(self) -> str:
        return f"ColumnMap({self.shape[0]} x {self.shape[1]} of {self.full.shape[1]} columns)"

    def __array__(self, dtype=None, copy=None):
        out = self._placed(np.take(self.full, self.cols, axis=1))
        return out if dtype is None else out.astype(dtype, copy=False)

    def toarray(self) -> np.ndarray:
        """The columns as a dense array (a copy)."""
        return self.__array__()

    def _placed(self, Y: np.ndarray) -> np.ndarray:
        """``Y`` (rows of ``full``'s space) on the map's rows (zero where ``rows < 0``)."""
        if self.rows is None:
            return Y
        out = np.zeros((self.rows.size,) + Y.shape[1:], dtype=Y.dtype)
        has = self.rows >= 0
        out[has] = Y[self.rows[has]]
        return out

    def _padded(self, X) -> np.ndarray:
        X = np.asarray(X)
        if X.shape[:1] != (self.cols.size,):
            raise ValueError(f"ColumnMap of shape {self.shape}: cannot multiply {X.shape}")
        out = np.zeros((self.full.shape[1],) + X.shape[1:], dtype=np.result_type(X, self.full))
        out[self.cols] = X
        return out

    def __matmul__(self, X) -> np.ndarray:
        if sp.issparse(X):
            X = X.toarray()
        return self._placed(self.full @ self._padded(X))

    def __rmatmul__(self, Y) -> np.ndarray:
        if self.rows is not None:  # Y's columns onto the rows of ``full``
            has = np.flatnonzero(self.rows >= 0)
            S = sp.csr_matrix(
                (np.ones(has.size), (has, self.rows[has])), shape=(self.rows.size, len(self.full))
            )
            Y = Y @ S
        return np.asarray(Y @ self.full)[..., self.cols]

    def __getitem__(self, key):
        if isinstance(key, tuple):  # rows and columns: from the dense copy
            return np.asarray(self)[key]
        if self.rows is None:  # a block of rows: only its columns copied
            if isinstance(key, slice) or np.ndim(key) == 0:
                return self.full[key][..., self.cols]
            return self.full[np.ix_(np.asarray(key), self.cols)]
        src = np.atleast_1d(self.rows[key])
        out = np.zeros((src.size, self.cols.size), dtype=self.full.dtype)
        has = src >= 0
        out[has] = self.full[np.ix_(src[has], self.cols)]
        return out if np.ndim(self.rows[key]) else out[0]


def prolonged(P, R) -> ColumnMap | None:
    """``P R`` as a :class:`ColumnMap` of ``R`` (no copy) when ``P`` is a prolongation (at most
    one 1 in each row, in distinct columns: the full model's ``to_full``), else ``None``."""
    if not sp.issparse(P):
        return None
    P = sp.csr_matrix(P)
    per_row = np.diff(P.indptr)
    if per_row.max(initial=0) > 1 or not np.all(P.data == 1.0):
        return None
    rows = np.full(P.shape[0], -1, dtype=np.intp)
    rows[per_row == 1] = P.indices
    if np.unique(P.indices).size != P.indices.size or P.shape[1] != len(R):
        return None
    return ColumnMap(R, np.arange(np.shape(R)[1]), rows)


def columns_of(M, cols) -> ColumnMap:
    """The columns ``cols`` of a dense map or of a :class:`ColumnMap` (shared, not copied)."""
    return M.columns(cols) if isinstance(M, ColumnMap) else ColumnMap(M, cols)


def _block(Q, cols: np.ndarray):
    """``Q[c, c]`` of a dense or sparse square form, as CSR (``None`` stays ``None``)."""
    if Q is None:
        return None
    Q = Q.toarray() if sp.issparse(Q) else np.asarray(Q)
    return sp.csr_matrix(Q[np.ix_(cols, cols)])


def sliced_contact(largest, contact, cols: np.ndarray):
    """``contact`` (the full model's: gap, heat and wear functions) with the projected rows
    of the ``largest`` reduced contact restricted to the columns ``cols``."""
    if contact is None:
        return None
    rows = {k: getattr(largest, k)[cols] for k in CONTACT_ROWS if getattr(largest, k) is not None}
    return dataclasses.replace(contact, **rows)


def sliced_loads(largest: list, loads: list, cols: np.ndarray) -> list:
    """The full model's ``loads`` (their signals) with the largest reduced vectors sliced."""
    return [
        LoadTerm(r.vector[cols], t.signal, power=r.power[cols], heat=t.heat, name=t.name)
        for r, t in zip(largest, loads, strict=True)
    ]


def sliced_energy(forms, cols: np.ndarray):
    """The projected energy forms of the largest model restricted to ``cols`` (before the
    reductor recomputes the rates that are not projections)."""
    return dataclasses.replace(
        forms,
        Qk=_block(forms.Qk, cols),
        Qe=_block(forms.Qe, cols),
        Pth=_block(forms.Pth, cols),
        Pd=_block(forms.Pd, cols),
        Wth=_block(forms.Wth, cols),
        heat_content=np.asarray(forms.heat_content)[cols],
        heat_outflow=np.asarray(forms.heat_outflow)[cols],
    )
