"""
A free bar hits a wall: the exact solution
==========================================

A titanium bar (0.3 m, 1 mm²) flies at v0 = 0.1 m/s towards a rigid obstacle 10 µm away.
The continuous bar's answer is known in closed form (d'Alembert; Doyen, Ern & Piperno 2011):
the contact lasts 2L/c with the constant force ρ c A v0, and the bar leaves at −v0. The
θ-method with the Newton impact law approaches it as the mesh and the step are refined
together at a fixed Courant number ν = c h / Δx.
"""

import os

import matplotlib.pyplot as plt
import numpy as np

import femrub as fr
from femrub.cases.analytic import bar_impact
from femrub.cases.bar import impact_bar_model

E, RHO, AREA, LENGTH, V0, GAP = 110e9, 4500.0, 1e-6, 0.3, 0.1, 1e-5  # SI
exact = bar_impact(LENGTH, E, RHO, AREA, V0, GAP)
wave_speed = np.sqrt(E / RHO)
meshes = (25, 100) if os.environ.get("FEMRUB_DOCS_QUICK") else (25, 100, 400)

fig, ax = plt.subplots(figsize=(7, 4))
for n in meshes:
    model = impact_bar_model(
        n, velocity=V0, gap=GAP, young=E, density=RHO, area=AREA, length=LENGTH
    )
    h = 0.5 * (LENGTH / n) / wave_speed  # ν = 0.5
    res = fr.ThetaMethod(model, h=h).run(1.5 * (exact.contact_start + exact.contact_duration))
    start, end = res.contact_phases()[0][0], res.contact_phases()[-1][1]
    print(f"{n:4d} elements: contact {end - start:.3e} s (exact {exact.contact_duration:.3e} s)")
    ax.plot(res.t * 1e3, res.force[:, 0], label=f"θ-method, {n} elements")

# %%
# The exact force is a plateau of height ρ c A v0 over [t_c, t_c + 2L/c].
t_c, duration = exact.contact_start, exact.contact_duration
plateau = exact.contact_force  # ρ c A v0
ax.plot(
    np.array([0, t_c, t_c, t_c + duration, t_c + duration, 1.5 * (t_c + duration)]) * 1e3,
    [0, 0, plateau, plateau, 0, 0],
    "k--",
    label="exact (d'Alembert)",
)
ax.set_xlabel("time (ms)")
ax.set_ylabel("contact force (N)")
ax.legend()
fig.tight_layout()
plt.show()
