"""The NASA Rotor 37 rub: the built-in scenes are the published set-up; the example runs it
(slow: model building and 50 revolutions take minutes; run with -m slow)."""

import json
import math
import os

import numpy as np
import pytest

from femrub.scene import load_scene


@pytest.mark.parametrize("name", ["rotor37", "rotor37-thermal"])
def test_rotor37_scenes_are_the_published_setup(name):
    s = load_scene(name)
    m, c = s["material"], s["contact"]
    assert (m["young"], m["poisson"], m["density"]) == (210e9, 0.3, 9000.0)
    assert c["casing"] == {"kind": "two-lobe", "mean_gap": 0.356e-3, "width": 0.15}
    assert c["friction"] == 0.15 and len(c["nodes"]) == 16
    # the published point contacts on the rigid casing; tip patches under the coating
    assert c["spread"] == ("node" if name == "rotor37" else "patch")
    assert s["physics"]["damping_ratio"] == 0.005
    omega = s["loads"]["rotation_speed"]
    assert omega == 1344.0
    period = 2 * math.pi / omega
    # published: about 1000 steps per revolution; the coated scene steps 16x finer, where its
    # cutting episodes and frictional heat converge (docs/abradable.md)
    steps = 1000 if name == "rotor37" else 16000
    assert period / s["scheme"]["h"] == pytest.approx(steps, rel=1e-3)
    assert s["scheme"]["t_end"] / period == pytest.approx(50, rel=1e-4)
    assert s["physics"]["thermal"] == ("off" if name == "rotor37" else "on")
    # the coated rub's step is judged; its contacts read the coating through their footprint
    assert s["scheme"]["step_check"] == (name == "rotor37-thermal")
    assert c["abradable"]["footprint"] == (0.0 if name == "rotor37" else pytest.approx(7.6e-3))


@pytest.mark.slow
def test_rotor37_example_runs(shared_data, tmp_path, monkeypatch):
    monkeypatch.setenv("FEMRUB_OUT", str(tmp_path))
    monkeypatch.setenv("FEMRUB_SHARED_DATA", str(shared_data))
    import rotor37_rub as ex

    assert ex.available
    assert ex.fe_dofs > 90_000 and ex.reduced_dofs < 400
    out = tmp_path / "rotor37"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok", summary["message"]
    assert summary["revolutions"] == pytest.approx(50.0, abs=1e-2)
    assert summary["n_contacts"] == 16
    assert summary["reduction_error"]["estimate"] <= summary["reduction_error"]["tolerance"]
    check = summary["coulomb_check"]
    assert check["cone"] <= 1e-8 and check["slip_equality"] <= 1e-8
    assert check["direction"] <= 1e-8 and check["force_without_normal"] == 0.0
    assert summary["max_friction_force"] > 0 and summary["friction_work"] > 0
    with np.load(out / "history.npz") as d:
        lam, ff, sv = d["normal_force"], d["friction_force"], d["slip_velocity"]
        assert ff.shape == (summary["steps"] + 1, 16, 3)
        assert np.all(np.linalg.norm(ff, axis=-1) <= 0.15 * lam * (1 + 1e-8))
        slip = d["contact_state"] == 2
        np.testing.assert_allclose(np.linalg.norm(ff, axis=-1)[slip], 0.15 * lam[slip], rtol=1e-8)
        cos = np.einsum("...i,...i", ff, sv)[slip]
        assert np.all(cos <= 0.0)
    assert os.path.exists(out / "vtk" / "rub.pvd") and os.path.exists(out / "spectrum.png")
