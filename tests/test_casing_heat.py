"""Frictional heat into the casing: lumped wall cells, expansion closing the gap."""

import json
import math

import pytest

from femrub.app.run import run_scene
from femrub.contact.abradable import CasingGrid
from femrub.contact.casing_heat import CasingHeat, effusivity_partition
from femrub.scene import load_scene

E, A, L = 110e9, 1e-6, 0.30
K_TIP = E * A / L


def test_effusivity_partition():
    eta = effusivity_partition((3.35, 4500.0, 585.0), (15.0, 7800.0, 460.0))
    eb, ec = math.sqrt(3.35 * 4500 * 585), math.sqrt(15 * 7800 * 460)
    assert eta == pytest.approx(eb / (eb + ec))


def test_lumped_cell_step_response():
    """Constant power q into one cell: T = q/G (1 − e^{−t/τ}), then free cooling."""
    grid = CasingGrid([0.0], [0.0], 0.3, 0.0, n_angle=1, n_axial=1)
    heat = CasingHeat(grid, 2e-3, 100.0, 100.0, 0.5, 1e-4, partition=0.5, alpha=[3.0])
    G = 0.5 * grid.cell_area[0] / 2e-3
    h, P = 1e-3, 2e-3  # impulse per step: λ = 2 N, power (1 − η)/η α λ = 6 W
    for k in range(1, 201):
        heat.update(k * h, heat.power_per_impulse * P, h)  # J over the step
    t = 200 * h
    assert heat.temperature_at(t)[0] == pytest.approx(6.0 / G * (1 - math.exp(-t / heat.tau)))
    T1 = heat.temperature_at(t + 0.05)[0]
    assert T1 == pytest.approx(heat.temperature_at(t)[0] * math.exp(-0.05 / heat.tau))
    assert heat.closure_at(t)[0] == pytest.approx(1e-4 * 2e-3 * heat.temperature_at(t)[0])
    assert heat.heat_in == pytest.approx(200 * 6.0 * h)


SCENE = """
name = "bar-casing-heat"
[geometry]
kind = "bar"
n_elements = 10
[contact]
casing = { kind = "concentric", clearance = "5 um" }
heat_coefficient = 3.0
heat_partition = 0.5

[contact.casing_heat]
thickness = 2e-3
density = 100.0
specific_heat = 100.0
conductivity = 0.5
expansion = 1e-4
n_angle = 1
n_axial = 1
[loads]
tip_force = { law = "ramp", amplitude = 7.0, ramp_time = 0.05 }
[physics]
coupling = "none"
damping_ratio = 0.05
damping_modes = [1, 2]
[scheme]
name = "theta"
h = 2e-5
t_end = 0.5
[outputs]
plots = false
"""


def test_hot_casing_closes_the_gap_to_the_analytic_steady_force(tmp_path):
    """Steady state: λ = (F − k d) / (1 − k β), β = α_c b (1 − η) α / G (the casing's own
    expansion pushes the bar back in proportion to the force that heats it). The cell's
    time constant with that feedback is τ / (1 − k β) ≈ 0.1 s: by 0.5 s the force is within
    0.3 % of its steady value."""
    path = tmp_path / "bar.toml"
    path.write_text(SCENE)
    res, built = run_scene(load_scene(str(path)), tmp_path / "out")
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    grid = built.model.contact.casing_heat.grid
    G = 0.5 * grid.cell_area[0] / 2e-3
    beta = 1e-4 * 2e-3 * 0.5 * 3.0 / G
    expected = (7.0 - K_TIP * 5e-6) / (1 - K_TIP * beta)
    assert res.force.sum(axis=1)[-1] == pytest.approx(expected, rel=0.01)
    assert summary["max_casing_temperature"] > 0 and summary["casing_heat_in"] > 0
    assert (tmp_path / "out" / "casing_temperature.csv").exists()
