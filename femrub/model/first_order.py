"""The first-order model ``A Ẋ = B X + F(t) + H λ`` (paper Eqs. 8–9), full or reduced.

Every stepper works on :class:`FirstOrderModel` alone, so a full finite-element model and a
reduced one (paper Eq. 15, built by a reductor) are the same type. The state is ordered in
three blocks, ``X = [u, v, θ]`` (``layout``); in a reduced model these blocks hold reduced
coordinates and ``A`` may have off-diagonal blocks (``A_21``, ``A_23``, ...).

Contact (paper Eq. 8b) is described in gap form, independent of the model's coordinates,
by :class:`~femrub.contact.gap.Contact` (``g = g0(t) + Gᵀ X``, ``ġ = ġ0(t) + Gvᵀ X``, force
``Hm λ + Ht (α λ)``).

Models are immutable (``with_`` returns a changed copy) and carry their parameters, in the
spirit of pyMOR's ``mu``: ``model.parameters["rotation_speed"]`` (Ω, rad/s) and
``model.with_parameters(rotation_speed=...)``, a model at another speed that shares every
matrix (full or reduced alike: Ω enters only the contact's gap functions, the casing's
sliding velocity and the loads whose frequency is an engine order, through
:class:`CasingSweep`). A model whose stiffness was prestressed at Ω (centrifugal
prestress) refuses another speed: its matrices depend on Ω, rebuild it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from ..contact.gap import Contact
from ..fem.linalg import project

__all__ = [
    "CasingSweep",
    "Contact",
    "EnergyForms",
    "FirstOrderModel",
    "Layout",
    "LoadTerm",
    "Parameters",
]


@dataclass(frozen=True)
class Layout:
    """Sizes of the three state blocks ``[u, v, θ]`` (``n_t = 0`` when there is no thermal part).

    The state of Eq. (8) is ``X = [u, v, θ]``: displacements (m), velocities (m/s) and
    temperatures above ambient (K), or their reduced coordinates (Eqs. 10-15).

    Attributes
    ----------
    n_u, n_v, n_t : int
        Sizes of the displacement, velocity and temperature blocks.
    """

    n_u: int
    n_v: int
    n_t: int

    @property
    def n(self) -> int:
        return self.n_u + self.n_v + self.n_t

    @property
    def u(self) -> slice:
        return slice(0, self.n_u)

    @property
    def v(self) -> slice:
        return slice(self.n_u, self.n_u + self.n_v)

    @property
    def t(self) -> slice:
        return slice(self.n_u + self.n_v, self.n)


def _csc(a):
    """``a`` as a CSC matrix (itself when it is one: a model at other parameters shares it)."""
    return a if isinstance(a, sp.csc_matrix) else sp.csc_matrix(a)


def _csr(a):
    return a if isinstance(a, sp.csr_matrix) else sp.csr_matrix(a)


def _as_signal(signal) -> Callable:
    if callable(signal):
        return signal
    value = float(signal)
    return lambda t: value * np.ones_like(np.asarray(t, dtype=float))


@dataclass(frozen=True)
class LoadTerm:
    """One load ``F_j s_j(t)``: a state-space vector times a time signal (immutable).

    ``power`` is the state-space vector whose product with ``X`` is the mechanical power of
    the load per unit signal (``vᵀ f^u``); ``heat`` is the heat input per unit signal (W).
    """

    vector: np.ndarray
    signal: Callable
    power: np.ndarray
    heat: float = 0.0
    name: str = "load"

    def __post_init__(self):
        object.__setattr__(self, "signal", _as_signal(self.signal))


class Parameters(Mapping):
    """The parameters of a model (immutable mapping; ``rotation_speed``: Ω in rad/s).

    Its one attribute, ``_items`` (sorted ``(name, value)`` pairs), is plain data, so the
    model cache stores it as such (:mod:`femrub.app.cache_codec`)."""

    def __init__(self, values: Mapping | None = None, **more):
        items = {**dict(values or {}), **more}
        object.__setattr__(self, "_items", tuple(sorted((k, float(v)) for k, v in items.items())))

    def __getitem__(self, key: str) -> float:
        for k, v in self._items:
            if k == key:
                return v
        raise KeyError(key)

    def __iter__(self):
        return (k for k, _ in self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __setattr__(self, name, value):
        raise AttributeError("Parameters are immutable; use model.with_parameters(...)")

    def __hash__(self) -> int:
        return hash(self._items)

    def __eq__(self, other) -> bool:
        return isinstance(other, Mapping) and dict(self) == dict(other)

    def __repr__(self) -> str:
        return f"Parameters({dict(self._items)!r})"

    def __reduce__(self):
        return Parameters, (dict(self._items),)


@dataclass(frozen=True)
class CasingSweep:
    """What the rotation speed Ω changes in a rub model, and nothing else.

    ``casing`` (a :class:`~femrub.contact.casing.CasingProfile`), the contacts' ``angles``
    (rad), ``offsets`` (m, added clearance) and ``radii`` (m): the swept gap ``g(σ Ω t +
    φ_i) + offset_i`` and the casing's sliding velocity ``−s σ Ω r_i`` (the model's contact,
    full or reduced; :mod:`femrub.contact.casing`); ``direction`` σ: +1 counterclockwise,
    −1 clockwise about the machine axis; ``slip`` s: +1, or −1 for the reversed sliding of
    ``contact.slip_direction``; both are kept at every speed. ``prestress_speed``: Ω of a
    centrifugal prestress in the stiffness, or ``None``.
    """

    casing: object
    angles: np.ndarray
    offsets: np.ndarray
    radii: np.ndarray
    prestress_speed: float | None = None
    direction: float = 1.0
    slip: float = 1.0

    def contact_at(self, contact, omega: float):
        """``contact`` with its gap functions and casing velocity at ``omega`` (rad/s)."""
        from ..contact.casing import sliding_velocity, swept_gap

        if contact.wear is not None or contact.casing_heat is not None:
            raise ValueError(
                "rotation_speed: an abradable coating or a casing heat model is swept at the "
                "speed it was built for; build the model again at the new speed"
            )
        gap, rate = swept_gap(self.casing, self.angles, omega, self.offsets, self.direction)
        changes = {"gap0": gap, "gap_rate": rate}
        if contact.casing_velocity is not None:
            changes["casing_velocity"] = sliding_velocity(
                self.radii, omega, self.direction, self.slip
            )
        return replace(contact, **changes)


@dataclass
class EnergyForms:
    """Energy functionals of the state, so any model can report an energy balance.

    kinetic ``½ Xᵀ Qk X``, elastic ``½ Xᵀ Qe X``; powers ``Xᵀ Pth X`` (thermal stresses),
    ``Xᵀ Pd X`` (damping); heat content ``cᵀ X`` (J above ambient) and heat outflow rate
    through the boundaries and strain heating ``rᵀ X`` (W).

    ``Wth`` (optional): the work of the thermal stresses over a step as a form of the state
    increment, ``ΔW_th = (X_{k+1} − X_k)ᵀ Wth X_m`` (``Δuᵀ(−K^uθ θ_m)``). A full model does
    not need it (``u̇ = v`` makes it ``h X_mᵀ P_th X_m``); a reduced model whose displacement
    holds quasi-static expansion shapes moves when a heat impulse changes its temperature,
    and this form counts the work of that motion too.
    """

    Qk: sp.spmatrix
    Qe: sp.spmatrix
    Pth: sp.spmatrix
    Pd: sp.spmatrix
    heat_content: np.ndarray
    heat_outflow: np.ndarray
    Wth: sp.spmatrix | None = None

    def project(self, R, parts=None) -> EnergyForms:
        """The forms on the basis ``R`` (``parts``: row blocks of ``R``, see
        :func:`~femrub.fem.linalg.project`)."""

        def pr(Q):
            if sp.issparse(R):
                return sp.csr_matrix(R.T @ (Q @ R))
            return sp.csr_matrix(project(R, Q, R, parts=parts))

        return EnergyForms(
            Qk=pr(self.Qk),
            Qe=pr(self.Qe),
            Pth=pr(self.Pth),
            Pd=pr(self.Pd),
            heat_content=np.asarray(R.T @ self.heat_content).ravel(),
            heat_outflow=np.asarray(R.T @ self.heat_outflow).ravel(),
            Wth=None if self.Wth is None else pr(self.Wth),
        )


@dataclass(frozen=True)
class FirstOrderModel:
    """``A Ẋ = B X + Σ_j F_j s_j(t) + (Hm + Ht diag α) λ``, with contact in gap form.

    Immutable: :meth:`with_` and :meth:`with_parameters` return new models.

    Attributes
    ----------
    A, B : sparse (N, N) matrices (paper Eq. 9, or Eq. 14 for a reduced model).
    layout : :class:`Layout` of ``X = [u, v, θ]``.
    loads : list of :class:`LoadTerm`.
    contact : :class:`Contact` or ``None``.
    observations : name -> sparse (k, N) rows giving physical signals (tip displacement, ...).
    energy : :class:`EnergyForms` or ``None``.
    blocks : the Eq. (2) matrices of a full model (``None`` for a reduced one), so a reductor
        reads them instead of recovering them from ``A`` and ``B``.
    boundary : ``{"u": positions in the u-block, "theta": positions in the θ-block}`` of the
        dofs the contacts act on (paper Eq. 10), set by the constructor of a full model.
    to_full : optional (n_full, N) map from the state to the full-mesh physical state
        ``[u_all, v_all, θ_all]`` (Dirichlet dofs included); used for VTK output.
    x0 : initial state (zeros by default).
    info : free-form description (sizes, physics kept or dropped and why).
    length_scale : the blade's characteristic size (m): the bar's length or the mesh's
        largest extent, set by the builder and kept by every reduction; NaN when unknown.
    parameters : :class:`Parameters` (``rotation_speed``, rad/s, of a rub model).
    sweep : :class:`CasingSweep` of a rub model (what Ω changes), or ``None``.
    """

    A: sp.spmatrix
    B: sp.spmatrix
    layout: Layout
    loads: list[LoadTerm] = field(default_factory=list)
    contact: Contact | None = None
    observations: dict[str, sp.spmatrix] = field(default_factory=dict)
    energy: EnergyForms | None = None
    blocks: object = None
    boundary: dict | None = None
    to_full: object = None
    x0: np.ndarray | None = None
    info: dict = field(default_factory=dict)
    length_scale: float = float("nan")
    parameters: Parameters = field(default_factory=Parameters)
    sweep: CasingSweep | None = None

    def __post_init__(self):
        n = self.layout.n
        A, B = _csc(self.A), _csc(self.B)
        if A.shape != (n, n) or B.shape != (n, n):
            raise ValueError(f"A and B must be {n}x{n} to match the layout, got {A.shape}")
        x0 = np.zeros(n) if self.x0 is None else np.asarray(self.x0, dtype=float)
        if x0.shape != (n,) or not np.all(np.isfinite(x0)):
            raise ValueError(f"initial state must be a finite vector of length {n}")
        fixed = {
            "A": A,
            "B": B,
            "x0": x0,
            "loads": list(self.loads),
            "observations": {k: _csr(v) for k, v in self.observations.items()},
            "info": dict(self.info),
            "length_scale": float(self.length_scale),
            "parameters": Parameters(self.parameters),
        }
        for name, value in fixed.items():
            object.__setattr__(self, name, value)

    @property
    def n_dofs(self) -> int:
        return self.layout.n

    @property
    def n_contacts(self) -> int:
        return 0 if self.contact is None else self.contact.n

    def load(self, t: float) -> np.ndarray:
        """State-space load ``F(t) = Σ_j F_j s_j(t)``."""
        out = np.zeros(self.layout.n)
        for term in self.loads:
            out += term.vector * float(term.signal(t))
        return out

    def observe(self, X: np.ndarray) -> dict[str, np.ndarray]:
        """Physical signals of the state ``X`` (one array per observation name)."""
        return {k: np.asarray(O @ X).ravel() for k, O in self.observations.items()}

    def with_(self, **changes) -> FirstOrderModel:
        """A copy with some fields changed (e.g. ``model.with_(x0=...)``)."""
        return replace(self, **changes)

    def with_parameters(self, **values) -> FirstOrderModel:
        """This model at other parameter values (``rotation_speed=`` Ω in rad/s), sharing
        every matrix (module docstring). The contacts are those the builder kept at the
        model's own speed (its reach filter is not run again).

        Raises
        ------
        ValueError
            An unknown parameter, a speed that is not finite, or a speed that changes a
            matrix (a centrifugal prestress at another Ω) or a swept casing cell state
            (an abradable coating, a casing heat model): rebuild the model then.
        """
        unknown = sorted(set(values) - {"rotation_speed"})
        if unknown:
            raise ValueError(f"unknown model parameter(s) {unknown}; known: rotation_speed")
        if "rotation_speed" not in values:
            return self
        omega = float(values["rotation_speed"])
        if not math.isfinite(omega):
            raise ValueError(f"rotation_speed must be finite (rad/s), got {omega!r}")
        if omega == self.parameters.get("rotation_speed"):
            return self
        return replace(self, **_at_speed(self, omega))


def _at_speed(model: FirstOrderModel, omega: float) -> dict:
    """The fields of ``model`` that change at the rotation speed ``omega`` (rad/s)."""
    sweep = model.sweep
    if sweep is None:
        raise ValueError("rotation_speed: this model has no rotating casing (no CasingSweep)")
    if sweep.prestress_speed is not None:
        raise ValueError(
            f"rotation_speed = {omega:g} rad/s: the stiffness holds the centrifugal prestress "
            f"at {sweep.prestress_speed:g} rad/s; build the model again at the new speed"
        )
    loads = [_load_at(term, omega) for term in model.loads]
    contact = None if model.contact is None else sweep.contact_at(model.contact, omega)
    return {
        "contact": contact,
        "loads": loads,
        "parameters": Parameters(model.parameters, rotation_speed=omega),
        "info": {**model.info, "rotation_speed": omega},
    }


def _load_at(term: LoadTerm, omega: float) -> LoadTerm:
    """``term`` with its signal at ``omega`` when its frequency is an engine order of Ω."""
    at = getattr(term.signal, "at_rotation_speed", None)
    return term if at is None else replace(term, signal=at(omega))
