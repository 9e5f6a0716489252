"""The compiled frictional kernels (femrub.contact.coulomb) and the same code as Python.

The kernels are the only implementation of the frictional step: with ``NUMBA_DISABLE_JIT=1``
they run as plain Python. Both ways must give the same impulses (to round-off) on random
problems, on every activation rule, and along a frictional θ-method run with several
contacts.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from femrub.contact.activation import frictional_fixed_point, rule_code
from femrub.contact.coulomb import NON_POSITIVE, SLIP, SOLVED, STICK
from femrub.contact.friction import coulomb_check
from femrub.contact.jit import compiled

ROOT = Path(__file__).resolve().parents[1]


def problems(count=60, seed=3):
    """Random frictional steps: (rule code, g_k, ġ_k, g_p, GZ3, W, q, μ, e, u⁻, U)."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        n = int(rng.integers(1, 7))
        a = rng.normal(size=(3 * n, 3 * n))
        W = a @ a.T + 0.05 * np.eye(3 * n)
        if k % 3 == 1:  # non-symmetric (Newton stalls now and then: Gauss–Seidel, then Newton)
            W += 0.3 * rng.normal(size=W.shape) * np.sqrt(np.outer(np.diag(W), np.diag(W)))
        GZ3 = 0.5 * W[::3] * rng.uniform(0.5, 1.5)
        q = rng.normal(size=(n, 3))
        mu = rng.uniform(0.0, 0.8, n) * (rng.uniform(size=n) > 0.15)
        g_k, gd_k, g_p = rng.normal(size=n), rng.normal(size=n), rng.normal(size=n)
        e = np.where(gd_k > 0.0, 1.0, rng.uniform(0.0, 0.5))
        U = np.where(rng.uniform(size=n) < 0.3, rng.uniform(0.1, 1.0, n), np.inf)
        code = rule_code("predicted" if k % 4 == 0 else "paper")
        yield code, g_k, gd_k, g_p, GZ3, W, q, mu, e, gd_k.copy(), U


def solve_all() -> list:
    out = []
    for code, g_k, gd_k, g_p, GZ3, W, q, mu, e, ub, U in problems():
        n = q.shape[0]
        act, P, u, state, res, it, status = frictional_fixed_point(
            code,
            g_k,
            gd_k,
            g_p,
            GZ3,
            W,
            q,
            mu,
            e,
            ub,
            U,
            np.zeros((n, 3)),
            False,
            1e-3,
            0.5,
            1e-12,
            60,
        )
        out.append(
            {
                "active": act.tolist(),
                "P": P.tolist(),
                "u": u.tolist(),
                "state": state.tolist(),
                "status": int(status),
            }
        )
    return out


def test_fixed_point_solutions_satisfy_signorini_coulomb():
    solved = 0
    for k, ((code, g_k, _, g_p, GZ3, W, _, mu, e, ub, U), r) in enumerate(
        zip(problems(), solve_all())
    ):
        if r["status"] == NON_POSITIVE:  # a perturbed W with a non-positive W_nn
            assert np.any(np.diag(W)[::3] <= 0.0)
            continue
        if k % 3 == 1 and r["status"] != SOLVED:  # non-symmetric: may have no solution
            continue
        assert r["status"] == SOLVED
        solved += 1
        P, u, state = np.array(r["P"]), np.array(r["u"]), np.array(r["state"])
        act = np.array(r["active"])
        un = (u[:, 0] + e * ub) / (1.0 + e)  # Newton's law
        assert np.all(P[~act] == 0.0)
        assert np.all(P[:, 0] >= 0.0) and np.all(P[:, 0] <= U * (1 + 1e-12))
        free = act & (P[:, 0] < U * (1 - 1e-9))
        assert np.all(un[free] >= -1e-9) and np.all(np.abs(P[free, 0] * un[free]) <= 1e-9)
        nt = np.linalg.norm(P[:, 1:], axis=1)
        assert np.all(nt <= mu * P[:, 0] * (1 + 1e-12) + 1e-300)
        slip = state == SLIP
        np.testing.assert_allclose(nt[slip], mu[slip] * P[slip, 0], rtol=1e-12)
        stick = (state == STICK) & free
        assert np.all(np.linalg.norm(u[stick, 1:], axis=1) <= 1e-9)
        if code == rule_code("paper"):  # the set is the fixed point, or kept active
            closed_after = (g_k <= 0.0) | (g_p + GZ3 @ P.reshape(-1) <= 0.0)
            assert np.all(act | ~closed_after)
    assert solved >= 55


