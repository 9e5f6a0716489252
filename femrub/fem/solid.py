"""3D blade rubbing a rigid casing: the first-order model of a :class:`BladeMesh`.

Same forms and first-order builder as the 1D bar (:mod:`femrub.fem.assembly`,
:mod:`femrub.model.build`), with vector P2 displacement (P1 tetrahedra lock in bending) and
P1 temperature on the linear tetrahedra of the mesh, HRZ-lumped mass (row-sum lumping of P2
goes negative), isotropic thermal-stress coupling, root face clamped and held at ambient.

Contact ``i`` at point ``p_i`` of the tip: the normal is the casing radial direction ``n_i``
(away from the machine axis), the gap ``g_i(t) = g(Ω t + φ_i) − n_i · u(p_i)`` follows the
casing profile ``g`` (:mod:`femrub.contact.casing`) swept at the rotation speed ``Ω`` from the node's
angular position ``φ_i``, and the frictional heat ``α_i λ_i`` with ``α_i = μ Ω r_i`` (Coulomb
friction ``μ``, sliding speed ``Ω r_i``) enters as a uniform flux over the part of the tip
face nearest to ``p_i`` (its tributary area), not into one vertex.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import skfem as fem
from scipy.spatial import cKDTree

from ..contact.casing import CasingProfile, Concentric
from ..model.build import ContactSpec, Load, first_order_model
from ..model.first_order import FirstOrderModel
from .assembly import assemble_thermoelastic
from .forms import lame_parameters
from .material import Material, check_finite_positive

__all__ = ["FieldMap", "ContactNodes", "locate_contacts", "solid_matrices", "solid_model"]


@dataclass
class ContactNodes:
    """Contact points of a blade and their dofs (full numbering of the bases)."""

    points: np.ndarray  # (3, n_c) m
    normals: np.ndarray  # (3, n_c) outward radial unit vectors
    radii: np.ndarray  # (n_c,) m
    angles: np.ndarray  # (n_c,) rad, around the machine axis
    u_dofs: np.ndarray  # (3, n_c) displacement dofs (x, y, z components)
    heat: sp.csr_matrix  # (n_c, n_t_all) weights on the temperature dofs (rows sum to 1)


@dataclass
class FieldMap:
    """What output needs to turn a state into fields on the mesh (VTK, plots)."""

    mesh: fem.MeshTet1
    basis_u: fem.Basis
    basis_t: fem.Basis
    contacts: ContactNodes
    lam: float
    mu: float
    b: float
    info: dict = field(default_factory=dict)

    def vertex_displacement_dofs(self) -> np.ndarray:
        """(3, n_vertices) displacement dofs at the mesh vertices."""
        return self.basis_u.nodal_dofs


def _axis_frame(axis):
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    e1 = np.eye(3)[np.argmin(np.abs(a))]
    e1 = e1 - (e1 @ a) * a
    e1 /= np.linalg.norm(e1)
    return a, e1, np.cross(a, e1)


def _component_of(basis: fem.Basis) -> np.ndarray:
    """Component (0, 1, 2) of every dof of a vector P1/P2 basis (rows interleave components)."""
    comp = np.full(basis.N, -1)
    for name in ("nodal_dofs", "edge_dofs", "facet_dofs", "interior_dofs"):
        d = getattr(basis, name, None)
        if d is not None and d.size:
            comp[d] = (np.arange(d.shape[0]) % 3)[:, None]
    return comp


def locate_contacts(blade, basis_u: fem.Basis, basis_t: fem.Basis) -> ContactNodes:
    """Displacement dofs, normals and heat weights of the blade's contact points."""
    pts = np.asarray(blade.contact_points, dtype=float).reshape(3, -1)
    if pts.shape[1] == 0:
        raise ValueError(f"blade mesh from {blade.source} has no contact points; give some")
    mesh = blade.mesh
    scale = float(np.ptp(mesh.p, axis=1).max())
    tol = 1e-6 * scale
    tree = cKDTree(basis_u.doflocs.T)
    dist, idx = tree.query(pts.T, k=3)
    if np.any(dist > tol):
        bad = int(np.argmax(dist.max(axis=1)))
        raise ValueError(
            f"contact point {bad} at {pts[:, bad]} is not a displacement node; use P2 "
            "displacement (order=2) for mid-edge points or pick mesh nodes"
        )
    comp = _component_of(basis_u)
    u_dofs = np.empty((3, pts.shape[1]), dtype=int)
    for j in range(pts.shape[1]):
        c = comp[idx[j]]
        if sorted(c.tolist()) != [0, 1, 2]:
            raise ValueError(f"contact point {j}: could not find its three displacement dofs")
        u_dofs[c, j] = idx[j]
    vw = _tributary_heat_weights(blade, pts, tol)
    tdofs = basis_t.nodal_dofs[0]
    heat = sp.csr_matrix((vw.data, tdofs[vw.indices], vw.indptr), shape=(pts.shape[1], basis_t.N))
    a, e1, e2 = _axis_frame(blade.axis)
    radial = pts - np.outer(a, a @ pts)
    radii = np.linalg.norm(radial, axis=0)
    if np.any(radii <= 0):
        raise ValueError("a contact point lies on the machine axis: no radial direction")
    normals = radial / radii
    angles = np.arctan2(e2 @ pts, e1 @ pts)
    return ContactNodes(pts, normals, radii, angles, u_dofs, heat)


