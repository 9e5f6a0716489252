"""The scene schema: every section, key, unit, default and allowed value (SI units).

``SCHEMA`` maps a section to its keys (:class:`~femrub.scene.spec.Spec`) or to a
:class:`~femrub.scene.spec.Variant` whose keys depend on a selector. ``docs/scenes.md``
documents the same table; :func:`schema_rows` lists it for the docs and the tests.
"""

from __future__ import annotations

from .schema_rotor import CASING_SECTION, ROTOR
from .schema_run import LIMITS, OUTPUTS, REDUCTION, SCHEME, SIGNALS
from .spec import NONNEG, POS, REQUIRED, Spec, Variant
from .spec import float_spec as _f

__all__ = ["SCHEMA", "SIGNALS", "TOP", "schema_rows"]

F, I, B, S, C = "float", "int", "bool", "str", "choice"
UNITS_LEN = ("m", "cm", "mm")
AXES = ("x", "y", "z")


_BLADE_MESH = {
    "h": _f(None, "length", "target element size (default: from the section thickness)", **POS),
    "h_min": _f(None, "length", "smallest element size (default h/4)", **POS),
    "n_contact": Spec(I, 10, lo=1, hi=200, doc="contact points on the tip camber line"),
    "contact_margin": _f(0.05, "none", "chord fraction kept free of contacts", lo=0.0, hi=0.49),
}

GEOMETRY = Variant(
    "kind",
    default="bar",
    doc="1D bar of the paper, gmsh parametric blade (box, naca), sections or a mesh file",
    variants={
        "bar": {
            "length": _f(0.30, "length", "bar length", **POS),
            "area": _f(1e-6, "area", "cross-section area", **POS),
            "n_elements": Spec(I, 20, lo=1, hi=5000, doc="number of linear elements"),
            "grading": _f(1.0, "none", "mesh grading towards the tip (1: uniform)", lo=1.0),
            "total_mass": Spec(
                F,
                0.1,
                "mass",
                choices=("density",),
                doc="mass spread along the bar "
                "(m/n per node, m/2n at the tip), or 'density' for material.density",
                **POS,
            ),
        },
        "box": {
            "span": _f(0.1, "length", "radial length", **POS),
            "chord": _f(0.03, "length", "chord", **POS),
            "thickness": _f(0.003, "length", "thickness", **POS),
            "hub_radius": _f(0.0, "length", "radius of the root face", **NONNEG),
            **_BLADE_MESH,
        },
        "naca": {
            "code": Spec(S, "0012", doc="NACA 4-digit code"),
            "span": _f(0.1, "length", "radial length", **POS),
            "root_chord": _f(0.05, "length", "root chord", **POS),
            "tip_chord": _f(0.035, "length", "tip chord", **POS),
            "twist": _f(20.0, "angle", "tip twist relative to the root", lo=-90.0, hi=90.0),
            "n_sections": Spec(I, 5, lo=2, hi=50, doc="lofted sections"),
            "hub_radius": _f(0.0, "length", "radius of the root section", **NONNEG),
            "stacking": _f(0.25, "none", "chord fraction of the twist axis", lo=0.0, hi=1.0),
            "n_points": Spec(I, 40, lo=4, hi=400, doc="points per section side"),
            **_BLADE_MESH,
        },
        "sections": {
            "path": Spec(S, None, doc="folder of section files (relative to the scene file)"),
            "files": Spec("strs", None, doc="section files hub to tip (instead of path)"),
            "pattern": Spec(S, "*.csv", doc="glob pattern inside path"),
            "length_unit": Spec(C, "cm", choices=UNITS_LEN, doc="unit of the coordinates"),
            "axis": Spec(C, "x", choices=AXES, doc="machine rotation axis"),
            "interpolate": Spec(B, False, doc="interpolating splines instead of B-splines"),
            "ruled": Spec(B, False, doc="ruled loft"),
            **_BLADE_MESH,
        },
        "mesh": {
            "path": Spec(
                S,
                REQUIRED,
                doc="mesh file (.msh, .inp, .vtu); '{shared}/' is the "
                "reference-data folder, other relative paths start at the scene file",
            ),
            "length_unit": Spec(
                C,
                None,
                choices=UNITS_LEN,
                doc="unit of the coordinates (required for Abaqus/CalculiX decks; default m)",
            ),
            "axis": Spec(C, None, choices=AXES, doc="rotation axis (default: stored or z)"),
            "tip": Spec(S, None, doc="node group of the tip face, or 'detect'"),
        },
    },
)

