"""The full first-order model of a scene: bar or 3D blade, loads, thermal part, contacts.

* Temperature dofs are kept only when something heats the blade (``physics.thermal =
  "auto"``): frictional heat on a contact the casing can reach, or strain-rate heating.
* Contacts are kept only where the casing can reach them (:func:`contact_reach`): a contact
  point whose smallest gap over a revolution stays above ``contact.reach`` is dropped.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..cases.bar import BarCase, bar_model
from ..contact.casing import casing_profile
from ..fem.material import Material
from ..model.first_order import Contact

__all__ = ["ForceLaw", "build_full", "contact_reach", "restrict_contacts", "thermal_choice"]


class ForceLaw:
    """Time signal of the tip force, times its amplitude (``law`` of ``loads.tip_force``)."""

    def __init__(self, law: str, omega: float = 0.0, phase: float = 0.0, ramp_time: float = 1.0):
        self.law, self.omega, self.phase, self.ramp_time = law, omega, phase, ramp_time

    def __call__(self, t):
        if self.law == "sin":
            return np.sin(self.omega * t + self.phase)
        if self.law == "ramp":
            return np.minimum(np.asarray(t, dtype=float) / self.ramp_time, 1.0)
        return np.ones_like(np.asarray(t, dtype=float))


def force_law(scene):
    """``(amplitude N, ForceLaw, ω rad/s or None)`` of the tip force, or ``None``."""
    f = scene["loads"]["tip_force"]
    if f["law"] == "none" or f["amplitude"] == 0.0:
        return None
    omega = None
    if f["law"] == "sin":
        omega = f["frequency"]
        if omega == "rotation":
            omega = f["engine_order"] * scene["loads"]["rotation_speed"]
        law = ForceLaw("sin", omega, math.radians(f["phase"]))
    else:
        law = ForceLaw(f["law"], ramp_time=f.get("ramp_time", 1.0))
    return f["amplitude"], law, omega


def coupling_of(scene) -> str:
    c = scene["physics"]["coupling"]
    return c if c != "auto" else ("paper" if scene["geometry"]["kind"] == "bar" else "physical")


def thermal_choice(scene, heated: bool, reachable: bool = True) -> tuple[bool, str]:
    """Keep the temperature dofs? ``heated``: frictional heat on a reachable contact.

    ``reachable=False`` says that the heat would come from contacts the casing never reaches.
    """
    mode = scene["physics"]["thermal"]
    coupling = coupling_of(scene)
    if mode == "on":
        return True, f"kept (physics.thermal = 'on'; coupling {coupling!r})"
    if mode == "off":
        return False, "dropped (physics.thermal = 'off': frictional heat and coupling ignored)"
    sources = ["frictional heat at the contacts"] if heated else []
    if scene["physics"]["strain_heating"] and coupling != "none":
        sources.append("strain-rate heating")
    if sources:
        return True, f"kept: {' and '.join(sources)} (coupling {coupling!r})"
    if not reachable:
        why = "no contact the casing can reach"
    elif scene["geometry"]["kind"] == "bar":
        why = "contact.heat_coefficient = 0"
    elif scene["contact"]["friction"] == 0.0:
        why = "contact.friction = 0"
    else:
        why = "loads.rotation_speed = 0 (no sliding)"
    return False, f"dropped: no heat source ({why}); the coupling has nothing to act on"


def heat_possible(scene) -> bool:
    """Frictional heat is produced on contact (before knowing which contacts are reachable)."""
    c = scene["contact"]
    if scene["geometry"]["kind"] == "bar":
        return c["heat_coefficient"] > 0.0
    return c["friction"] > 0.0 and scene["loads"]["rotation_speed"] > 0.0


def material_of(scene) -> Material:
    m = scene["material"]
    return Material(
        young=m["young"], rho=m["density"], poisson=m["poisson"],
        rho_c=m["density"] * m["specific_heat"], conductivity=m["conductivity"],
        expansion=m["expansion"], reference_temperature=m["reference_temperature"],
    )  # fmt: skip


def casing_of(scene):
    params = dict(scene["contact"]["casing"])
    kind = params.pop("kind")
    if "phase" in params:
        params["phase"] = math.radians(params["phase"])
    return casing_profile(kind, **params)


def build_full(scene, thermal: bool, blade=None):
    """Full model (and :class:`~femrub.fem.solid.FieldMap` in 3D, else ``None``)."""
    g, p, c = scene["geometry"], scene["physics"], scene["contact"]
    force = force_law(scene)
    lumping = p["lumping"]
    if g["kind"] == "bar":
        m = scene["material"]
        case = BarCase(
            length=g["length"], area=g["area"], young=m["young"], density=m["density"],
            total_mass=None if g["total_mass"] == "density" else g["total_mass"],
            specific_heat=m["specific_heat"], conductivity=m["conductivity"],
            expansion=m["expansion"], n_elements=g["n_elements"], grading=g["grading"],
            coupling=coupling_of(scene), beta=p["beta"], strain_heating=p["strain_heating"],
            lumping="row-sum" if lumping == "auto" else lumping, rayleigh=tuple(p["rayleigh"]),
            clamped=scene["boundary"]["clamped"], gap=c["casing"]["clearance"],
            restitution=c["restitution"], alpha=c["heat_coefficient"],
            force_amplitude=force[0] if force else 0.0, thermal=bool(thermal),
        )  # fmt: skip
        model = bar_model(case)
        if force:
            model.loads = [replace(term, signal=force[1]) for term in model.loads]
        return model, None
    from ..fem.solid import solid_model

    tip_force = None
    if force:
        d = scene["loads"]["tip_force"]["direction"]
        if d == "radial":
            d = blade.radial_direction(blade.contact_points).mean(axis=1)
        d = np.asarray(d, dtype=float)
        if not np.linalg.norm(d) > 0:
            raise ValueError("loads.tip_force.direction = [0, 0, 0]: give a non-zero vector")
        tip_force = (force[0] * d / np.linalg.norm(d), force[1])
    return solid_model(
        blade, material_of(scene), casing=casing_of(scene),
        rotation_speed=scene["loads"]["rotation_speed"], friction=c["friction"],
        restitution=c["restitution"], order=p["order"], coupling=coupling_of(scene),
        strain_heating=p["strain_heating"], rayleigh=tuple(p["rayleigh"]),
        lumping=None if lumping == "auto" else lumping, tip_force=tip_force, thermal=thermal,
    )  # fmt: skip


def _max_normal_displacement(model, omega) -> float:
    """Largest contact normal displacement under the tip force amplitude (static, harmonic)."""
    if not model.loads or model.contact is None:
        return 0.0
    L = model.layout
    blocks = model.blocks
    f = sum(term.vector[L.v] for term in model.loads)
    N = -model.contact.G[L.u].T
    out = 0.0
    for w in [0.0] + ([omega] if omega else []):
        try:
            u = spla.splu(sp.csc_matrix(blocks.K - w * w * blocks.M)).solve(f)
        except RuntimeError:  # singular: free structure or exact resonance
            return math.inf
        out = max(out, float(np.max(np.abs(N @ u))))
    return out


def contact_reach(scene, model, fields) -> dict:
    """Which contacts the casing can reach; see ``docs/scenes.md`` (``contact.reach``).

    Returns a dict with ``min_gap`` (smallest gap of each contact over a revolution, m),
    ``offset`` (added clearance, m), ``reach`` (m), ``deflection`` (largest contact
    displacement under the tip force, m), ``intrusion`` (m) and the boolean ``keep``.
    """
    c = scene["contact"]
    casing = casing_of(scene)
    n = model.n_contacts
    if fields is None:
        radii, angles = np.ones(n), np.zeros(n)
    else:
        radii, angles = fields.contacts.radii, fields.contacts.angles
    offset = radii.max() - radii if c["gap_reference"] == "outermost" else np.zeros(n)
    if scene["loads"]["rotation_speed"] > 0.0:
        min_gap = casing.min_gap() + offset
    else:
        min_gap = np.asarray(casing.gap(angles), dtype=float) + offset
    intrusion = max(0.0, -float(min_gap.min())) if n else 0.0
    force = force_law(scene)
    deflection = _max_normal_displacement(model, force[2] if force else None)
    reach = c["reach"]
    if reach == "all":
        reach = math.inf
    elif reach == "auto":
        reach = 2.0 * deflection + intrusion + c["reach_margin"]
    return {
        "min_gap": min_gap,
        "offset": offset,
        "reach": reach,
        "deflection": deflection,
        "intrusion": intrusion,
        "keep": min_gap <= reach,
    }


def _pick(a, idx):
    return a[idx] if not callable(a) else (lambda t, _a=a, _i=idx: np.asarray(_a(t))[_i])


def restrict_contacts(model, fields, keep, offset):
    """The model (and field map) with only the contacts ``keep`` and gaps ``+ offset``."""
    c = model.contact
    idx = np.flatnonzero(keep)
    if c is None or (idx.size == c.n and not np.any(offset)):
        return model, fields
    obs = dict(model.observations)
    contact = None
    if idx.size:
        off = np.asarray(offset, dtype=float)[idx]
        g0 = c.gap0
        gap = (
            (lambda t, _g=g0, _i=idx, _o=off: np.asarray(_g(t))[_i] + _o)
            if callable(g0)
            else (g0[idx] + off)
        )
        alpha = c.heat_coefficient
        contact = Contact(
            G=c.G[:, idx], Gv=c.Gv[:, idx], Hm=c.Hm[:, idx], Ht=c.Ht[:, idx], gap0=gap,
            restitution=c.restitution, heat_coefficient=_pick(alpha, idx),
            names=[c.names[i] for i in idx],
            gap_rate=None if c.gap_rate is None else _pick(c.gap_rate, idx),
        )  # fmt: skip
    for name in ("contact_displacement", "contact_temperature"):
        if name in obs:
            if idx.size:
                sub = sp.csr_matrix(obs[name])[idx]
                obs[name] = sub
                obs[name.replace("contact_", "tip_")] = sp.csr_matrix(sub.mean(axis=0))
            else:
                del obs[name]
    info = dict(model.info, n_contacts=int(idx.size))
    L = model.layout
    rows = lambda M, sl: np.flatnonzero(np.any(M[sl][:, idx] != 0.0, axis=1))  # noqa: E731
    boundary = {"u": rows(c.G, L.u), "theta": rows(c.Ht, L.t) if L.n_t else np.zeros(0, int)}
    model = model.with_(contact=contact, observations=obs, info=info, boundary=boundary)
    if fields is not None:
        k = fields.contacts
        sub = replace(
            k, points=k.points[:, idx], normals=k.normals[:, idx], radii=k.radii[idx],
            angles=k.angles[idx], u_dofs=k.u_dofs[:, idx], heat=k.heat[idx],
        )  # fmt: skip
        fields = replace(fields, contacts=sub)
    return model, fields
