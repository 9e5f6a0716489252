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
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from ..model.first_order import LoadTerm

__all__ = ["CONTACT_ROWS", "sliced_contact", "sliced_energy", "sliced_loads"]

#: the fields of a :class:`~femrub.contact.gap.Contact` that a reduction projects
CONTACT_ROWS = ("G", "Gv", "Hm", "Ht", "Gvt", "Hmt")


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
