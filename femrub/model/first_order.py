"""The first-order model ``A Ẋ = B X + F(t) + H λ`` (paper Eqs. 8–9), full or reduced.

Every stepper works on :class:`FirstOrderModel` alone, so a full finite-element model and a
reduced one (paper Eq. 15, built by a reductor) are the same type. The state is ordered in
three blocks, ``X = [u, v, θ]`` (``layout``); in a reduced model these blocks hold reduced
coordinates and ``A`` may have off-diagonal blocks (``A_21``, ``A_23``, ...).

Contact (paper Eq. 8b) is described in gap form, independent of the model's coordinates,
by :class:`~femrub.contact.gap.Contact` (``g = g0(t) + Gᵀ X``, ``ġ = ġ0(t) + Gvᵀ X``, force
``Hm λ + Ht (α λ)``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from ..contact.gap import Contact
from ..fem.linalg import project

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