MATERIAL = {
    "young": _f(110e9, "pressure", "Young's modulus", **POS),
    "poisson": _f(
        0.3,
        "none",
        "Poisson's ratio (ignored by the 1D bar)",
        lo=-1.0,
        hi=0.5,
        lo_open=True,
        hi_open=True,
    ),
    "density": _f(4500.0, "density", "mass density (inertia in 3D; heat capacity always)", **POS),
    "specific_heat": _f(585.0, "specific_heat", "specific heat capacity c", **POS),
    "conductivity": _f(3.35, "conductivity", "thermal conductivity", **NONNEG),
    "expansion": _f(8.6e-6, "expansion", "linear thermal expansion coefficient"),
    "reference_temperature": _f(293.15, "temperature", "ambient temperature T0", **POS),
}

BOUNDARY = {
    "root": Spec(
        S,
        None,
        doc="node group clamped and held at ambient (default 'root'; "
        "Abaqus decks: the *BOUNDARY nodes)",
    ),
    "clamped": Spec(B, True, doc="bar only: clamp the root (false: free bar)"),
}

CASING = Variant(
    "kind",
    default="concentric",
    doc="rigid casing profile swept at the rotation speed (femrub.contact.casing)",
    variants={
        "concentric": {"clearance": _f(1e-4, "length", "radial clearance", **NONNEG)},
        "lobed": {
            "clearance": _f(1e-4, "length", "mean radial clearance", **NONNEG),
            "depth": _f(0.0, "length", "lobe depth (intrudes where depth > clearance)", **NONNEG),
            "lobes": Spec(I, 2, lo=1, hi=100, doc="number of lobes"),
            "phase": _f(0.0, "angle", "angular position of the first lobe"),
        },
        "two-lobe": {
            "mean_gap": _f(0.356e-3, "length", "g_m of Piollet et al. (2019)", **POS),
            "width": _f(0.15, "none", "lobe width w", **POS),
        },
    },
)

ABRADABLE = {
    "thickness": _f(0.0, "length", "coating thickness e (0: no coating, rigid casing)", **NONNEG),
    "yield": _f(0.0, "force", "force per contact at which the coating yields and is cut", **NONNEG),
    "n_angle": Spec(I, 360, lo=1, hi=100_000, doc="wear-map cells around the casing"),
    "n_axial": Spec(I, 16, lo=1, hi=10_000, doc="wear-map cells along the axis"),
    "footprint": _f(
        0.0,
        "length",
        "circumferential width of the tip each contact stands for: it reads the "
        "worn surface as its mean over that width and cuts it to its reach there (0: a point)",
        **NONNEG,
    ),
}

CASING_HEAT = {
    "thickness": _f(
        0.0, "length", "casing wall thickness b of the lumped thermal model (0: off)", **NONNEG
    ),
    "density": _f(7800.0, "density", "casing wall density", **POS),
    "specific_heat": _f(460.0, "specific_heat", "casing wall specific heat", **POS),
    "conductivity": _f(15.0, "conductivity", "casing wall conductivity", **POS),
    "expansion": _f(12e-6, "expansion", "casing wall expansion (closes the gap by α b T)"),
    "n_angle": Spec(I, 360, lo=1, hi=100_000, doc="casing cells around (without a coating)"),
    "n_axial": Spec(I, 16, lo=1, hi=10_000, doc="casing cells along the axis (without a coating)"),
}

