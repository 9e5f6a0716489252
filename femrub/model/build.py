"""Build the paper's first-order model (Eqs. 8–9) from thermoelastic matrices::

        [I  0   0  ]        [ 0      I      0    ]
    A = [0  M   0  ],   B = [−K^uu  −C^uu  −K^uθ ],   X = [u, v, θ]
        [0  0  C^θθ]        [ 0     −C^θu  −K^θθ ]

Contact ``i`` has a normal row ``n_i`` on the displacement dofs (``u_n = n_i · u``, towards
the casing) and a temperature dof receiving the frictional heat ``α_i λ_i``. Loads are
``f^u s(t)`` and ``f^θ s(t)`` terms. With ``thermal="auto"`` the temperature dofs are kept
only when something thermal is asked for (coupling, heat input or a heat load); otherwise
they are dropped and ``info["dropped"]`` says why.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..contact.patches import patch_masters
from ..fem.assembly import ThermoelasticMatrices
from .first_order import Contact, EnergyForms, FirstOrderModel, Layout, LoadTerm

__all__ = ["ContactSpec", "Load", "contact_boundary", "first_order_model"]


@dataclass
class ContactSpec:
    """Contacts on the free dofs of a :class:`ThermoelasticMatrices`.

    Parameters
    ----------
    normals : (n_c, n_u) array or sparse: row i gives the normal displacement of contact i,
        positive towards the casing (closing the gap).
    heat_dofs : (n_c,) free temperature dof receiving the frictional heat of contact i, or a
        (n_c, n_θ) array distributing it.
    gap : initial gap(s) (m), array or callable ``t -> (n_c,)``.
    restitution : Newton's coefficient e in [0, 1].
    heat_coefficient : α (m/s) in ``f_tip = α λ``; scalar, (n_c,) or callable of t.
    gap_rate : ``dg/dt`` of a moving obstacle, callable ``t -> (n_c,)`` (m/s), or None.
    tangents : (2 n_c, n_u) rows giving the displacement of contact i along its two tangents
        (rows ``2 i``, ``2 i + 1``), or None (no tangential force).
    friction : Coulomb μ per contact; casing_velocity : (n_c, 2) velocity of the casing
        surface along the tangents (m/s); frames : (n_c, 3, dim) normal and tangents in
        global axes; heat_law ``"alpha"`` or ``"power"``; heat_partition η.
    wear : :class:`~femrub.contact.abradable.Abradable` coating on the obstacle, or None;
        casing_heat : :class:`~femrub.contact.casing_heat.CasingHeat`, or None.
    patches : (dim n_c, n_u) rows of the patch mean displacements the normal and tangent
        rows are made of (:mod:`femrub.contact.patches`), or None (contacts on nodes). The
        model's ``boundary`` then holds them as ``"u_rows"``, with one master dof per row as
        ``"u"`` (:mod:`femrub.reduction.boundary_coordinates`).
    """

    normals: object
    gap: object
    heat_dofs: object = None
    restitution: float = 0.0
    heat_coefficient: object = 0.0
    names: list | None = None
    gap_rate: object = None
    tangents: object = None
    friction: object = 0.0
    casing_velocity: object = None
    frames: object = None
    heat_law: str = "alpha"
    heat_partition: object = 1.0
    wear: object = None
    casing_heat: object = None
    patches: object = None


@dataclass
class Load:
    """A load ``vector × signal(t)`` on the displacement (``field="u"``) or temperature dofs.

    One term ``f_j s_j(t)`` of ``f^u`` or ``f^θ`` in Eq. (2), placed into ``F`` of Eq. (8) by
    :func:`first_order_model`.

    Attributes
    ----------
    vector : (n_u,) or (n_θ,) array
        Nodal forces (N) on the free displacement dofs, or nodal heat flows (W) on the free
        temperature dofs, for a signal of 1.
    signal : callable
        ``s(t)`` (dimensionless, t in s).
    field : {"u", "t"}
        The dofs the load acts on.
    name : str
        The load's name in the energy balance.
    """

    vector: np.ndarray
    signal: object
    field: str = "u"
    name: str = "load"


def _rows(a, n_cols):
    a = sp.csr_matrix(a, copy=True) if sp.issparse(a) else sp.csr_matrix(np.atleast_2d(a))
    a.eliminate_zeros()  # a zero normal component is no boundary dof
    if a.shape[1] != n_cols:
        raise ValueError(f"contact normals must have {n_cols} columns, got {a.shape[1]}")
    return a


def contact_boundary(contact: ContactSpec | None, n_u: int) -> dict:
    """The displacement boundary of a model with ``contact`` (the model's ``boundary``
    without ``"theta"``): ``{"u": dofs the normal and tangent rows act on}``, or with
    patches ``{"u": one master dof per row, "u_rows": the patch rows}``."""
    if contact is None:
        return {"u": np.zeros(0, dtype=int)}
    if contact.patches is not None:  # boundary coordinates: the patch means
        P = _rows(contact.patches, n_u)
        return {"u": patch_masters(P), "u_rows": P}
    u = np.unique(_rows(contact.normals, n_u).indices).astype(int)
    if contact.tangents is not None:
        u = np.union1d(u, _rows(contact.tangents, n_u).indices).astype(int)
    return {"u": u}


def _has_heat(contact: ContactSpec | None) -> bool:
    """Whether ``contact`` heats the blade (a heat coefficient, or friction power)."""
    if contact is None:
        return False
    if callable(contact.heat_coefficient) or np.any(np.asarray(contact.heat_coefficient) > 0):
        return True
    return bool(
        contact.heat_law == "power"
        and np.any(np.asarray(contact.friction) > 0)
        and np.any(np.asarray(contact.heat_partition) > 0)
    )


def _keep_thermal(mats, contact, loads, thermal) -> tuple[bool, list]:
    """Keep the temperature dofs? ``(keep, dropped notes)`` (``thermal``: module docstring)."""
    has_coupling = mats.Kut.count_nonzero() > 0 or mats.Ctu.count_nonzero() > 0
    wanted = bool(has_coupling or _has_heat(contact) or any(ld.field == "theta" for ld in loads))
    if thermal == "auto":
        note = "temperature dofs: no thermal coupling, heat input or heat load"
        return wanted, [] if wanted else [note]
    keep = bool(thermal)
    dropped = not keep and wanted
    return keep, ["temperature dofs dropped on request: coupling and heat ignored"] * dropped


def _zeros(r: int, c: int) -> sp.csr_matrix:
    return sp.csr_matrix((r, c))


def _operators(mats, L: Layout) -> tuple[sp.spmatrix, sp.spmatrix]:
    """``A`` and ``B`` of Eq. (9) on the layout ``L``."""
    nu, nt, Z = L.n_u, L.n_t, _zeros
    I_u = sp.identity(nu, format="csr")
    A = sp.block_diag([I_u, mats.M] + ([mats.Ctt] if nt else []), format="csc")
    if not nt:
        return A, sp.bmat([[Z(nu, nu), I_u], [-mats.K, -mats.C]], format="csc")
    B = sp.bmat(
        [
            [Z(nu, nu), I_u, Z(nu, nt)],
            [-mats.K, -mats.C, -mats.Kut],
            [Z(nt, nu), -mats.Ctu, -mats.Ktt],
        ],
        format="csc",
    )
    return A, B


def _embed(L: Layout, block: str, vec) -> np.ndarray:
    out = np.zeros(L.n)
    out[getattr(L, block)] = np.asarray(vec, dtype=float).ravel()
    return out


def _load_terms(loads, L: Layout) -> list[LoadTerm]:
    """The state-space :class:`LoadTerm` of each :class:`Load` (heat loads only with θ)."""
    terms = []
    for ld in loads:
        if ld.field not in ("u", "theta"):
            raise ValueError(f"load field must be 'u' or 'theta', got {ld.field!r}")
        if ld.field == "u":
            vec = _embed(L, "v", ld.vector)
            terms.append(LoadTerm(vec, ld.signal, power=vec.copy(), heat=0.0, name=ld.name))
        elif L.n_t:
            vec = _embed(L, "t", ld.vector)
            heat = float(np.sum(ld.vector))
            terms.append(LoadTerm(vec, ld.signal, power=np.zeros(L.n), heat=heat, name=ld.name))
    return terms


def _heat_columns(contact: ContactSpec, L: Layout, nc: int) -> np.ndarray:
    """``Ht`` (N, n_c): where each contact's heat enters (zero without temperature dofs)."""
    Ht = np.zeros((L.n, nc))
    if not L.n_t or contact.heat_dofs is None:
        return Ht
    hd = np.asarray(contact.heat_dofs)
    if hd.ndim == 1:
        Ht[L.t.start + hd.astype(int), np.arange(nc)] = 1.0
    else:
        Ht[L.t] = hd.T
    return Ht


