"""NASA Rotor 37 blade rubbing a two-lobe casing: the built-in scene ``rotor37``.

The published set-up of Piollet, Nyssen & Batailly (J. Sound Vib. 460 (2019) 114878) on the
CalculiX blade of ``../shared/data/rotor37-fe-mesh`` (GPL-3.0, mm, 16 tip contact nodes):
E = 210 GPa, ν = 0.3, ρ = 9000 kg/m³, 0.5 % modal damping, two-lobe rigid casing of mean
gap 0.356 mm, Ω = 1344 rad/s, Coulomb friction μ = 0.15, 1000 steps per revolution,
50 revolutions, mechanical, reduced model (docs/rotor37.md). Writes ``out/rotor37/`` (or
``$FEMRUB_OUT/rotor37``): history, summary.json, response/spectrum/contact-force plots and
vtk/rub.pvd.

Run: ``python examples/rotor37_rub.py [REVOLUTIONS]`` (default: the scene's 50). Without
the reference data it prints a message and sets ``available = False``.
"""

import math
import os
import sys
from pathlib import Path

from femrub.app import run_scene
from femrub.geometry import shared_data_dir
from femrub.scene import load_scene

args = sys.argv[1:] if __name__ == "__main__" else []
OUT = Path(os.environ.get("FEMRUB_OUT", "out")) / "rotor37"

available = (Path(shared_data_dir()) / "rotor37-fe-mesh" / "blade.inp").is_file()
if not available:
    print("Rotor 37 data not found (../shared/data or FEMRUB_SHARED_DATA): example skipped.")
else:
    scene = load_scene("rotor37")
    omega = scene["loads"]["rotation_speed"]
    if args:  # a shorter (or longer) run of the same set-up
        scene = scene.with_changes({"scheme.t_end": float(args[0]) * 2 * math.pi / omega})
    results, sim = run_scene(scene, OUT, overwrite=True, progress=__name__ == "__main__")
    fe_dofs, reduced_dofs = sim.full.info["fe_dofs"], sim.model.n_dofs
    status = results.status
    revolutions = results.t[-1] * omega / (2 * math.pi)
    max_force = float(results.force.max())

if __name__ == "__main__" and available:
    print(f"FE dofs {fe_dofs}, reduced {reduced_dofs}; {revolutions:.2f} revolutions")
    print({k: round(v, 2) for k, v in results.info["timings"].items()})
    print(f"status {status}: {results.message}; max normal force {max_force:.1f} N")
    print(f"results in {OUT}/ (open vtk/rub.pvd in ParaView)")
