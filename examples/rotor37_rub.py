"""NASA Rotor 37 blade rubbing a two-lobe casing, thermal coupling on, reduced model.

The CalculiX blade of ``../shared/data/rotor37-fe-mesh`` (GPL-3.0, mm) with its 16 tip
contact nodes, the two-lobe casing of Piollet, Nyssen & Batailly (J. Sound Vib. 460 (2019)
114878: mean gap 0.356 mm), Ω = 1344 rad/s, Coulomb friction μ = 0.15 (frictional heat
``η μ Ω r λ``), 0.5 % modal damping (Rayleigh, modes 1 and 5), 1000 steps per revolution.
Material: E = 210 GPa, ν = 0.3, ρ = 9000 kg/m³ (blade.inp); thermal properties of a steel
(c = 460 J/(kg K), k = 15 W/(m K), α_th = 12e-6 1/K; not in the source deck). The model
(P2 displacement, P1 temperature: about 99,000 FE dofs) is reduced with the thermoelastic
Craig–Bampton basis and integrated with the θ-method; a tip temperature rise of 1000 K is
the physical stop criterion. Writes ``out/rotor37/``: history.csv/.npz, summary.json,
signals.png, vtk/rub.pvd (+ .vtu, reconstructed full fields) and snapshot.png.

Run: ``python examples/rotor37_rub.py [REVOLUTIONS]``. Without the reference data it prints
a message and sets ``available = False``.
"""

import math
import os
import sys
import time
from pathlib import Path

import femrub as fr
from femrub.contact.casing import TwoLobePiollet
from femrub.geometry import read_rotor37_mesh, shared_data_dir
from femrub.model.rub import solid_model
from femrub.output.run_folder import run_to_folder
from femrub.reduction import craig_bampton_thermal

OMEGA = 1344.0  # rad/s
FRICTION = 0.15
HEAT_PARTITION = float(os.environ.get("FEMRUB_HEAT_PARTITION", 1.0))
STEPS_PER_REV = 1000
REVOLUTIONS = float(sys.argv[1]) if len(sys.argv) > 1 and __name__ == "__main__" else 5.0
N_UV, N_THETA = 20, 20
OUT = Path(os.environ.get("FEMRUB_OUT", "out")) / "rotor37"

try:
    data = shared_data_dir()
    available = (Path(data) / "rotor37-fe-mesh" / "blade.inp").is_file()
except Exception:  # noqa: BLE001 - any failure to locate the data means: skip
    available = False

timings = {}
if not available:
    print("Rotor 37 data not found (../shared/data or FEMRUB_SHARED_DATA): example skipped.")
else:
    t0 = time.perf_counter()
    blade = read_rotor37_mesh()
    timings["read"] = time.perf_counter() - t0
    material = fr.Material(
        young=210e9,
        poisson=0.3,
        rho=9000.0,
        rho_c=9000.0 * 460.0,
        conductivity=15.0,
        expansion=12e-6,
    )
    t0 = time.perf_counter()
    full, fields = solid_model(
        blade,
        material,
        casing=TwoLobePiollet(),
        rotation_speed=OMEGA,
        friction=FRICTION,
        heat_partition=HEAT_PARTITION,
        damping_ratio=0.005,
    )
    timings["model"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    model, reductor = craig_bampton_thermal(full, N_UV, N_THETA)
    timings["reduction"] = time.perf_counter() - t0
    period = 2.0 * math.pi / OMEGA
    h = period / STEPS_PER_REV
    stepper = fr.ThetaMethod(model, h)
    t0 = time.perf_counter()
    results = run_to_folder(
        stepper,
        REVOLUTIONS * period,
        OUT,
        fields=fields,
        vtk_stride=max(1, int(REVOLUTIONS * STEPS_PER_REV) // 40),
        inputs={
            "omega": OMEGA,
            "friction": FRICTION,
            "heat_partition": HEAT_PARTITION,
            "revolutions": REVOLUTIONS,
            "n_uv": N_UV,
            "n_theta": N_THETA,
        },
        limits={"tip_temperature": 1000.0},
        progress=__name__ == "__main__",
        overwrite=True,
    )
    timings["run"] = time.perf_counter() - t0
    fe_dofs = full.info["fe_dofs"]
    state_dofs, reduced_dofs = full.n_dofs, model.n_dofs
    status = results.status
    max_force = float(results.force.max())

if __name__ == "__main__" and available:
    print(f"FE dofs {fe_dofs}, first-order state {state_dofs}, reduced {reduced_dofs}")
    print({k: round(v, 2) for k, v in timings.items()}, full.info["timings"])
    print(f"status {status}: {results.message}; max contact force {max_force:.1f} N")
    print(f"results in {OUT}/ (open vtk/rub.pvd in ParaView)")
