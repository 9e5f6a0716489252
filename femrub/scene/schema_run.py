"""The scene schema of how a scene runs: stepper, reduction, outputs and stop limits.

Part of :data:`femrub.scene.schema.SCHEMA` (``scheme``, ``reduction``, ``outputs``,
``limits``); the signals a model can observe (:data:`SIGNALS`) and their dimensions.
"""

from __future__ import annotations

from ..contact.activation import DEFAULT_FRICTIONAL_RULE, DEFAULT_RULE, FRICTIONAL_RULES, RULES
from .spec import NONNEG, POS, REQUIRED, Spec, Variant
from .spec import float_spec as _f

__all__ = [
    "LIMITS",
    "OUTPUTS",
    "PROBE",
    "PROBE_COMPONENTS",
    "PROBE_QUANTITIES",
    "REDUCTION",
    "probe_names",
    "SCHEME",
    "SIGNALS",
]

I, B, C = "int", "bool", "choice"

SCHEME = Variant(
    "name",
    default="theta",
    doc="time stepper (femrub.steppers)",
    common={
        "h": _f(REQUIRED, "time", "time step", **POS),
        "t_end": _f(REQUIRED, "time", "end time", **POS),
        "step_check": Spec(
            B,
            False,
            doc="also step the model at h/2 and judge the run by the difference "
            "(a-posteriori time-step error, femrub.analysis.step_check; doubles the stepping)",
        ),
        "step_tolerance": _f(
            0.05,
            "none",
            "estimated time-step error above which a checked run is inaccurate",
            lo=0.0,
            hi=1.0,
            lo_open=True,
        ),
    },
    variants={
        "theta": {
            "gamma": _f(0.5, "none", "θ of the θ-method", lo=0.5, hi=1.0),
            "gamma_thermal": _f(
                None,
                "none",
                "θ of the heat-equation rows (default: gamma; 1 damps stiff thermal modes)",
                lo=0.5,
                hi=1.0,
            ),
            "activation": Spec(
                C,
                None,
                choices=RULES,
                doc=f"contact rule (femrub.contact.activation; default {DEFAULT_RULE!r}, "
                f"{DEFAULT_FRICTIONAL_RULE!r} with friction, the only rules with friction: "
                f"{' and '.join(map(repr, FRICTIONAL_RULES))})",
            ),
        },
        "carpenter": {},
        "penalty": {
            "stiffness": _f(REQUIRED, "stiffness", "penalty stiffness", **POS),
            "damping": _f(0.0, "damping", "penalty damping", **NONNEG),
            "method": Spec(C, "Radau", choices=("Radau", "BDF"), doc="implicit integrator"),
        },
        "exponential": {
            "events": Spec(
                B, True, doc="locate contact closings and releases inside the step (exact times)"
            ),
        },
    },
)

REDUCTION = Variant(
    "method",
    default="none",
    doc="thermoelastic Craig-Bampton reduction (paper Sec. 2)",
    common={
        "projection": Spec(
            C,
            "static-mass",
            choices=("static-mass", "petrov-galerkin", "galerkin", "adjoint", "second-order"),
            doc="left basis (static-mass: Petrov-Galerkin with the static shapes' inertia; "
            "second-order: classical Galerkin Craig-Bampton of the mechanics)",
        ),
        "thermal": Spec(
            C,
            "inputs",
            choices=("inputs", "boundary"),
            doc="thermal reduction: one shape pair per heat input, or the heated dofs kept",
        ),
        "tolerance": _f(
            0.05,
            "none",
            "estimated relative error above which a run is inaccurate",
            lo=0.0,
            hi=1.0,
            lo_open=True,
        ),
    },
    variants={
        "none": {},
        "craig-bampton": {
            "n_uv": Spec(I, REQUIRED, lo=0, doc="first-order mechanical shapes"),
            "n_theta": Spec(I, REQUIRED, lo=0, doc="thermal modes"),
        },
        "auto": {
            "target": _f(0.01, "none", "relative error target", lo=0.0, hi=1.0, lo_open=True),
            "modes": Spec(I, 10, lo=1, hi=50, doc="natural frequencies that must meet it"),
            "max_n_uv": Spec(I, 64, lo=2, hi=400, doc="largest n_uv tried"),
            "max_n_theta": Spec(I, 64, lo=0, hi=400, doc="largest n_theta tried"),
        },
    },
)

