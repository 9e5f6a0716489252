"""The 1D thermoelastic bar (blade) of the paper, as a ``MeshLine`` case of the generic code.

Defaults are the paper case of ``model-notes.md``: L = 0.30 m, A = 1 mm², E = 110 GPa, total
mass 0.1 kg lumped along 20 elements (m/n per node, m/2n at the tip), ρ c = 4500 × 585
J/(m³ K), λ_th = 3.35 W/(m K), root clamped and held at ambient, paper coupling
``K^uθ = β K^uu`` with β = −4.5e-7 m/K, tip force 7 sin(Ω t) N with Ω = 2000 rpm, gap 15 µm,
restitution 0, frictional heat ``α λ`` at the tip. Ω is :func:`~femrub.scene.units.rpm`,
the scene's own conversion of ``"2000 rpm"``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

from ..contact.casing import Concentric
from ..fem.assembly import ThermoelasticMatrices
from ..fem.material import Material, check_finite_positive
from ..geometry.bar import bar_mesh
from ..model.builder import build_rub
from ..model.config import ContactConfig, ForceConfig, ForceLaw, RubConfig
from ..model.first_order import FirstOrderModel
from ..scene.units import rpm

__all__ = [
    "BarCase",
    "PAPER",
    "bar_config",
    "bar_matrices",
    "bar_model",
    "impact_bar_model",
    "rpm",
]


@dataclass(frozen=True)
class BarCase:
    """Parameters of a 1D bar rub case (SI units); the defaults are the paper case.

    The bar is the blade of the paper's Sec. 1: Eq. (2) on ``n_elements`` linear elements,
    clamped at the root, its tip node rubbing a rigid concentric casing ``gap`` away under
    the Signorini conditions and Newton's impact law (Eq. 3), heated by ``alpha × λ``.

    Attributes
    ----------
    length : float
        Bar length L (m).
    area : float
        Cross-section A (m²).
    young : float
        Young's modulus E (Pa).
    total_mass : float or None
        Mass of the bar (kg), lumped along it (m/n per node, m/2n at the tip); ``None``:
        ``density × area × length``.
    density, specific_heat, conductivity, expansion : float
        ρ (kg/m³), c (J/(kg K)), λ_th (W/(m K)) and the expansion coefficient (1/K).
    n_elements : int
        Number of elements.
    grading : float
        Exponent p of the nodes ``x = L (1 − (1 − ξ)^p)`` (1: uniform; > 1: finer at the tip).
    coupling : {"paper", "physical", "none"}
        ``K^uθ = β K^uu`` (the paper's), ``E A α_th ∫ N_u' N_θ dx``, or none.
    beta : float
        β of the paper coupling (m/K).
    strain_heating : bool
        Keep the thermoelastic heating block ``C^θu`` of Eq. (2).
    lumping : str
        Mass lumping (``"row-sum"``, ``"hrz"`` or ``"consistent"``).
    rayleigh : tuple of float
        Rayleigh damping ``C = a M + b K`` as ``(a, b)`` (1/s, s).
    clamped : bool
        Clamp the root (``False``: a free bar).
    gap : float
        Initial tip-casing clearance d (m).
    restitution : float
        Coefficient of restitution e of the impact law, in [0, 1].
    alpha : float
        Frictional heat coefficient α (m/s): heat flux ``α λ`` (W) into the tip.
    force_amplitude, force_frequency : float
        Tip force ``F sin(Ω t)``: F (N) and Ω (rad/s; 2000 rpm by default).
    initial_velocity : float
        Uniform initial velocity of the bar (m/s).
    thermal : bool or "auto"
        Keep the temperature unknowns (``"auto"``: when something heats the blade).
    reach : float or str
        The reach filter of the contacts (:mod:`femrub.contact.reach`).
    """

    length: float = 0.30
    area: float = 1e-6
    young: float = 110e9
    total_mass: float | None = 0.1
    density: float = 4500.0
    specific_heat: float = 585.0
    conductivity: float = 3.35
    expansion: float = 8.6e-6
    n_elements: int = 20
    grading: float = 1.0
    coupling: str = "paper"
    beta: float = -4.5e-7
    strain_heating: bool = False
    lumping: str = "row-sum"
    rayleigh: tuple = (0.0, 0.0)
    clamped: bool = True
    gap: float = 15e-6
    restitution: float = 0.0
    alpha: float = 1.0
    force_amplitude: float = 7.0
    force_frequency: float = field(default_factory=lambda: rpm(2000.0))
    initial_velocity: float = 0.0
    thermal: str | bool = "auto"
    #: the reach filter (:mod:`femrub.contact.reach`): ``"all"`` keeps the tip whatever
    #: the force (a free bar thrown at the casing has none), ``"auto"`` as a scene
    reach: float | str = "all"

    def __post_init__(self):
        for name in ("length", "area", "young", "density", "specific_heat"):
            check_finite_positive(name, getattr(self, name))
        if self.total_mass is not None:
            check_finite_positive("total_mass", self.total_mass)
        for name in ("gap", "alpha", "force_amplitude", "force_frequency", "conductivity"):
            v = float(getattr(self, name))
            if not math.isfinite(v):
                raise ValueError(f"{name} must be finite, got {v!r}")
        if self.alpha < 0:
            raise ValueError(
                f"alpha must be >= 0 (frictional heat is never negative), got {self.alpha}"
            )
        if not (math.isfinite(float(self.grading)) and float(self.grading) >= 1.0):
            raise ValueError(f"grading must be >= 1 (1: uniform mesh), got {self.grading!r}")
        if self.coupling == "paper" and float(self.grading) != 1.0:
            # β K^uu expands each node by -β θ whatever its element size: on a graded mesh a
            # hot micrometre-long tip element would push the tip tens of µm (mesh-dependent)
            raise ValueError(
                "coupling='paper' (K^uθ = β K^uu) needs a uniform mesh (grading = 1); "
                "use coupling='physical' on a graded mesh"
            )
        if not (isinstance(self.n_elements, int) and self.n_elements >= 1):
            raise ValueError(f"n_elements must be a positive integer, got {self.n_elements!r}")
        if not (0.0 <= float(self.restitution) <= 1.0):
            raise ValueError(f"restitution must be in [0, 1], got {self.restitution!r}")

    def with_(self, **changes) -> BarCase:
        return replace(self, **changes)

    def as_dict(self) -> dict:
        return asdict(self)

    @property
    def rho_mass(self) -> float:
        """Density of the mass matrix: total_mass / (A L) when a total mass is given."""
        if self.total_mass is None:
            return self.density
        return self.total_mass / (self.area * self.length)

    @property
    def material(self) -> Material:
        return Material(
            young=self.young,
            rho=self.rho_mass,
            rho_c=self.density * self.specific_heat,
            conductivity=self.conductivity,
            expansion=self.expansion,
        )


PAPER = BarCase()


def bar_config(case: BarCase = PAPER) -> RubConfig:
    """The :class:`~femrub.model.config.RubConfig` of ``case`` (the built-in scene
    ``paper`` turns into the same one): concentric casing at ``gap``, heat ``α λ``, tip force
    ``force_amplitude sin(Ω t)`` with the rotation speed Ω = ``force_frequency`` (engine
    order 1, as the scene's ``frequency = "rotation"``)."""
    F0 = float(case.force_amplitude)
    force = None
    if F0 != 0.0:
        omega = float(case.force_frequency)
        force = ForceConfig(F0, ForceLaw("sin", omega, engine_order=1), frequency=omega)
    return RubConfig(
        case.material,
        ContactConfig(
            casing=Concentric(case.gap),
            heat_law="alpha",
            heat_coefficient=case.alpha,
            restitution=case.restitution,
            reach=case.reach,
        ),
        rotation_speed=float(case.force_frequency),
        order=1,
        clamped=case.clamped,
        area=case.area,
        lumping=case.lumping,
        coupling=case.coupling,
        beta=case.beta,
        strain_heating=case.strain_heating,
        rayleigh=tuple(case.rayleigh),
        thermal=case.thermal,
        tip_force=force,
        initial_velocity=case.initial_velocity,
    )


def _bar_build(case: BarCase):
    return build_rub(bar_mesh(case.length, case.n_elements, case.grading), bar_config(case))


def _bar_parts(case: BarCase):
    """Discretisation, Eq. (2) blocks and contact point (the tip) of the bar."""
    built = _bar_build(case)
    return built.disc, built.mats, built.candidates


def _tip_dof(built) -> int:
    return int(built.mats.u_index(built.candidates.u_dofs[0])[0])


def bar_matrices(case: BarCase = PAPER) -> tuple[ThermoelasticMatrices, int]:
    """The bar's Eq. (2) blocks (scikit-fem) and the tip's free displacement dof.

    Parameters
    ----------
    case : BarCase
        The bar (default :data:`PAPER`).

    Returns
    -------
    matrices : ThermoelasticMatrices
        ``M`` (kg), ``C`` (N s/m), ``K`` (N/m), ``K^uθ`` (N/K), ``C^θu``, ``C^θθ`` (J/K),
        ``K^θθ`` (W/K) on the free dofs.
    tip_dof : int
        Index of the tip's displacement among the free displacement dofs.
    """
    built = _bar_build(case)
    return built.mats, _tip_dof(built)


def bar_model(case: BarCase = PAPER, **changes) -> FirstOrderModel:
    """First-order model of the bar rubbing a rigid casing at its tip (paper Sec. 1).

    Built by the one builder of every rub model (:func:`femrub.model.builder.build_rub`,
    configuration :func:`bar_config`): the same model as the built-in scene ``paper`` with
    the same values. Observed signals: ``tip_displacement`` (m), ``tip_velocity`` (m/s),
    ``tip_temperature`` (K above ambient, when the thermal part is kept).
    """
    if changes:
        case = case.with_(**changes)
    built = _bar_build(case)
    model = built.model
    return model.with_(info={**model.info, "case": case.as_dict(), "tip_dof": _tip_dof(built)})


def impact_bar_model(
    n_elements: int,
    *,
    velocity: float = 0.1,
    gap: float = 1e-5,
    young: float = 110e9,
    density: float = 4500.0,
    area: float = 1e-6,
    length: float = 0.3,
    **changes,
) -> FirstOrderModel:
    """A free bar moving at ``velocity`` (m/s) towards a rigid obstacle ``gap`` (m) away.

    The benchmark with an exact solution (:func:`femrub.cases.analytic.bar_impact`): no clamp, no
    load, no thermal part, consistent density (no lumped total mass), e = 0 at the contact.
    """
    case = dict(
        n_elements=n_elements,
        clamped=False,
        total_mass=None,
        density=density,
        young=young,
        area=area,
        length=length,
        force_amplitude=0.0,
        coupling="none",
        alpha=0.0,
        gap=gap,
        initial_velocity=velocity,
        restitution=0.0,
    )
    case.update(changes)
    return bar_model(PAPER, **case)
