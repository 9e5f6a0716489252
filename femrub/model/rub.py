"""A blade (3D, or the paper's 1D bar) rubbing a rigid casing, as a first-order model.

The one path from a discretised blade to a :class:`~femrub.model.FirstOrderModel`
(paper Eqs. 8-9): the Eq. (2) blocks of :func:`femrub.fem.discretisation.assemble`, the
:class:`~femrub.contact.points.ContactPoints` (already restricted to those the casing can
reach), the casing gap swept at the rotation speed (:func:`~femrub.contact.casing.swept_gap`)
and the frictional heat coefficients (:mod:`femrub.contact.heat`) go through
:func:`~femrub.model.build.first_order_model`.

Contact ``i`` at point ``p_i``: normal ``n_i`` (radial), gap ``g_i(t) = g(Ω t + φ_i) −
n_i · u(p_i)``, heat ``α_i λ_i`` spread over its tributary part of the tip face. Observed
signals: ``tip_displacement``, ``tip_velocity`` and ``tip_temperature`` (means over the
contacts; the tip itself on the bar) and, with several contacts, ``contact_displacement`` and
``contact_temperature`` per contact.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import skfem as fem

from ..contact.casing import CasingProfile, Concentric, sliding_velocity, swept_gap
from ..contact.points import ContactPoints
from ..fem.discretisation import Discretisation
from ..fem.forms import lame_parameters
from ..fem.material import Material
from ..fem.strain import centroid_strain
from .build import ContactSpec, Load, contact_boundary, first_order_model
from .first_order import CasingSweep, FirstOrderModel, Parameters

__all__ = ["DEFAULT_CLEARANCE", "FieldMap", "rub_model", "solid_model", "tip_load"]

#: Casing clearance (m) of :func:`solid_model` when no casing is given.
DEFAULT_CLEARANCE = 1e-4


@dataclass(frozen=True)
class FieldMap:
    """What output needs to turn a state into fields on the mesh (VTK, plots): the mesh, the
    displacement and temperature dofs at its vertices, the strain at each element's centroid
    as an operator on the displacement dofs, the contacts and the Lamé parameters (Pa).

    It holds no finite-element basis (their values at every quadrature point are an
    assembly's, and the largest arrays of a 3D build): :meth:`of` takes what it needs from
    a :class:`~femrub.fem.discretisation.Discretisation` once.
    """

    mesh: object
    contacts: ContactPoints
    lam: float
    mu: float
    #: displacement dofs at the vertices, ``(dim, n_vertices)``; ``n_u``: displacement dofs
    vertex_dofs_u: np.ndarray
    #: temperature dofs at the vertices, ``(n_vertices,)``
    vertex_dofs_t: np.ndarray
    n_u: int
    #: ``(G u)[c n_e + e] = ε_ab`` at the centroid of element ``e``, ``c`` over ``pairs``
    strain: sp.csr_matrix
    pairs: tuple

    @classmethod
    def of(cls, disc: Discretisation, contacts: ContactPoints, lam: float, mu: float):
        """The map of ``disc``'s mesh (:func:`~femrub.fem.strain.centroid_strain`)."""
        G, pairs = centroid_strain(disc.dofs_u)
        return cls(
            disc.mesh,
            contacts,
            lam,
            mu,
            disc.dofs_u.nodal_dofs,
            disc.dofs_t.nodal_dofs[0],
            int(disc.dofs_u.N),
            G,
            tuple(pairs),
        )


def tip_load(disc: Discretisation, mats, force, signal) -> Load:
    """Total force ``force`` (N, a ``dim``-vector) spread as a uniform traction on the tip
    faces (the tip node of the bar), times ``signal(t)``."""
    facets = disc.facets_of("tip")
    if facets.size == 0:
        raise ValueError(f"the 'tip' node set of {disc.blade.source} covers no boundary face")
    fb = fem.FacetBasis(disc.mesh, disc.dofs_u.elem, mapping=disc.dofs_u.mapping, facets=facets)
    area = float(fem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).assemble(fb))
    traction = np.asarray(force, dtype=float).reshape(disc.dim) / area

    @fem.LinearForm
    def load(v, w):
        return sum(traction[i] * v[i] for i in range(disc.dim))

    return Load(load.assemble(fb)[mats.free_u], signal, "u", "tip_force")


def _observations(normal_rows, heat_rows) -> dict:
    nc = normal_rows.shape[0]
    mean = sp.csr_matrix(np.full((1, nc), 1.0 / nc))
    observe = {
        "tip_displacement": ("u", mean @ normal_rows),
        "tip_velocity": ("v", mean @ normal_rows),
        "tip_temperature": ("theta", mean @ heat_rows),
    }
    if nc > 1:
        observe["contact_displacement"] = ("u", normal_rows)
        observe["contact_temperature"] = ("theta", heat_rows)
    return observe


