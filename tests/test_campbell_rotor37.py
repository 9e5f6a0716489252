"""Rotor 37 Campbell diagram 0-1800 rad/s (slow: minutes and ~4 GB; -m slow or benchmarks).

The rest frequencies of the CalculiX C3D15 model with the deck's material (E = 210 GPa,
ν = 0.3, ρ = 9000 kg/m³): 312.12, 922.81, 1165.62 Hz (shared data README)."""

import numpy as np
import pytest

PUBLISHED_HZ = (312.12, 922.81, 1165.62)
DECK = {"material.young": 210e9, "material.poisson": 0.3, "material.density": 9000.0}


@pytest.mark.slow
def test_rotor37_campbell(shared_data, tmp_path, monkeypatch):
    monkeypatch.setenv("FEMRUB_SHARED_DATA", str(shared_data))
    from femrub.app.campbell import campbell, parse_speeds, write_campbell
    from femrub.scene import load_scene

    scene = load_scene(  # the scene's runs have no prestress; its Campbell diagram has
        "rotor37", {**DECK, "physics.lumping": "consistent", "loads.centrifugal": "nonlinear"}
    )
    res = campbell(scene, parse_speeds("0:1800:10"), modes=6)
    doc = write_campbell(res, tmp_path)
    rest = np.array(doc["rest_frequencies_hz"][:3])
    assert np.allclose(rest, PUBLISHED_HZ, rtol=0.005), rest
    assert doc["status"] == "ok" and doc["max_error_bound"] < 0.005
    assert np.all(res.frequencies[-1, :3] > res.frequencies[0, :3])  # centrifugal stiffening
    assert (tmp_path / "campbell.png").exists() and (tmp_path / "campbell.csv").exists()
