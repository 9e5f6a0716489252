"""The reduction error estimate compares the models over what the run itself can reach: its
runs stop at the scene's stop limits, as the run does (a runaway is not judged past its stop)."""

from __future__ import annotations

from test_cache import SMALL as COARSE

from femrub.app.simulation import build
from femrub.scene import load_scene

# the coarse twisted blade of the cache tests, long enough for the tip to reach the casing
SMALL = {**COARSE, "scheme.t_end": 4e-4}


def test_estimate_runs_stop_where_the_run_stops():
    free = build(load_scene("twisted-naca", SMALL), cache=None)
    e = free.report["reduction"]["error"]
    assert e["status_run"] == e["status_reference"] == "ok"
    assert e["checkpoints"][-1] > 0.9 * SMALL["scheme.t_end"]
    # a force limit far below the first impact's: the run stops there, and so do the
    # estimate's runs (both sizes), so the estimate covers the part before the stop only
    stopped = build(load_scene("twisted-naca", {**SMALL, "limits.contact_force": 1e-3}), cache=None)
    e = stopped.report["reduction"]["error"]
    assert e["status_run"] == e["status_reference"] == "diverged-physically"
    assert e["checkpoints"][-1] < 0.5 * SMALL["scheme.t_end"]
    res = stopped.stepper.run(SMALL["scheme.t_end"], limits=stopped.limits)
    assert res.status == "diverged-physically"
    assert res.t[-1] < 0.5 * SMALL["scheme.t_end"]