def _friction_spec(points: ContactPoints, mats, friction: float, velocity) -> dict:
    """Tangent rows, μ, casing surface ``velocity`` (n_c, 2) and frames of the contacts."""
    if not friction > 0.0:
        return {}
    if points.tangents is None:
        raise ValueError("Coulomb friction needs a 3D blade (the bar has no tangent plane)")
    return {
        "tangents": points.tangent_rows(mats),
        "friction": float(friction),
        "casing_velocity": velocity,
        "frames": points.frames(),
    }


def rub_model(  # noqa: PLR0913 (the parts of a rub model, all keyword-only but the FE ones)
    disc: Discretisation,
    mats,
    points: ContactPoints,
    material: Material,
    *,
    casing: CasingProfile,
    rotation_speed: float = 0.0,
    alpha=0.0,
    restitution: float = 0.0,
    offset=0.0,
    loads=(),
    thermal: str | bool = "auto",
    observe_at: ContactPoints | None = None,
    friction: float = 0.0,
    heat_law: str = "alpha",
    heat_partition: float = 1.0,
    wear=None,
    casing_heat=None,
    damping=None,
    length_scale: float = float("nan"),
    direction: float = 1.0,
    slip: float = 1.0,
) -> tuple[FirstOrderModel, FieldMap]:
    """First-order model of ``disc`` rubbing ``casing`` at ``points`` (module docstring).

    Parameters
    ----------
    mats : Eq. (2) blocks of ``disc``.
    alpha : heat coefficients ``α_i`` (m/s) of the contacts (:mod:`femrub.contact.heat`).
    offset : clearance added to each contact's gap (m).
    loads : :class:`~femrub.model.build.Load` terms (e.g. :func:`tip_load`).
    thermal : keep the temperature dofs: ``"auto"`` (when something heats the blade),
        ``True`` or ``False``.
    observe_at : points whose signals are observed (default ``points``; with no contact in
        reach, the candidate points still show the tip's response).
    friction : Coulomb μ. With μ > 0 on a 3D blade each contact gets the axial and
        circumferential tangents of ``points``, and the casing surface slides past it at
        ``−σ Ω r_i`` along the circumferential one (the blade frame turns at σ Ω).
    heat_law : ``"alpha"`` (heat ``α_i λ_i``) or ``"power"`` (heat ``η`` × friction power,
        ``η = heat_partition``).
    wear : :class:`~femrub.contact.abradable.Abradable` coating over ``points``, or None.
    casing_heat : :class:`~femrub.contact.casing_heat.CasingHeat` of the casing, or None.
    damping : ``(mats, boundary) -> mats`` with their damping ``C^uu`` set, called once the
        contacts' displacement boundary (:func:`~femrub.model.build.contact_boundary`) is
        known and before the model is built (the pipeline's modal damping, which takes the
        frequencies through the reduction's interior factorisation), or None.
    length_scale : the blade's characteristic size (m; the model's ``length_scale``).
    direction : σ, +1 counterclockwise or −1 clockwise about the machine axis: the casing
        phase ``σ Ω t + φ_i`` and the sliding velocity (:mod:`femrub.contact.casing`).
    slip : +1, or −1 for the casing sliding reversed against the phase
        (``contact.slip_direction = "reversed"``, a verification device).
    """
    N, Q = points.normal_rows(mats), points.heat_rows(mats)
    if observe_at is None or observe_at is points:
        observe = _observations(N, Q)
    else:
        observe = _observations(observe_at.normal_rows(mats), observe_at.heat_rows(mats))
    gap, gap_rate = swept_gap(casing, points.angles, rotation_speed, offset, direction)
    velocity = sliding_velocity(points.radii, rotation_speed, direction, slip)
    spec = (
        None
        if points.n == 0
        else ContactSpec(
            normals=N,
            gap=gap,
            gap_rate=gap_rate,
            heat_dofs=Q.toarray(),
            restitution=restitution,
            heat_coefficient=np.broadcast_to(np.asarray(alpha, dtype=float), (points.n,)).copy(),
            names=list(points.names),
            heat_law=heat_law,
            heat_partition=heat_partition,
            **_friction_spec(points, mats, friction, velocity),
            wear=wear,
            casing_heat=casing_heat,
            patches=None if points.patch is None else points.mean_rows(mats),
        )
    )
    if damping is not None:
        mats = damping(mats, contact_boundary(spec, mats.n_u))
    info = dict(
        blade=disc.blade.source,
        order=disc.order,
        n_contacts=points.n,
        fe_dofs=mats.n_u + mats.n_t,
        casing=casing.as_dict(),
        rotation_speed=float(rotation_speed),
        rotation_direction=float(direction),
        slip_direction=float(slip),
        rayleigh=mats.info.get("rayleigh", (0.0, 0.0)),
    )
    offsets = np.broadcast_to(np.asarray(offset, dtype=float), (points.n,)).copy()
    sweep = CasingSweep(
        casing,
        points.angles,
        offsets,
        points.radii,
        mats.info.get("prestress_speed"),
        float(direction),
        float(slip),
    )
    model = first_order_model(
        mats,
        contact=spec,
        loads=loads,
        observe=observe,
        thermal=thermal,
        info=info,
        length_scale=length_scale,
        parameters=Parameters(rotation_speed=rotation_speed),
        sweep=sweep,
    )
    lam, mu = lame_parameters(material.young, material.poisson, disc.dim)
    return model, FieldMap.of(disc, points, lam, mu)


