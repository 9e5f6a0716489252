"""NASA Rotor 37 blade rubbing a two-lobe casing, thermal coupling on, reduced model.

The built-in scene ``rotor37`` (CalculiX blade of ``../shared/data/rotor37-fe-mesh``,
GPL-3.0, mm, 16 tip contact nodes) with the set-up of Piollet, Nyssen & Batailly (J. Sound
Vib. 460 (2019) 114878): two-lobe casing of mean gap 0.356 mm, Ω = 1344 rad/s, Coulomb
friction μ = 0.15 (frictional heat ``η μ Ω r λ``, η = ``contact.heat_partition``), 0.5 %
modal damping (Rayleigh, modes 1 and 5), 1000 steps per revolution. Material: E = 210 GPa,
ν = 0.3, ρ = 9000 kg/m³ (blade.inp); thermal properties of a steel (c = 460 J/(kg K),
k = 15 W/(m K), α_th = 12e-6 1/K; not in the source deck). A tip temperature rise of
1000 K is the physical stop criterion. Writes ``out/rotor37/`` (or ``$FEMRUB_OUT/rotor37``):
history, summary.json, signals.png, vtk/rub.pvd and snapshot.png.

Run: ``python examples/rotor37_rub.py [REVOLUTIONS [HEAT_PARTITION]]``. Without the
reference data it prints a message and sets ``available = False``.
"""

import math
import os
import sys
from pathlib import Path

from femrub.app import run_scene
from femrub.geometry import shared_data_dir
from femrub.scene import load_scene

OMEGA = 1344.0  # rad/s
STEPS_PER_REV = 1000
args = sys.argv[1:] if __name__ == "__main__" else []
REVOLUTIONS = float(args[0]) if args else 5.0
HEAT_PARTITION = float(args[1]) if len(args) > 1 else 1.0
OUT = Path(os.environ.get("FEMRUB_OUT", "out")) / "rotor37"

available = (Path(shared_data_dir()) / "rotor37-fe-mesh" / "blade.inp").is_file()
if not available:
    print("Rotor 37 data not found (../shared/data or FEMRUB_SHARED_DATA): example skipped.")
else:
    period = 2.0 * math.pi / OMEGA
    scene = load_scene(
        "rotor37",
        {
            "material.young": "210 GPa", "material.poisson": 0.3, "material.density": 9000.0,
            "material.specific_heat": 460.0, "material.conductivity": 15.0,
            "material.expansion": 12e-6,
            "contact.casing.kind": "two-lobe", "contact.friction": 0.15,
            "contact.heat_partition": HEAT_PARTITION,
            "loads.rotation_speed": OMEGA, "physics.damping_ratio": 0.005,
            "scheme.h": period / STEPS_PER_REV, "scheme.t_end": REVOLUTIONS * period,
            "reduction.n_uv": 20, "reduction.n_theta": 20,
            "outputs.vtk_stride": max(1, int(REVOLUTIONS * STEPS_PER_REV) // 40),
            "limits.tip_temperature": 1000.0,
        },
    )  # fmt: skip
    results, sim = run_scene(scene, OUT, overwrite=True, progress=__name__ == "__main__")
    fe_dofs = sim.full.info["fe_dofs"]
    state_dofs, reduced_dofs = sim.full.n_dofs, sim.model.n_dofs
    status = results.status
    max_force = float(results.force.max())

if __name__ == "__main__" and available:
    print(f"FE dofs {fe_dofs}, first-order state {state_dofs}, reduced {reduced_dofs}")
    print({k: round(v, 2) for k, v in results.info["timings"].items()})
    print(f"status {status}: {results.message}; max contact force {max_force:.1f} N")
    print(f"results in {OUT}/ (open vtk/rub.pvd in ParaView)")
