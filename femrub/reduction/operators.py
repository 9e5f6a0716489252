"""The reduced operators of a Craig–Bampton reductor's bases (paper Eqs. 14–15).

Two ways to the same operators of a reduced model of the columns ``c`` of the bases:

* the projection over the full state, in two halves: :func:`left_projected` (``Ā = R̃_cᵀ A
  R_c``, ``B̄ = R̃_cᵀ B R_c``, the loads ``R̃_cᵀ F``, the contact rows, ``Contact.project``)
  and :func:`right_projected` (the observations ``O R_c``, the energy forms,
  :func:`~.energy_forms.reduced_energy`, and the map to the mesh ``to_full R_c``);
* :func:`sliced`: the same as blocks of the largest model's projected operators
  (:mod:`femrub.reduction.truncation`), with the full model's gap, heat and load functions;
  only the energy rates, which are not projections, are recomputed; the map to the mesh is
  the largest model's, restricted to the columns without a copy
  (:class:`~femrub.reduction.truncation.ColumnMap`).

Both return ``{"A", "B", "loads", "contact", "observations", "energy", "growth",
"to_full"}`` (``growth``: the largest energy growth rate of the reduced model,
:func:`~.energy_forms.reduced_energy`).
"""

from __future__ import annotations

import numpy as np

from ..fem.linalg import project
from ..model.first_order import LoadTerm
from .energy_forms import energy_rates, reduced_energy
from .truncation import columns_of, prolonged, sliced_contact, sliced_energy, sliced_loads

__all__ = ["left_projected", "right_projected", "sliced"]


def left_projected(fom, R, left) -> dict:
    """Operators of ``fom`` projected with the left basis ``left`` (``R̃``; ``R`` itself for a
    Galerkin projection) on the right basis ``R``: ``A``, ``B``, the loads, the contact; the
    rest is :func:`right_projected`'s (a caller that makes ``left`` for this call only has it
    released before the energy forms copy ``R``)."""
    L = fom.layout
    parts = [0, L.u.stop, L.v.stop, L.n]  # the u, v, θ rows of the bases
    return {
        "A": project(left, fom.A, R, parts=parts),
        "B": project(left, fom.B, R, parts=parts),
        "loads": [
            LoadTerm(left.T @ t.vector, t.signal, power=R.T @ t.power, heat=t.heat, name=t.name)
            for t in fom.loads
        ],
        "contact": None if fom.contact is None else fom.contact.project(left, R),
    }


def right_projected(fom, R, left_parts: dict, layout, n_boundary_u: int, to_full=None) -> dict:
    """What ``R`` alone projects, given :func:`left_projected`'s ``A`` and ``B``, of reduced
    ``layout``: the energy forms and growth rate, the observations, the map to the mesh
    (``to_full``: ``fom.to_full @ R`` when already at hand, e.g. the largest model's columns
    as a :class:`~femrub.reduction.truncation.ColumnMap`; else computed)."""
    energy, growth = None, 0.0
    if fom.energy is not None:
        Ar, Br = left_parts["A"], left_parts["B"]
        energy, growth = reduced_energy(fom, n_boundary_u, R, Ar, Br, layout)
    return {
        "observations": {k: np.asarray(O @ R) for k, O in fom.observations.items()},
        "energy": energy,
        "growth": growth,
        "to_full": to_full if to_full is not None or fom.to_full is None else _mapped(fom, R),
    }


def _mapped(fom, R):
    """``fom.to_full @ R``: ``R`` itself with the mesh's constrained rows put back
    (:func:`~femrub.reduction.truncation.prolonged`, no copy), else the dense product."""
    shared = prolonged(fom.to_full, R)
    return shared if shared is not None else np.asarray(fom.to_full @ R)


def left_sliced(largest: dict, fom, cols) -> dict:
    """:func:`left_projected` of the columns ``cols`` of both bases, as blocks of the
    ``largest`` model's (``R̃_cᵀ A R_c = (R̃ᵀ A R)[c, c]``, ...: no columns of the bases
    copied), with ``fom``'s gap, heat and load functions."""
    return {
        "A": largest["A"][np.ix_(cols, cols)],
        "B": largest["B"][np.ix_(cols, cols)],
        "loads": sliced_loads(largest["loads"], fom.loads, cols),
        "contact": sliced_contact(largest["contact"], fom.contact, cols),
    }


def sliced(largest: dict, fom, cols, layout, energy=None) -> dict:
    """The operators of the columns ``cols`` as blocks of the ``largest`` model's
    (projected on every column), with ``fom``'s gap, heat and load functions.

    ``energy``: the ``(forms, growth rate)`` of these columns already made on a model with
    the same matrices (they rest on ``Ā``, ``B̄`` and the projected forms only), or ``None``
    to make them (:func:`~femrub.reduction.energy_forms.energy_rates`)."""
    left = left_sliced(largest, fom, cols)
    A, B = left["A"], left["B"]
    every = cols.size == A.shape[0] == largest["A"].shape[0] and np.array_equal(
        cols, np.arange(cols.size)
    )
    to_full = largest["to_full"]
    if to_full is not None and not every:  # the map to the mesh of the largest model is
        to_full = columns_of(to_full, cols)  # shared, not copied (n × r: 0.6 GB on Rotor 37)
    if energy is None:
        energy = (None, 0.0)
        if largest["energy"] is not None:
            energy = energy_rates(fom, sliced_energy(largest["energy"], cols), A, B, layout)
    energy, growth = energy
    return {
        **left,
        "observations": {k: O[:, cols] for k, O in largest["observations"].items()},
        "energy": energy,
        "growth": growth,
        "to_full": to_full,
    }
