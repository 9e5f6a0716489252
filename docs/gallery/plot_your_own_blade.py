"""
Your own blade: from airfoil sections to an interaction map
===========================================================

A blade femrub does not know: three cambered sections (NACA 4412, chord tapering from 50 to
35 mm, twisted by 20°) from hub to tip, written as the CSV files a design tool would export.
The scene meshes them with gmsh, puts six contact points on the tip, and faces them with a
three-lobed casing. Four commands then answer the usual questions: how does the tip respond
at the design speed (a probed run), where are the blade's frequencies as it spins (a Campbell
diagram with the centrifugal stiffening), and how does the rub change with speed (a small
interaction map). Every result must come out ``ok``: the example stops otherwise.

The same steps from a shell are ``femrub run my-blade.toml``, ``femrub campbell my-blade.toml
--speeds 0:3000:1000`` and ``femrub sweep my-blade.toml --param
loads.rotation_speed=1000:2000:1000``; the sweep below runs its points in this process
(``--workers 0``), as a script without a ``__main__`` guard must.
"""

import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import femrub as fr
from femrub.app.cli import main as femrub

# the test suite's build (FEMRUB_DOCS_QUICK): a coarser mesh, two Campbell speeds, a shorter
# run, and a map whose first point is the design speed (its models from the run's cache)
QUICK = bool(os.environ.get("FEMRUB_DOCS_QUICK"))
SPEEDS, T_END = ("0,3000", 0.003) if QUICK else ("0:3000:1000", 0.005)  # rad/s, s
MESH = 0.02 if QUICK else 0.012  # m
MAP = "1500:2000:500" if QUICK else "1000:2000:1000"  # rad/s
work = Path(tempfile.mkdtemp(prefix="my-blade-"))
os.environ.setdefault("FEMRUB_CACHE_DIR", str(work / "cache"))  # models shared by the steps

# %%
# Sections: a NACA 4412 (4 % camber at 40 % chord, 12 % thick) at three radii, in mm, the
# machine axis along x, each section in the plane of its radius z = r.


def naca4412(n=30):
    x = 0.5 * (1 - np.cos(np.linspace(0, np.pi, n)))
    half = 0.6 * (0.2969 * np.sqrt(x) - 0.126 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1036 * x**4)
    m, p = 0.04, 0.4
    camber = np.where(
        x < p, m / p**2 * (2 * p * x - x**2), m / (1 - p) ** 2 * (1 - 2 * p + 2 * p * x - x**2)
    )
    return np.vstack(
        [np.column_stack([x, camber + half])[::-1], np.column_stack([x, camber - half])[1:]]
    )


(work / "sections").mkdir()
for k, (radius, chord, twist) in enumerate([(200, 50, 0), (250, 42, 10), (300, 35, 20)]):
    xy = (naca4412() - [0.25, 0.0]) * chord
    a = np.radians(twist)
    xy = xy @ np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    points = np.column_stack([xy, np.full(len(xy), radius)])
    np.savetxt(
        work / "sections" / f"section{k}.csv", points, delimiter=",", header="x,y,z", comments=""
    )
leading_edge = points[np.argmin(xy[:, 0])]  # of the tip section (mm): the probed point
probe_point = ", ".join(f'"{c:.3f} mm"' for c in leading_edge)

# %%
# The scene: the sections meshed by gmsh, titanium, six contact points on the tip camber
# line, a casing with three lobes 50 µm deep, a probe of the tip's leading edge.
scene = f"""
name = "my-blade"
[geometry]
kind = "sections"
path = "sections"
length_unit = "mm"
axis = "x"
h = {MESH}
n_contact = 6
[material]
young = "110 GPa"
poisson = 0.3
density = 4500.0
[contact]
casing = {{ kind = "lobed", clearance = "20 um", depth = "50 um", lobes = 3 }}
friction = 0.1
gap_reference = "outermost"
[loads]
rotation_speed = 1500.0
[physics]
thermal = "off"
[scheme]
h = 2e-6
t_end = {T_END}
[reduction]
method = "craig-bampton"
n_uv = 24
n_theta = 8
[outputs]
vtk_stride = 0
probes = [{{ name = "tip_le", point = [{probe_point}], component = "radial" }}]
"""
(work / "my-blade.toml").write_text(scene)

# %%
# A run at the design speed, 1500 rad/s: the probe's radial displacement and the forces.
assert femrub(["run", str(work / "my-blade.toml"), "-o", str(work / "run"), "-q"]) == 0
run = fr.load_results(work / "run")
assert run.status == "ok", run.message
fig, ax = plt.subplots(1, 2, figsize=(10, 3.5))
ax[0].plot(run.t * 1e3, run.probe("tip_le") * 1e6)
ax[0].set(xlabel="time (ms)", ylabel="tip leading edge, radial (µm)")
ax[1].plot(run.t * 1e3, run.force)
ax[1].set(xlabel="time (ms)", ylabel="contact forces (N)")
fig.tight_layout()

# %%
# The Campbell diagram: the frequencies of the spinning, prestressed blade, checked against
# exact solves (a failed check ends the command with a non-zero status).
assert (
    femrub(
        [
            "campbell",
            str(work / "my-blade.toml"),
            "-o",
            str(work / "campbell"),
            "-q",
            "--speeds",
            SPEEDS,
            "--modes",
            "3",
        ]
    )
    == 0
)
campbell = np.genfromtxt(work / "campbell" / "campbell.csv", delimiter=",", names=True)
fig, ax = plt.subplots(figsize=(6, 4))
for name in [n for n in campbell.dtype.names if n.startswith("f")]:
    ax.plot(campbell["speed_rad_s"], campbell[name], "o-", label=name)
ax.set(xlabel="rotation speed (rad/s)", ylabel="frequency (Hz)")
ax.legend()

# %%
# The interaction map: one run per speed, each judged like the single run.
assert (
    femrub(
        [
            "sweep",
            str(work / "my-blade.toml"),
            "-o",
            str(work / "map"),
            "-q",
            "--workers",
            "0",
            "--param",
            f"loads.rotation_speed={MAP}",
        ]
    )
    == 0
)
points = np.genfromtxt(
    work / "map" / "interaction.csv", delimiter=",", names=True, dtype=None, encoding=None
)
assert (points["status"] == "ok").all(), points["message"]
fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(points["loadsrotation_speed"], points["max_probe_tip_le_m"] * 1e6, "o-")
ax.set(xlabel="rotation speed (rad/s)", ylabel="largest radial tip displacement (µm)")
plt.show()