CONTACT = {
    "abradable": ABRADABLE,
    "group": Spec(S, "contact", doc="node group of the contact points ('tip': every tip node)"),
    "nodes": Spec("ints", None, doc="node numbers of the contact points (mesh files)"),
    "casing": CASING,
    "spread": Spec(
        C,
        "patch",
        choices=("patch", "node"),
        doc="3D: a contact acts on its share of the tip face (mean displacement, force "
        "spread like its heat; femrub.contact.patches) or on its node alone",
    ),
    "restitution": _f(0.0, "none", "Newton's restitution coefficient e", lo=0.0, hi=1.0),
    "slip_direction": Spec(
        C,
        "rotation",
        choices=("rotation", "reversed"),
        doc="expert, a verification device: the casing slides past the blade against its "
        "rotation (rotation), or the other way while the lobe phase stays (reversed: to "
        "cross-check codes that prescribe the sliding velocity apart from the phase)",
    ),
    "friction": _f(
        0.0, "none", "3D: Coulomb coefficient μ (tangential force |λ_t| <= μ λ)", **NONNEG
    ),
    "heat_law": Spec(
        C,
        "auto",
        choices=("auto", "alpha", "power"),
        doc="frictional heat: 'alpha' (heat_partition α λ), 'power' (heat_partition × friction "
        "power |λ_t · v_slip|); 'auto': alpha on the bar, power on a blade",
    ),
    "heat_coefficient": _f(
        0.0, "velocity", "bar: α of the heat input heat_partition α λ", **NONNEG
    ),
    "heat_partition": Spec(
        F,
        "auto",
        "none",
        choices=("auto", "effusivity"),
        doc="fraction η of the frictional power that enters the blade (auto: 1, or from the "
        "effusivities of blade and casing with contact.casing_heat)",
        lo=0.0,
        hi=1.0,
    ),
    "casing_heat": CASING_HEAT,
    "reach": Spec(
        F,
        "auto",
        "length",
        choices=("auto", "all"),
        doc="keep a contact point when its smallest gap over a revolution is <= reach",
        **NONNEG,
    ),
    "reach_margin": _f(0.0, "length", "added to the automatic reach", **NONNEG),
    "clearance": Spec(
        C,
        "running",
        choices=("running", "cold"),
        doc="casing clearances are measured from the tip at speed (running) or at rest "
        "(cold: the centrifugal tip growth closes them)",
    ),
    "gap_reference": Spec(
        C,
        "per-node",
        choices=("per-node", "outermost"),
        doc="casing clearance at every contact point, or at the outermost one",
    ),
}

_AMPLITUDE = _f(REQUIRED, "force", "force amplitude (total over the tip face)")
_DIRECTION = Spec("vec3", "radial", "none", choices=("radial",), doc="3D: force direction")
TIP_FORCE = Variant(
    "law",
    default="none",
    doc="force on the tip (bar: tip node; 3D: spread over the tip face)",
    variants={
        "none": {},
        "constant": {"amplitude": _AMPLITUDE, "direction": _DIRECTION},
        "sin": {
            "amplitude": _AMPLITUDE,
            "direction": _DIRECTION,
            "frequency": Spec(
                F,
                "rotation",
                "angular_speed",
                choices=("rotation",),
                doc="ω of amplitude sin(ω t + phase); 'rotation': engine_order Ω",
                **POS,
            ),
            "engine_order": Spec(I, 1, lo=1, hi=1000, doc="k in ω = k Ω"),
            "phase": _f(0.0, "angle", "phase"),
        },
        "ramp": {
            "amplitude": _AMPLITUDE,
            "direction": _DIRECTION,
            "ramp_time": _f(REQUIRED, "time", "time to reach the amplitude", **POS),
        },
    },
)

