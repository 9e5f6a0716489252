"""The first-order model ``A Ẋ = B X + F(t) + H λ`` (paper Eqs. 8–9), full or reduced.

Every stepper works on :class:`FirstOrderModel` alone, so a full finite-element model and a
reduced one (paper Eq. 15, built by a reductor) are the same type. The state is ordered in
three blocks, ``X = [u, v, θ]`` (``layout``); in a reduced model these blocks hold reduced
coordinates and ``A`` may have off-diagonal blocks (``A_21``, ``A_23``, ...).

Contact (paper Eq. 8b) is described in gap form, independent of the model's coordinates::

    g(t, X) = g0(t) + Gᵀ X          normal gap at each contact (m), g >= 0 means open
    ġ       = ġ0(t) + Gvᵀ X         normal gap velocity (m/s); ġ0 = dg0/dt (moving casing)
    force   = Hm λ + Ht (α λ)       reaction λ >= 0 (N) and frictional heat α λ (W)

The paper's tip node is the case ``G = −e_u(n)``, ``Gv = Hm = −e_v(n)``, ``Ht = e_θ(n)``:
the reaction pushes the tip away from the casing and the heat input ``α λ`` is never negative.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

__all__ = ["Layout", "LoadTerm", "Contact", "EnergyForms", "FirstOrderModel"]


@dataclass(frozen=True)
class Layout:
    """Sizes of the three state blocks ``[u, v, θ]`` (``n_t = 0`` when there is no thermal part)."""

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


def _as_signal(signal) -> Callable:
    if callable(signal):
        return signal
    value = float(signal)
    return lambda t: value * np.ones_like(np.asarray(t, dtype=float))


@dataclass
class LoadTerm:
    """One load ``F_j s_j(t)``: a state-space vector times a time signal.

    ``power`` is the state-space vector whose product with ``X`` is the mechanical power of
    the load per unit signal (``vᵀ f^u``); ``heat`` is the heat input per unit signal (W).
    """

    vector: np.ndarray
    signal: Callable
    power: np.ndarray
    heat: float = 0.0
    name: str = "load"

    def __post_init__(self):
        self.signal = _as_signal(self.signal)


@dataclass
class Contact:
    """Unilateral contacts in gap form (see module docstring).

    Parameters
    ----------
    G, Gv, Hm, Ht : (N, n_c) arrays (dense; n_c is small).
    gap0 : (n_c,) initial gaps (m) or a callable ``t -> (n_c,)`` (rotating casing profile).
    gap_rate : ``dg0/dt``, a callable ``t -> (n_c,)`` (m/s) when ``gap0`` moves; ``None``: 0.
    restitution : Newton restitution coefficient e in [0, 1].
    heat_coefficient : α (m/s) per contact, scalar, array or callable ``t -> (n_c,)``.
    names : labels of the contacts.
    """

    G: np.ndarray
    Gv: np.ndarray
    Hm: np.ndarray
    Ht: np.ndarray
    gap0: np.ndarray | Callable
    restitution: float = 0.0
    heat_coefficient: float | np.ndarray | Callable = 0.0
    names: list[str] = field(default_factory=list)
    gap_rate: Callable | None = None

    def __post_init__(self):
        self.G, self.Gv, self.Hm, self.Ht = (
            np.atleast_2d(np.asarray(a, dtype=float).T).T
            for a in (self.G, self.Gv, self.Hm, self.Ht)
        )
        e = float(self.restitution)
        if not (0.0 <= e <= 1.0):
            raise ValueError(f"restitution must be in [0, 1], got {self.restitution!r}")
        if not callable(self.gap0):
            self.gap0 = np.broadcast_to(np.asarray(self.gap0, dtype=float), (self.n,)).copy()
            if not np.all(np.isfinite(self.gap0)):
                raise ValueError("contact gap must be finite")
        if not callable(self.heat_coefficient):
            a = np.broadcast_to(np.asarray(self.heat_coefficient, dtype=float), (self.n,)).copy()
            if not np.all(np.isfinite(a)) or np.any(a < 0):
                raise ValueError(f"heat coefficient alpha must be finite and >= 0, got {a}")
            self.heat_coefficient = a
        if not self.names:
            self.names = [f"c{i}" for i in range(self.n)]

    @property
    def n(self) -> int:
        return self.G.shape[1]

    def gap_at(self, t: float) -> np.ndarray:
        return np.asarray(self.gap0(t), dtype=float) if callable(self.gap0) else self.gap0

    def rate_at(self, t: float) -> np.ndarray | float:
        """``dg0/dt`` at ``t`` (0 for a fixed obstacle)."""
        return 0.0 if self.gap_rate is None else np.asarray(self.gap_rate(t), dtype=float)

    def alpha_at(self, t: float) -> np.ndarray:
        if callable(self.heat_coefficient):
            return np.asarray(self.heat_coefficient(t), dtype=float)
        return self.heat_coefficient

    @property
    def has_heat(self) -> bool:
        a = self.heat_coefficient
        return callable(a) or bool(np.any(np.asarray(a) > 0) and np.any(self.Ht))

    def project(self, left: np.ndarray, right: np.ndarray) -> Contact:
        """Contact of the model reduced by ``X = right X̄`` and left projection ``leftᵀ``."""
        return replace(
            self,
            G=right.T @ self.G,
            Gv=right.T @ self.Gv,
            Hm=left.T @ self.Hm,
            Ht=left.T @ self.Ht,
        )


@dataclass
class EnergyForms:
    """Energy functionals of the state, so any model can report an energy balance.

    kinetic ``½ Xᵀ Qk X``, elastic ``½ Xᵀ Qe X``; powers ``Xᵀ Pth X`` (thermal stresses),
    ``Xᵀ Pd X`` (damping); heat content ``cᵀ X`` (J above ambient) and heat outflow rate
    through the boundaries and strain heating ``rᵀ X`` (W).
    """

    Qk: sp.spmatrix
    Qe: sp.spmatrix
    Pth: sp.spmatrix
    Pd: sp.spmatrix
    heat_content: np.ndarray
    heat_outflow: np.ndarray

    def project(self, R) -> EnergyForms:
        def pr(Q):
            out = R.T @ (Q @ R)
            return sp.csr_matrix(out) if sp.issparse(out) else sp.csr_matrix(np.asarray(out))

        return EnergyForms(
            Qk=pr(self.Qk),
            Qe=pr(self.Qe),
            Pth=pr(self.Pth),
            Pd=pr(self.Pd),
            heat_content=np.asarray(R.T @ self.heat_content).ravel(),
            heat_outflow=np.asarray(R.T @ self.heat_outflow).ravel(),
        )


@dataclass
class FirstOrderModel:
    """``A Ẋ = B X + Σ_j F_j s_j(t) + (Hm + Ht diag α) λ``, with contact in gap form.

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

    def __post_init__(self):
        self.A = sp.csc_matrix(self.A)
        self.B = sp.csc_matrix(self.B)
        n = self.layout.n
        if self.A.shape != (n, n) or self.B.shape != (n, n):
            raise ValueError(f"A and B must be {n}x{n} to match the layout, got {self.A.shape}")
        if self.x0 is None:
            self.x0 = np.zeros(n)
        self.x0 = np.asarray(self.x0, dtype=float)
        if self.x0.shape != (n,) or not np.all(np.isfinite(self.x0)):
            raise ValueError(f"initial state must be a finite vector of length {n}")
        self.observations = {k: sp.csr_matrix(v) for k, v in self.observations.items()}

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
