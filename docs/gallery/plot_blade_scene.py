"""
A 3D blade from a scene, and its results folder
===============================================

The built-in scene ``twisted-naca`` (``femrub scene show twisted-naca``) describes a twisted
NACA 0012 blade meshed with gmsh, rubbing a casing with three lobes at 1500 rad/s, with
frictional heating and thermal expansion. A scene is validated when it is loaded; keys can be
changed with dotted names, as ``femrub run --set`` does. Here the model is reduced to fixed
sizes and P1 elements so that the example runs in seconds.

``run_scene`` writes the results folder that other tools read: ``summary.json`` (status,
sizes, forces, balances, timings) and ``history.npz`` (time, per-contact arrays,
``signal_*``), SI units.
"""

import json
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from femrub.app import run_scene
from femrub.scene import load_scene

changes = {
    "scheme.t_end": 2e-3 if os.environ.get("FEMRUB_DOCS_QUICK") else 1e-2,  # s
    "physics.order": 1,
    "reduction.method": "craig-bampton",
    "reduction.n_uv": 16,
    "reduction.n_theta": 12,
    "outputs.vtk_stride": 0,  # no ParaView series here
}
scene = load_scene("twisted-naca", changes)
out = Path(tempfile.mkdtemp()) / "twisted-naca-out"
results, built = run_scene(scene, out)

# %%
# ``summary.json`` holds the verdict and the key numbers of the run.
summary = json.loads((out / "summary.json").read_text())
for key in ("status", "n_full", "n_dofs", "n_contacts", "steps", "max_contact_force"):
    print(f"{key:18s} {summary[key]}")

# %%
# ``history.npz`` holds the time series: the normal force of each contact and the signals.
history = np.load(out / "history.npz")
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
top.plot(history["t"] * 1e3, history["normal_force"])
top.set_ylabel("normal force per contact (N)")
bottom.plot(history["t"] * 1e3, history["signal_tip_temperature"])
bottom.set_ylabel("tip temperature rise (K)")
bottom.set_xlabel("time (ms)")
fig.tight_layout()
plt.show()