@pytest.mark.skipif(not compiled(), reason="kernels not compiled (NUMBA_DISABLE_JIT)")
def test_compiled_and_python_kernels_agree():
    code = "import json, tests.test_coulomb_kernels as t; print(json.dumps(t.solve_all()))"
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(ROOT)}
    run = subprocess.run(
        [sys.executable, "-c", code],
        env=env,
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
    )
    python, jit = json.loads(run.stdout), solve_all()
    assert len(python) == len(jit)
    for a, b in zip(python, jit):
        assert a["active"] == b["active"] and a["state"] == b["state"]
        assert a["status"] == b["status"]
        scale = max(np.abs(b["P"]).max(), 1e-300)
        np.testing.assert_allclose(a["P"], b["P"], rtol=0, atol=1e-10 * scale)


def test_theta_run_with_several_frictional_contacts_meets_coulomb(model_cache):
    """A frictional θ-method run through the compiled step: Coulomb checks of the run."""
    from femrub.app import build
    from femrub.scene import load_scene

    scene = load_scene(
        "twisted-naca",
        {
            "physics.thermal": "off",
            "contact.friction": 0.3,
            "scheme.t_end": 0.0015,
            "outputs.vtk_stride": 0,
            "contact.casing.depth": "200 um",
            "contact.casing.clearance": "5 um",
            "reduction.method": "craig-bampton",
            "reduction.n_uv": 12,
            "reduction.n_theta": 0,
            "contact.reach": "all",
        },
    )
    sim = build(scene, log=lambda s: None, cache=model_cache)
    res = sim.stepper.run(scene["scheme"]["t_end"])
    assert sim.model.contact.n >= 4
    assert res.status == "ok", res.message  # includes the Coulomb check at 1e-8
    active = res.contact_state > 0
    assert active.any(axis=1).mean() > 0.3  # rubs most of the time
    assert int((active.sum(axis=1) >= 2).sum()) > 10  # several contacts at once
    check = coulomb_check(
        res.force, res.friction_force, res.slip_velocity, res.contact_state, res.friction_limit
    )
    assert check["cone"] <= 1e-8 and check["slip_equality"] <= 1e-8
    assert check["direction"] <= 1e-8 and check["slip_steps"] > 0


def test_power_heat_fixed_point_meets_its_heat_and_skips_without_feedback():
    """The ``"power"`` heat fixed point (one implementation for every stepper): the final
    impulses solve the step with the heat's velocity shift, and the heat is
    ``η (−P_t · w_mid)`` of those impulses; without a shift (``W_θ = 0``) the first solve
    stands."""
    from femrub.contact.friction import power_heat_fixed_point, solve_frictional_contact

    rng = np.random.default_rng(7)
    n = 3
    a = rng.normal(size=(3 * n, 3 * n))
    W = a @ a.T + 0.5 * np.eye(3 * n)
    q = np.column_stack([-np.ones(n), rng.normal(size=(n, 2))])
    mu, eta, active = np.full(n, 0.4), np.full(n, 0.6), np.ones(n, dtype=bool)
    w_before = rng.normal(size=(n, 2))
    first = solve_frictional_contact(W, q, mu, active)
    Wt = 1e-3 * rng.normal(size=(3 * n, n))
    res, heat = power_heat_fixed_point(first, w_before, eta, W, q, Wt, mu, active)
    assert np.all(heat != 0.0) and not np.array_equal(res.P, first.P)
    w_mid = 0.5 * (w_before + res.u[:, 1:])
    np.testing.assert_allclose(heat, eta * -np.einsum("ij,ij->i", res.P[:, 1:], w_mid), rtol=1e-10)
    shifted = solve_frictional_contact(W, q + (Wt @ heat).reshape(n, 3), mu, active, warm=res.P)
    np.testing.assert_allclose(res.P, shifted.P, rtol=1e-9, atol=1e-12 * np.abs(res.P).max())
    same, heat0 = power_heat_fixed_point(first, w_before, eta, W, q, 0 * Wt, mu, active)
    assert np.array_equal(same.P, first.P) and np.array_equal(same.u, first.u)
    np.testing.assert_allclose(
        heat0,
        eta * -np.einsum("ij,ij->i", first.P[:, 1:], 0.5 * (w_before + first.u[:, 1:])),
        rtol=1e-14,
    )
