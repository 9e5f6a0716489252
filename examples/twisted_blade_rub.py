"""A twisted NACA blade rubbing a lobed casing, thermal coupling on, written to VTK.

Meshes a twisted, tapered NACA 0012 blade with gmsh (:func:`femrub.geometry.naca_blade`,
contact nodes embedded on the tip camber line), builds its first-order thermoelastic model
(:func:`femrub.model.rub.solid_model`: P2 displacement, P1 temperature, physical coupling,
frictional heat ``μ Ω r λ`` at the contacts) facing a rigid casing with three lobes that
intrude by 20 µm, reduces it (thermoelastic Craig–Bampton, paper Sec. 2), integrates with the
θ-method and writes the results folder (:func:`femrub.output.run_folder.run_to_folder`): history,
summary, plots and a ParaView series ``vtk/rub.pvd``. About 10 s.

Run: ``python examples/twisted_blade_rub.py`` (writes ``twisted-blade-out/``, or the folder
in ``$FEMRUB_EXAMPLE_OUT``). The same case as a scene: ``femrub run twisted-naca``.
Results are module-level names that the tests import.
"""

import os
from pathlib import Path

import numpy as np

import femrub as fr
from femrub.contact.casing import Lobed
from femrub.geometry import naca_blade
from femrub.model.rub import solid_model
from femrub.output.run_folder import run_to_folder
from femrub.reduction import craig_bampton_thermal

OUT = Path(os.environ.get("FEMRUB_EXAMPLE_OUT", "twisted-blade-out"))
OMEGA = 1500.0  # rad/s
H, T_END = 2e-6, 6e-3  # s

blade = naca_blade(
    "0012",
    span=0.1,
    root_chord=0.05,
    tip_chord=0.035,
    twist=20.0,
    n_sections=3,
    hub_radius=0.2,
    h=0.012,
    n_contact=5,
)
material = fr.Material(
    young=110e9,
    rho=4500.0,
    poisson=0.3,
    rho_c=4500.0 * 585.0,
    conductivity=7.0,
    expansion=8.6e-6,
)
casing = Lobed(clearance=20e-6, depth=40e-6, lobes=3)
full, fields = solid_model(
    blade,
    material,
    casing=casing,
    rotation_speed=OMEGA,
    friction=0.02,
    coupling="physical",
    thermal=True,
)
# the scene's reduction: contact dofs with the inertia of their static shapes, a thermal
# basis of the heat inputs (the heat balance exact; docs/reduction.md, sections 8 and 10)
model, reductor = craig_bampton_thermal(
    full, n_uv=24, n_theta=20, projection="static-mass", thermal="inputs"
)
results = run_to_folder(
    fr.ThetaMethod(model, h=H),
    T_END,
    OUT,
    fields=fields,
    vtk_stride=100,
    overwrite=True,
    snapshot=False,
    inputs={"example": "twisted_blade_rub", "casing": casing.as_dict()},
)

n_tets = blade.n_tets
full_dofs, reduced_dofs = full.n_dofs, model.n_dofs
max_contact_force = float(results.force.max())
max_temperature = float(np.abs(results.signals["tip_temperature"]).max())
first_contact_time = results.first_contact_time()
pvd = OUT / "vtk" / "rub.pvd"

if __name__ == "__main__":
    print(blade.summary())
    print(
        f"model: {full_dofs} -> {reduced_dofs} dofs, status {results.status}, "
        f"first contact {first_contact_time:.4g} s, max force {max_contact_force:.4g} N, "
        f"max tip temperature rise {max_temperature:.4g} K"
    )
    print(f"open {pvd} in ParaView")
