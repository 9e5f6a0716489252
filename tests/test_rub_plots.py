"""The contact-force map: the largest force of each cell of rotor angle × revolution."""

import numpy as np
import pytest

import femrub as fr
from femrub.output.rub_plots import contact_force_panel, force_map


def test_the_force_map_puts_each_step_in_its_angle_and_revolution():
    omega = 2 * np.pi * 10.0  # 10 revolutions per second
    t = np.arange(0.0, 0.3, 1e-4)  # 3 revolutions of 1000 steps
    angle = np.mod(omega * t, 2 * np.pi)
    rev = np.floor(omega * t / (2 * np.pi))
    force = np.where(np.abs(np.degrees(angle) - 95.0) < 2.0, 1.0 + rev, 0.0)  # a lobe at 95°
    edges, grid = force_map(t, force, omega, 36)
    assert grid.shape == (3, 36) and np.allclose(edges, [0, 1, 2, 3])
    np.testing.assert_array_equal(np.nanargmax(grid, axis=1), [9, 9, 9])  # the 90-100° cell
    np.testing.assert_array_equal(np.nanmax(grid, axis=1), [1.0, 2.0, 3.0])
    assert not np.isnan(grid).any()


def test_cells_no_step_falls_in_are_empty():
    _, grid = force_map(np.array([0.0, 0.26]), np.array([5.0, 7.0]), 2 * np.pi, 4)
    assert grid.shape == (1, 4) and grid[0, 0] == 5.0 and grid[0, 1] == 7.0
    assert np.isnan(grid[0, 2:]).all()


def test_a_run_draws_its_force_map():
    model = fr.bar_model()
    res = fr.ThetaMethod(model, 1e-4).run(0.06)
    omega = model.parameters["rotation_speed"]
    fig = contact_force_panel(res, omega)
    (ax, *_) = fig.axes
    mesh = ax.collections[0]
    assert mesh.get_array().max() == pytest.approx(res.force.sum(axis=1).max())


def test_the_response_drawn_is_the_first_displacement_probe():
    from types import SimpleNamespace

    from femrub.output.rub_plots import response_of

    rows = np.arange(6.0).reshape(3, 2)
    res = SimpleNamespace(
        signals={"contact_displacement": rows, "probe_T": rows[:, :1] + 7, "probe_y": rows[:, 1:]},
        info={"signal_units": {"probe_T": "K", "probe_y": "m"}},
    )
    y, label = response_of(res)
    np.testing.assert_array_equal(y, [1.0, 3.0, 5.0])
    assert label == "probe y"  # a displacement probe, not the temperature one
    res.signals.pop("probe_y")
    y, label = response_of(res, node=1)
    np.testing.assert_array_equal(y, [1.0, 3.0, 5.0])
    assert label == "contact 1 (normal)"


def test_a_run_ending_on_a_whole_revolution_has_no_row_for_its_last_time():
    omega = 2 * np.pi  # one revolution per second
    t = np.linspace(0.0, 2.0, 201)  # ends at 2 revolutions exactly
    edges, grid = force_map(t, np.ones_like(t), omega, 10)
    assert grid.shape == (2, 10) and np.allclose(edges, [0, 1, 2])
    assert not np.isnan(grid).any()
