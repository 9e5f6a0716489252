"""A reduced, damped, frictional 3D rub closes its energy balance.

The Petrov–Galerkin Craig–Bampton model keeps the boundary rows of the full model; with
Rayleigh damping its boundary velocity moves quasi-static shapes ``Γ = −K_ii⁻¹ C_ib``, so the
energy it conserves is not the projection of the full model's energy. The reductor builds
the forms of that energy (``ThermoelasticCraigBampton._energy``); before it, the damping form
of the rotating two-lobe Rotor 37 set-up was off by three orders of magnitude and the balance
"residual" was 1.9e3 times the stored energy.
"""

import numpy as np
import pytest

from femrub.app.run import run_scene
from femrub.scene.scene import load_scene

SCENE = {
    "physics.damping_ratio": 0.005,
    "contact.friction": 0.15,
    "scheme.t_end": 0.0015,
    "outputs.vtk_stride": 0,
    "outputs.plots": False,
    "reduction.method": "craig-bampton",
    "reduction.n_uv": 20,
    "reduction.tolerance": 1.0,
}


@pytest.mark.parametrize("thermal", ["off", "on"])
def test_reduced_damped_frictional_rub_closes_energy_balance(tmp_path, thermal, model_cache):
    over = dict(SCENE, **{"physics.thermal": thermal, "reduction.n_theta": 8})
    res, built = run_scene(load_scene("twisted-naca", over), tmp_path / "run", cache=model_cache)
    e = res.energy
    assert e["friction_work"][-1] > 1.0  # the casing drags the blade: joules flow through
    assert e["damping_work"][-1] < 0.0
    # energy stored is ~0.1 J while tens of J flow through friction: a 1e-6 residual is
    # round-off of the flow, a wrong damping form gives O(1)
    assert res.energy_error() < 1e-6, res.energy_error()
    rate = built.model.info["energy_growth_rate"]
    assert rate < 1e-3 * res.t[-1] ** -1, rate  # the reduction creates no energy


def test_second_order_craig_bampton_is_the_classical_galerkin_model(tmp_path, model_cache):
    """``projection = "second-order"``: M̄ = TᵀMT, K̄ = TᵀKT, C̄ = TᵀCT with T = [I 0; Ψ Φ]
    on u and v alike; the damped frictional rub closes its energy balance."""
    import scipy.sparse as sp

    from femrub.reduction import ThermoelasticCraigBampton

    over = dict(SCENE, **{"physics.thermal": "off", "reduction.n_theta": 0})
    over["reduction.projection"] = "second-order"
    res, built = run_scene(load_scene("twisted-naca", over), tmp_path / "run", cache=model_cache)
    assert res.energy_error() < 1e-6, res.energy_error()
    full = built.full
    red = ThermoelasticCraigBampton(full, 8, 0, projection="second-order")
    rm = red.reduce()
    L, Lr = full.layout, rm.layout
    T = red.R[L.u][:, Lr.u]
    assert np.allclose(red.R[L.v][:, Lr.v], T)  # velocity shapes = displacement shapes
    b = full.blocks
    A, B = rm.A.toarray(), rm.B.toarray()
    for got, want in (
        (A[Lr.v, Lr.v], T.T @ (b.M @ T)),
        (-B[Lr.v, Lr.u], T.T @ (b.K @ T)),
        (-B[Lr.v, Lr.v], T.T @ (sp.csr_matrix(b.C) @ T)),
    ):
        assert np.allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    assert rm.info["energy_growth_rate"] < 1e-3