def _tributary_heat_weights(blade, pts, tol) -> sp.csr_matrix:
    """(n_c, n_vertices) weights spreading each contact's heat over its share of the tip.

    The frictional heat of contact ``i`` is generated over the part ``S_i`` of the tip face
    closer to ``p_i`` than to any other contact point, as a uniform flux: the weight of
    vertex ``j`` is ``∫_{S_i} N_j ds / |S_i|`` (rows sum to 1). Dumping it into one vertex
    would make the temperature depend on the mesh (a point source in 3D); without a usable
    ``tip`` face the heat goes to the nearest vertex (or the two ends of the mid-edge).
    """
    mesh = blade.mesh
    n_c, n_v = pts.shape[1], mesh.p.shape[1]
    tip = blade.node_sets.get("tip")
    facets = np.zeros(0, dtype=int)
    if tip is not None and tip.size:
        bf = mesh.boundary_facets()
        facets = bf[np.all(np.isin(mesh.facets[:, bf], tip), axis=0)]
    if facets.size >= n_c:
        tri = mesh.facets[:, facets]  # (3, n_f)
        P = mesh.p[:, tri]  # (3 coords, 3 vertices, n_f)
        area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], axis=0), axis=0)
        owner = cKDTree(pts.T).query(P.mean(axis=1).T)[1]
        if np.unique(owner).size == n_c:
            rows = np.repeat(owner, 3)
            cols = tri.T.ravel()
            vals = np.repeat(area / 3.0, 3)  # ∫ N_j ds over a linear triangle = area / 3
            W = sp.csr_matrix((vals, (rows, cols)), shape=(n_c, n_v))
            return sp.diags(1.0 / np.asarray(W.sum(axis=1)).ravel()) @ W
    vd, vi = cKDTree(mesh.p.T).query(pts.T)
    edges = mesh.edges
    etree = cKDTree((0.5 * (mesh.p[:, edges[0]] + mesh.p[:, edges[1]])).T)
    rows, cols, vals = [], [], []
    for j in range(n_c):
        if vd[j] <= tol:
            rows.append(j), cols.append(vi[j]), vals.append(1.0)
            continue
        ed, ei = etree.query(pts[:, j])
        if ed > tol:
            raise ValueError(f"contact point {j} at {pts[:, j]} is neither a vertex nor mid-edge")
        for v in edges[:, ei]:
            rows.append(j), cols.append(v), vals.append(0.5)
    return sp.csr_matrix((vals, (rows, cols)), shape=(n_c, n_v))


