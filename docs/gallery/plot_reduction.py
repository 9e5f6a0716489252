"""
Reduced models of the bar: Craig–Bampton sizes
==============================================

The thermoelastic Craig–Bampton reduction (paper Sec. 2, Eqs. 10–15) keeps the contact dof
(the bar's tip), ``n_uv`` first-order mechanical shapes and ``n_θ`` thermal modes. One
reductor computes the bases once for its largest sizes; ``reduce(n_uv, n_θ)`` then gives any
smaller model as a block of them. The paper's RM1 keeps (3, 12) and RM2 (2, 5), against 38
and 19 interior coordinates in the full bar. Here the reductor is built as scenes build it: the
static shapes' inertia in the left basis (``projection="static-mass"``) and one pair of
thermal shapes per heat input (``thermal="inputs"``), which keeps the heat balance.
"""

import os

import matplotlib.pyplot as plt

import femrub as fr
from femrub.reduction import ThermoelasticCraigBampton

T_END = 0.1 if os.environ.get("FEMRUB_DOCS_QUICK") else 0.4  # s
full = fr.bar_model(alpha=3.0)
reductor = ThermoelasticCraigBampton(full, 8, 12, projection="static-mass", thermal="inputs")

runs = {"full (60 dofs)": fr.ThetaMethod(full, h=1e-4).run(T_END)}
for n_uv, n_theta in [(2, 5), (3, 12), (8, 12)]:
    model = reductor.reduce(n_uv, n_theta)
    runs[f"CB({n_uv}, {n_theta}): {model.n_dofs} dofs"] = fr.ThetaMethod(model, h=1e-4).run(T_END)

# %%
# Each reduced run is judged as the full one is: ``ok`` only when its energy and heat
# balances hold (otherwise ``inaccurate``, with the reason in ``res.message``).
for label, res in runs.items():
    print(f"{label:24s} {res.status:4s} first contact {res.first_contact_time():.5f} s")

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
for label, res in runs.items():
    top.plot(res.t, res.signal("tip_displacement") * 1e3, label=label)
    bottom.plot(res.t, res.signal("tip_temperature"), label=label)
top.set_ylabel("tip displacement (mm)")
bottom.set_ylabel("tip temperature (K)")
bottom.set_xlabel("time (s)")
top.legend(fontsize="small")
fig.tight_layout()
plt.show()