def _contact(contact: ContactSpec, L: Layout) -> tuple[Contact, dict]:
    """The :class:`Contact` in gap form on the state of layout ``L`` and its boundary."""
    nu, n = L.n_u, L.n
    N = _rows(contact.normals, nu)
    nc = N.shape[0]
    G = np.zeros((n, nc))
    G[L.u] = -N.T.toarray()
    Gv = np.zeros((n, nc))
    Gv[L.v] = -N.T.toarray()
    Gvt = None
    if contact.tangents is not None:
        T = _rows(contact.tangents, nu)
        Gvt = np.zeros((n, T.shape[0]))
        Gvt[L.v] = T.T.toarray()
    Ht = _heat_columns(contact, L, nc)
    boundary = {"u": np.zeros(0, dtype=int), "theta": np.zeros(0, dtype=int)}
    boundary.update(contact_boundary(contact, nu))
    boundary["theta"] = np.flatnonzero(np.any(Ht[L.t] != 0.0, axis=1))
    con = Contact(
        G=G,
        Gv=Gv,
        Hm=Gv.copy(),
        Ht=Ht,
        gap0=contact.gap,
        restitution=contact.restitution,
        heat_coefficient=contact.heat_coefficient if L.n_t else 0.0,
        names=list(contact.names or []),
        gap_rate=contact.gap_rate,
        Gvt=Gvt,
        friction=contact.friction,
        casing_velocity=contact.casing_velocity,
        frames=contact.frames,
        heat_law=contact.heat_law,
        heat_partition=contact.heat_partition,
        wear=contact.wear,
        casing_heat=contact.casing_heat,
    )
    return con, boundary