def _root_dofs(blade, basis_u, basis_t):
    mesh = blade.mesh
    root = blade.require("root")
    bf = mesh.boundary_facets()
    on = np.all(np.isin(mesh.facets[:, bf], root), axis=0)
    facets = bf[on]
    if facets.size == 0:
        raise ValueError(
            f"the 'root' node set of {blade.source} covers no boundary face; clamp a face"
        )
    return basis_u.get_dofs(facets).all(), basis_t.get_dofs(facets).all(), facets


def solid_matrices(
    blade,
    material: Material,
    *,
    order: int = 2,
    coupling: str = "physical",
    strain_heating: bool = False,
    rayleigh: tuple[float, float] = (0.0, 0.0),
    lumping: str | None = None,
):
    """Matrices of Eq. (2) of a blade, root face clamped and held at ambient.

    Vector P2 (``order=2``, HRZ-lumped mass) or P1 (row-sum) displacement and P1 temperature
    on the blade's tetrahedra. Returns ``(mats, basis_u, basis_t)``.
    """
    if order not in (1, 2):
        raise ValueError(f"displacement order must be 1 or 2, got {order!r}")
    elem = fem.ElementTetP2() if order == 2 else fem.ElementTetP1()
    basis_u = fem.Basis(blade.mesh, fem.ElementVector(elem))
    basis_t = basis_u.with_element(fem.ElementTetP1())  # same quadrature as basis_u
    fixed_u, fixed_t, _ = _root_dofs(blade, basis_u, basis_t)
    mats = assemble_thermoelastic(
        basis_u,
        basis_t,
        material,
        lumping=lumping or ("hrz" if order == 2 else "row-sum"),
        heat_lumping="row-sum",
        coupling=coupling,
        strain_heating=strain_heating,
        rayleigh=rayleigh,
        fixed_u=fixed_u,
        fixed_t=fixed_t,
    )
    return mats, basis_u, basis_t