#: observed signals and their dimension; which exist depends on the geometry
SIGNALS = {
    "tip_displacement": "length",
    "tip_velocity": "velocity",
    "tip_temperature": "temperature",
    "contact_displacement": "length",
    "contact_temperature": "temperature",
    "contact_force": "force",
}

#: what a probe reads, with its dimension (docs/probes.md)
PROBE_QUANTITIES = {"displacement": "length", "velocity": "velocity", "temperature": "temperature"}
#: directions of a probe: global axes, and the machine's axes at the probed node
PROBE_COMPONENTS = ("x", "y", "z", "radial", "axial", "circumferential")

PROBE = {
    "name": Spec(
        "str",
        REQUIRED,
        doc="probe name (letters, digits, '-', '_'): history.npz key probe_<name>, CSV column",
    ),
    "node": Spec(
        I,
        None,
        lo=0,
        doc="the mesh's own node number (a deck's node id, a .msh node tag; box, naca, "
        "sections: the gmsh node tag, as femrub mesh writes it; the bar: the vertex index "
        "from 0 at the root); or give point",
    ),
    "point": Spec(
        "vec3",
        None,
        "length",
        doc="coordinates of the point (the nearest mesh node is probed, its distance reported); "
        "or give node",
    ),
    "quantity": Spec(
        C, "displacement", choices=tuple(PROBE_QUANTITIES), doc="the field read at the node"
    ),
    "component": Spec(
        C,
        None,
        choices=PROBE_COMPONENTS,
        doc="direction of a displacement or velocity: global x, y, z, or radial, axial, "
        "circumferential (axis × radial) about the machine axis at the node; none for "
        "temperature",
    ),
    "blade": Spec(
        I,
        None,
        lo=0,
        choices=("all",),
        doc="a bladed disk (rotor.sectors): the blade s (0 to N - 1) whose node is read, the "
        "sector's node turned by s 2π/N about the axis (unset: blade 0), or 'all': one "
        "history per blade, probe_<name>_blade<s>",
    ),
}


def probe_names(probe: dict, n_blades: int | None = None) -> list[str]:
    """The names a probe table records under (``probe_<name>``): its ``name``, or with
    ``blade = "all"`` on a wheel of ``n_blades`` blades ``<name>_blade<s>`` for
    ``s = 0 .. n_blades − 1``."""
    if probe.get("blade") != "all":
        return [probe["name"]]
    return [f"{probe['name']}_blade{s}" for s in range(n_blades)]


OUTPUTS = {
    "signals": Spec("strs", "all", choices=("all",), doc="history signals kept"),
    "vtk_stride": Spec(I, 0, lo=0, doc="3D: write a VTK frame every that many steps (0: none)"),
    "csv_stride": Spec(
        I,
        1,
        lo=0,
        doc="history.csv: one row every that many steps (contact impulses summed, forces "
        "averaged over the steps between rows; 0: no history.csv, as for the points of a "
        "map); history.npz keeps every step",
    ),
    "history_npz": Spec(
        B,
        True,
        doc="history.npz: every step's signals, gaps, contact forces, energies (false: none, "
        "as for the points of a map; summary.json keeps each signal's and probe's largest "
        "magnitude and root mean square)",
    ),
    "plots": Spec(
        B,
        True,
        doc="the PNG plots of the run (signals, response, spectrum, contact forces, "
        "snapshot of the last VTK frame)",
    ),
    "probes": Spec(
        "tables",
        [],
        doc="one field component at one mesh node, recorded at every step "
        "(history.npz probe_<name>, a CSV column, signals.png); keys below",
        items=PROBE,
    ),
}

LIMITS = {
    name: _f(None, dim, f"stop the run when |{name}| exceeds this", **POS)
    for name, dim in SIGNALS.items()
}