LOADS = {
    "rotation_speed": _f(0.0, "angular_speed", "rotation speed Ω", **NONNEG),
    "rotation_direction": Spec(
        C,
        "auto",
        choices=("auto", "counterclockwise", "clockwise"),
        doc="direction of rotation about the machine axis (right-hand rule); the casing "
        "phase σ Ω t + φ and the casing's sliding velocity −σ Ω r follow it (auto: the "
        "blade moves towards its pressure side, read from the tip section's camber; "
        "counterclockwise where that cannot be derived, e.g. the bar or a symmetric section)",
    ),
    "centrifugal": Spec(
        C,
        "auto",
        choices=("auto", "off", "linear", "nonlinear"),
        doc="3D: static centrifugal prestress at Ω, its geometric stiffness and spin "
        "softening (auto: nonlinear when Ω > 0; the bar: off)",
    ),
    "tip_force": TIP_FORCE,
}

PHYSICS = {
    "thermal": Spec(
        C,
        "auto",
        choices=("auto", "on", "off"),
        doc="temperature dofs (auto: only when there is a heat source)",
    ),
    "coupling": Spec(
        C,
        "auto",
        choices=("auto", "none", "paper", "physical"),
        doc="thermal stresses (auto: paper for the bar, physical in 3D)",
    ),
    "beta": _f(-4.5e-7, "length_per_K", "β of the paper coupling K^uθ = β K^uu"),
    "strain_heating": Spec(B, False, doc="strain-rate heating C^θu = −T0 (K^uθ)ᵀ"),
    "rayleigh": Spec("pair", [0.0, 0.0], doc="Rayleigh damping [a (1/s), b (s)]", lo=0.0),
    "damping_ratio": _f(
        0.0,
        "none",
        "modal damping ratio ζ, as Rayleigh damping with ratio ζ at damping_modes "
        "(instead of rayleigh)",
        lo=0.0,
        hi=1.0,
        hi_open=True,
    ),
    "damping_modes": Spec(
        "ints", [1, 5], doc="the two clamped modes (1-based) damped exactly at damping_ratio"
    ),
    "order": Spec(I, 2, lo=1, hi=2, doc="3D displacement element order"),
    "lumping": Spec(
        C,
        "auto",
        choices=("auto", "row-sum", "hrz", "consistent"),
        doc="mass lumping (auto: row-sum for P1, HRZ for P2)",
    ),
    "conduction": Spec(
        C,
        "galerkin",
        choices=("galerkin", "monotone"),
        doc="heat conduction matrix (monotone: M-matrix by discrete upwinding, no undershoot)",
    ),
}

TOP = {
    "name": Spec(S, "scene", doc="scene name"),
    "description": Spec(S, "", doc="one-line description"),
}

SCHEMA: dict = {
    "geometry": GEOMETRY,
    "material": MATERIAL,
    "boundary": BOUNDARY,
    "contact": CONTACT,
    "loads": LOADS,
    "physics": PHYSICS,
    "scheme": SCHEME,
    "reduction": REDUCTION,
    "outputs": OUTPUTS,
    "limits": LIMITS,
    "rotor": ROTOR,
    "casing": CASING_SECTION,
}


def schema_rows(table=None, prefix: str = ""):
    """Yield ``(dotted key, Spec or Variant, variant name or None)`` for every key."""
    table = {**TOP, **SCHEMA} if table is None else table
    for key, spec in table.items():
        dotted = f"{prefix}{key}"
        if isinstance(spec, Variant):
            yield f"{dotted}.{spec.selector}", spec, None
            for choice in spec.variants:
                for sub, s, _ in schema_rows(spec.keys_for(choice), f"{dotted}."):
                    yield sub, s, choice
        elif isinstance(spec, dict):
            yield from schema_rows(spec, f"{dotted}.")
        else:
            yield dotted, spec, None
            if spec.items:  # an array of tables: each table's keys
                yield from schema_rows(spec.items, f"{dotted}[].")