def _observations(observe: dict | None, L: Layout) -> dict:
    """``observe`` (name -> (field, rows)) as rows on the whole state."""
    out = {}
    sizes = {"u": L.n_u, "v": L.n_v, "theta": L.n_t}
    blocks = {"u": L.u, "v": L.v, "theta": L.t}
    for name, (fld, rows) in (observe or {}).items():
        size, blk = sizes[fld], blocks[fld]
        if size == 0:
            continue
        r = rows if sp.issparse(rows) else np.asarray(rows)
        if not sp.issparse(r) and r.ndim == 1:
            r = sp.csr_matrix((np.ones(r.size), (np.arange(r.size), r)), shape=(r.size, size))
        r = sp.csr_matrix(r)
        k = r.shape[0]
        out[name] = sp.hstack([_zeros(k, blk.start), r, _zeros(k, L.n - blk.stop)], format="csr")
    return out


def _energy_forms(mats, L: Layout) -> EnergyForms:
    """Kinetic, elastic, damping and thermal-stress forms, heat content and outflow."""
    nu, nt, n, Z = L.n_u, L.n_t, L.n, _zeros
    theta = [Z(nt, nt)] if nt else []
    Qk = sp.block_diag([Z(nu, nu), mats.M] + theta, format="csr")
    Qe = sp.block_diag([mats.K, Z(nu, nu)] + theta, format="csr")
    Pd = sp.block_diag([Z(nu, nu), -mats.C] + theta, format="csr")
    Pth = Z(n, n)
    heat_content = np.zeros(n)
    heat_outflow = np.zeros(n)
    if nt:
        Pth = sp.bmat(
            [
                [Z(nu, nu), Z(nu, nu), Z(nu, nt)],
                [Z(nu, nu), Z(nu, nu), -mats.Kut],
                [None, None, Z(nt, nt)],
            ],
            format="csr",
        )
        ones = np.ones(nt)
        heat_content[L.t] = mats.Ctt.T @ ones
        heat_outflow[L.v] = mats.Ctu.T @ ones
        heat_outflow[L.t] = mats.Ktt.T @ ones
    return EnergyForms(Qk, Qe, Pth, Pd, heat_content, heat_outflow)


def first_order_model(
    mats: ThermoelasticMatrices,
    *,
    contact: ContactSpec | None = None,
    loads=(),
    observe: dict | None = None,
    thermal: str | bool = "auto",
    x0=None,
    info: dict | None = None,
    **fields,
) -> FirstOrderModel:
    """Assemble ``A``, ``B`` of Eq. (9) and the contact, load and energy data.

    ``observe`` maps a signal name to ``(field, rows)`` with ``field`` in {"u", "v", "theta"}
    and ``rows`` a (k, n_field) array/sparse matrix or an index array of free dofs.
    ``info``: entries added to the model's ``info``; ``fields``: other fields of the
    :class:`FirstOrderModel` (``length_scale``, ``parameters``, ``sweep``).
    """
    keep, dropped = _keep_thermal(mats, contact, loads, thermal)
    nt = mats.n_t if keep else 0
    L = Layout(mats.n_u, mats.n_u, nt)
    A, B = _operators(mats, L)
    con, boundary = None, {"u": np.zeros(0, dtype=int), "theta": np.zeros(0, dtype=int)}
    if contact is not None:
        con, boundary = _contact(contact, L)
    Pu = mats.prolongation_u()
    to_full = sp.block_diag([Pu, Pu] + ([mats.prolongation_t()] if nt else []), format="csr")
    return FirstOrderModel(
        A=A,
        B=B,
        layout=L,
        loads=_load_terms(loads, L),
        contact=con,
        observations=_observations(observe, L),
        energy=_energy_forms(mats, L),
        blocks=mats if nt else mats.mechanical(),
        boundary=boundary,
        to_full=to_full,
        x0=x0,
        info={
            "n_u": mats.n_u,
            "n_theta": nt,
            "thermal": bool(nt),
            "coupling": mats.info.get("coupling"),
            "dropped": dropped,
            **(info or {}),
        },
        **fields,
    )