def solid_model(
    blade,
    material: Material,
    *,
    casing: CasingProfile | None = None,
    rotation_speed: float = 0.0,
    friction: float = 0.0,
    heat_partition: float = 1.0,
    restitution: float = 0.0,
    order: int = 2,
    coupling: str = "physical",
    strain_heating: bool = False,
    rayleigh: tuple[float, float] = (0.0, 0.0),
    damping_ratio: float | None = None,
    damping_modes: tuple[int, int] = (1, 5),
    lumping: str | None = None,
    tip_force=None,
    thermal: str | bool = "auto",
) -> tuple[FirstOrderModel, FieldMap]:
    """First-order model (paper Eqs. 8–9) of a blade rubbing a rigid casing.

    Parameters
    ----------
    blade : :class:`femrub.geometry.BladeMesh` with node set ``root`` and contact points.
    material : :class:`Material` (SI).
    casing : casing profile (default: concentric, 0.1 mm clearance).
    rotation_speed : Ω (rad/s); the casing angle seen by a node is ``Ω t + φ``.
    friction : Coulomb coefficient μ; the frictional power is ``μ Ω r λ`` (W).
    heat_partition : fraction of the frictional power that enters the blade (the rest goes
        into the casing); the heat input is ``η μ Ω r λ``.
    restitution : Newton's coefficient e.
    order : 2 (vector P2 displacement, default) or 1 (P1, locks in bending).
    rayleigh : ``(a, b)`` of ``C = a M + b K``; or ``damping_ratio`` ζ, fitted as Rayleigh
        damping at the clamped modes ``damping_modes`` (1-based) of the blade.
    tip_force : optional ``(force_vector_N, signal)``: a total force spread uniformly over
        the ``tip`` node set's faces, times ``signal(t)``.

    Returns
    -------
    (model, fields) : the :class:`FirstOrderModel` and the :class:`FieldMap` for output.
    """
    t0 = time.perf_counter()
    omega = float(rotation_speed)
    mu_f = check_finite_positive("friction", friction, allow_zero=True)
    eta = check_finite_positive("heat_partition", heat_partition, allow_zero=True)
    if eta > 1.0:
        raise ValueError(f"heat_partition must be in [0, 1], got {heat_partition!r}")
    if not np.isfinite(omega):
        raise ValueError(f"rotation_speed must be finite (rad/s), got {rotation_speed!r}")
    casing = casing or Concentric(1e-4)
    mats, basis_u, basis_t = solid_matrices(
        blade,
        material,
        order=order,
        coupling=coupling,
        strain_heating=strain_heating,
        rayleigh=rayleigh,
        lumping=lumping,
    )
    contacts = locate_contacts(blade, basis_u, basis_t)
    t1 = time.perf_counter()
    if damping_ratio:
        from .damping import rayleigh_coefficients
        from .eigen import angular_frequencies

        i, j = damping_modes
        w = angular_frequencies(mats.K, mats.M, max(i, j))
        a, b = rayleigh_coefficients(float(damping_ratio), w[i - 1], w[j - 1])
        mats.C = (a * mats.M + b * mats.K).tocsr()
        rayleigh = (a, b)
    t2 = time.perf_counter()
    nc = contacts.points.shape[1]
    free_u = mats.u_index(contacts.u_dofs.ravel()).reshape(3, nc)
    N = sp.csr_matrix(
        (contacts.normals.T.ravel(), (np.repeat(np.arange(nc), 3), free_u.T.ravel())),
        shape=(nc, mats.n_u),
    )
    heat = contacts.heat[:, mats.free_t]
    angles = contacts.angles

    def gap(t, _profile=casing, _angles=angles, _omega=omega):
        return _profile.gap(_omega * t + _angles)

    def gap_rate(t, _profile=casing, _angles=angles, _omega=omega):
        return _omega * _profile.slope(_omega * t + _angles)

    spec = ContactSpec(
        normals=N,
        gap=gap,
        gap_rate=gap_rate,
        heat_dofs=heat.toarray(),
        restitution=restitution,
        heat_coefficient=eta * mu_f * abs(omega) * contacts.radii,
        names=[f"contact{i}" for i in range(nc)],
    )
    loads = []
    if tip_force is not None:
        loads.append(_tip_load(blade, basis_u, mats, *tip_force))
    mean = sp.csr_matrix(np.full((1, nc), 1.0 / nc))
    observe = {
        "contact_displacement": ("u", N),
        "contact_temperature": ("theta", heat),
        "tip_displacement": ("u", mean @ N),
        "tip_temperature": ("theta", mean @ heat),
    }
    model = first_order_model(mats, contact=spec, loads=loads, observe=observe, thermal=thermal)
    lam, mu = lame_parameters(material.young, material.poisson, 3)
    fields = FieldMap(
        mesh=blade.mesh,
        basis_u=basis_u,
        basis_t=basis_t,
        contacts=contacts,
        lam=lam,
        mu=mu,
        b=(3 * lam + 2 * mu) * material.expansion if coupling == "physical" else 0.0,
    )
    timings = {"assembly": t1 - t0, "damping": t2 - t1, "model": time.perf_counter() - t2}
    model.info.update(
        blade=blade.source,
        order=order,
        n_contacts=nc,
        fe_dofs=mats.n_u + mats.n_t,
        casing=casing.as_dict(),
        rotation_speed=omega,
        friction=mu_f,
        heat_partition=eta,
        rayleigh=tuple(float(x) for x in rayleigh),
        timings=timings,
    )
    fields.info.update(timings=timings)
    return model, fields


def _tip_load(blade, basis_u, mats, force, signal) -> Load:
    """Total force ``force`` (N, 3-vector) spread as a uniform traction on the tip faces."""
    mesh = blade.mesh
    tip = blade.require("tip")
    bf = mesh.boundary_facets()
    facets = bf[np.all(np.isin(mesh.facets[:, bf], tip), axis=0)]
    if facets.size == 0:
        raise ValueError(f"the 'tip' node set of {blade.source} covers no boundary face")
    fb = fem.FacetBasis(mesh, basis_u.elem, facets=facets)
    area = float(fem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).assemble(fb))
    traction = np.asarray(force, dtype=float) / area

    @fem.LinearForm
    def load(v, w):
        return sum(traction[i] * v[i] for i in range(3))

    f = load.assemble(fb)[mats.free_u]
    return Load(f, signal, "u", "tip_force")
