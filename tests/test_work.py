"""Exact works and heats of the exponential stepper's flights (steppers/exponential/work.py)."""

import math

import numpy as np
import pytest
import scipy.linalg as sla

import femrub as fr
from femrub.steppers.exponential.flows import LEVEL_MIN
from femrub.steppers.exponential.work import LINEAR, QUADRATIC


def _setup(h=2e-3):
    st = fr.ExponentialMoreau(fr.bar_model(alpha=3.0), h)
    return st, st._integrals, h / st.probes


def _quadrature(M, Q, C, z0, tau, pieces=64, nodes=8):
    """``∫ zᵀQz`` and ``∫ Cz`` on ``z(s) = e^{sM} z0`` by composite Gauss–Legendre, and the
    integrals of their absolute values (the scale of round-off in cancelling integrals)."""
    x, wts = np.polynomial.legendre.leggauss(nodes)
    d = tau / pieces
    at = [sla.expm(0.5 * (xi + 1.0) * d * M) for xi in x]  # the nodes of one piece
    step = sla.expm(d * M)
    w, scale, za = np.zeros(Q.shape[0] + C.shape[0]), np.zeros(Q.shape[0] + C.shape[0]), z0
    for _ in range(pieces):
        for E, wi in zip(at, wts):
            z = E @ za
            f = np.r_[np.einsum("i,kij,j->k", z, Q, z), C @ z]
            w += 0.5 * d * wi * f
            scale += 0.5 * d * wi * np.abs(f)
        za = step @ za
    return w, scale


@pytest.mark.parametrize("S", [(), (0,)])
def test_integrals_match_quadrature_on_the_exact_flow(S):
    st, W, unit = _setup()
    flows, h = st._flows, st.h
    M = flows.generator_z(S)
    Q, C = W.forms(S, M)
    rng = np.random.default_rng(3)
    n, s = st.model.n_dofs, len(S)
    z0 = np.r_[rng.standard_normal(n) * 1e-6, np.zeros(s), rng.standard_normal(M.shape[0] - n - s)]
    z0[st.model.layout.t] = 50.0 + 10.0 * rng.random(st.model.layout.n_t)
    for tau in (3e-9, 0.37 * unit, 2.3 * unit, 0.61 * h):
        # the segment composed of flows over unit 2^e, down to e = LEVEL_MIN
        composed = math.floor(tau / unit * 2.0**-LEVEL_MIN) * unit * 2.0**LEVEL_MIN
        ref, scale = _quadrature(M, Q, C, z0, composed)
        w = W.over(S, z0, tau, unit)
        assert np.all(np.abs(w - ref) <= 1e-11 * scale), (tau, w, ref)
    ref, scale = _quadrature(M, Q, C, z0, h, pieces=128)
    assert np.all(np.abs(W.step(S, z0, st.probes, unit) - ref) <= 1e-11 * scale)
    # the state composed with the integrals is the composed flow
    z1, _ = W.over(S, z0, 0.61 * h, unit, state=True)
    assert np.allclose(
        z1, flows.advance_z(S, z0, 0.61 * h, unit), rtol=0, atol=1e-14 * np.abs(z1).max()
    )


def test_integral_keys_are_the_meter_keys():
    from femrub.steppers.exponential.work import METER_ORDER
    from femrub.steppers.record import WORK_KEYS

    # the stepper hands them in this order
    assert tuple((QUADRATIC + LINEAR)[i] for i in METER_ORDER) == WORK_KEYS


@pytest.mark.parametrize("h", [5e-3, 5e-4])
def test_paper_case_balance_closes_at_coarse_steps(h):
    res = fr.ExponentialMoreau(fr.bar_model(alpha=3.0), h).run(0.1)
    assert res.status == "ok"
    assert res.energy_error() < 1e-9 and res.heat_error() < 1e-9
    assert np.all(np.diff(res.energy["contact_work"]) <= 1e-15)


@pytest.mark.parametrize("h", [1e-4, 5e-3])
@pytest.mark.parametrize("measure", [False, True])
@pytest.mark.parametrize("S", [(), (0,)])
def test_whole_step_product_matches_the_matrix_exponential(S, measure, h):
    """One product per step (`_flight`): end state, held impulse, integrals and the event
    check grid ``[g; λ_S]`` at ``j h / q`` equal the augmented flow's ``expm`` to round-off."""
    st, W, unit = _setup(h)
    st._measure = measure
    flows, q, c = st._flows, st.probes, st.model.contact
    n, s = st.model.n_dofs, len(S)
    M = flows.generator_z(S)
    rng = np.random.default_rng(5)
    X = rng.standard_normal(n) * 1e-6
    X[st.model.layout.t] = 50.0 + 10.0 * rng.random(st.model.layout.n_t)
    b = rng.standard_normal((flows.degree + 1, flows.G.shape[1]))
    Xe, PS, rest, V, calm = st._flight(S, X, b)
    z0 = np.r_[X, np.zeros(s), flows.chain(b, 0.0)]
    lam = flows.generator(S)[2]
    ref = []
    for j in range(q + 1):
        zj = sla.expm(j * h / q * M) @ z0
        u = (j / q) ** np.arange(b.shape[0]) @ b
        row = c.gap(st.t + j * h / q, zj[:n])
        ref.append(row if not S else np.r_[row, lam[:, :n] @ zj[:n] + lam[:, n:] @ u])
        if j == q:
            assert np.allclose(Xe, zj[:n], rtol=0, atol=1e-12 * np.abs(zj[:n]).max())
            assert np.allclose(PS, zj[n : n + s], rtol=1e-10, atol=1e-14)
    ref = np.array(ref)
    assert V.shape == ref.shape
    assert np.allclose(V, ref, rtol=0, atol=1e-10 * np.abs(ref).max())
    # the compiled quiet check agrees with the grid: no free gap below min(g(0), 0), no
    # held multiplier negative
    free = np.ones(c.n, dtype=bool)
    free[list(S)] = False
    fall = (ref[1:, : c.n][:, free] < np.minimum(ref[0, : c.n][free], 0.0)).any()
    assert calm == (not fall and not (ref[:, c.n :] < 0.0).any())
    if measure:
        assert np.allclose(rest, W.step(S, z0, q, unit), rtol=1e-10, atol=1e-16)
    else:
        assert rest is None


def test_proportional_forms_are_integrated_once():
    # the held friction heat of one sliding contact is −η times its tangential work
    from femrub.steppers.exponential.work import _proportional

    rng = np.random.default_rng(1)
    Q = np.zeros((6, 4, 4))
    Q[1] = rng.standard_normal((4, 4))
    Q[2] = Q[1] + np.eye(4)  # not proportional
    Q[4] = rng.standard_normal((4, 4))
    Q[5] = -0.7 * Q[4]
    act, (dst, src, coef) = _proportional(Q, np.array([1, 2, 4, 5]))
    assert act.tolist() == [1, 2, 4] and dst.tolist() == [5] and src.tolist() == [4]
    assert coef == pytest.approx([-0.7], rel=1e-15)
    act, (dst, _, _) = _proportional(Q, np.array([1, 2]))
    assert act.tolist() == [1, 2] and dst.size == 0