def solid_model(  # noqa: PLR0913 (the Python preset: keyword-only options, one per scene key)
    blade,
    material: Material,
    *,
    casing: CasingProfile | None = None,
    rotation_speed: float = 0.0,
    friction: float = 0.0,
    heat_law: str = "power",
    heat_partition: float = 1.0,
    restitution: float = 0.0,
    order: int = 2,
    coupling: str = "physical",
    strain_heating: bool = False,
    rayleigh: tuple[float, float] = (0.0, 0.0),
    damping_ratio: float | None = None,
    lumping: str = "auto",
    conduction: str = "galerkin",
    tip_force=None,
    thermal: str | bool = "auto",
    reach: float | str = "auto",
    gap_reference: str = "per-node",
    spread: str = "patch",
    centrifugal: str | None = None,
    rotation_direction: str = "auto",
    slip_direction: str = "rotation",
) -> tuple[FirstOrderModel, FieldMap]:
    """A blade rubbing a casing in one call: the scene's builder with Python arguments.

    The same model as a scene with the same values (:func:`~femrub.model.builder.build_rub`):
    vector P2 displacement (``order=2``, HRZ-lumped mass) and P1 temperature, root clamped
    and held at ambient, Coulomb friction ``friction`` μ on every contact (the casing slides
    past at ``Ω r``), frictional heat ``heat_partition`` η × friction power (``heat_law=
    "power"``; ``"alpha"`` with α = 0 turns it off), casing default: concentric with
    :data:`DEFAULT_CLEARANCE`. Only the contacts the casing can reach are kept, as in a
    scene (``reach="auto"``, :mod:`femrub.contact.reach`); ``reach="all"`` keeps every
    candidate, a length (m) sets the reach; ``gap_reference="outermost"``: the clearance
    is the outermost contact's. ``damping_ratio`` ζ gives Rayleigh damping
    with ratio ζ at the first and fifth clamped modes; ``tip_force``: ``(force vector N,
    signal)`` (a harmonic :class:`~femrub.model.config.ForceLaw` also gives the reach filter
    its frequency, as a scene's ``sin`` law); ``centrifugal``: prestress method at Ω
    (``"linear"``, ``"nonlinear"``; default ``None``: none, unlike a scene's
    ``loads.centrifugal = "auto"``); ``conduction``: ``"galerkin"`` or ``"monotone"`` (the
    scene's ``physics.conduction``); ``rotation_direction``, ``slip_direction``: as the
    scene's ``loads.rotation_direction`` and ``contact.slip_direction``. Returns
    ``(model, fields)``.
    """
    from .builder import build_rub  # the builder composes this module's rub_model
    from .config import ContactConfig, ForceConfig, ForceLaw, RubConfig

    force = None
    if tip_force is not None:
        vector, signal = tip_force
        vector = np.asarray(vector, dtype=float)
        amplitude = float(np.linalg.norm(vector))
        harmonic = isinstance(signal, ForceLaw) and signal.law == "sin"
        force = ForceConfig(
            amplitude,
            signal,
            frequency=signal.omega if harmonic else None,
            direction=tuple(vector / (amplitude or 1.0)),
        )
    config = RubConfig(
        material,
        ContactConfig(
            casing=casing or Concentric(DEFAULT_CLEARANCE),
            friction=friction,
            heat_law=heat_law,
            heat_partition=heat_partition,
            restitution=restitution,
            spread=spread,
            reach=reach,
            gap_reference=gap_reference,
            slip_direction=slip_direction,
        ),
        rotation_speed=float(rotation_speed),
        rotation_direction=rotation_direction,
        order=order,
        lumping=lumping,
        conduction=conduction,
        coupling=coupling,
        strain_heating=strain_heating,
        rayleigh=tuple(rayleigh),
        damping_ratio=damping_ratio or 0.0,
        thermal=thermal,
        centrifugal=centrifugal,
        tip_force=force,
    )
    built = build_rub(blade, config)
    return built.model, built.fields
