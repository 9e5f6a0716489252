"""Exact flows of the exponential stepper: sub-step flows, composed advances, event roots."""

import math

import numpy as np
import pytest
import scipy.linalg as sla

import femrub as fr
from femrub.contact.casing import casing_profile, swept_gap
from femrub.steppers.exponential.flows import LEVEL_MIN, Flow, first_zero, shift


def _family(h=2e-3):
    st = fr.ExponentialMoreau(fr.bar_model(alpha=3.0), h)
    return st, st._flows, h / st.probes


def _augmented(flows, S):
    K, E, _ = flows.generator(S)
    nz, m, p = K.shape[0], E.shape[1], flows.degree
    M = np.zeros((nz + (p + 1) * m,) * 2)
    M[:nz, :nz], M[:nz, nz : nz + m] = K, E
    for i in range(p):
        r = nz + i * m
        M[r : r + m, r + m : r + 2 * m] = np.eye(m)
    return M


@pytest.mark.parametrize("S", [(), (0,)])
def test_sub_step_flows_match_the_matrix_exponential(S):
    # levels by squaring one increment: every level is e^{τ M} to round-off
    _, flows, unit = _family()
    Z, M = flows.levels(S, unit), _augmented(flows, S)
    for e in (LEVEL_MIN, -20, -5, 0, len(Z) - 1 + LEVEL_MIN):
        ref = sla.expm(unit * 2.0**e * M)
        Ze = Z[e - LEVEL_MIN]
        assert np.max(np.abs(Ze - ref)) <= 1e-12 * np.max(np.abs(ref))
        eye = np.eye(M.shape[0])  # the increment too (no cancellation against I)
        assert np.max(np.abs((Ze - eye) - (ref - eye))) <= 1e-12 * np.max(np.abs(ref - eye))


@pytest.mark.parametrize("S", [(), (0,)])
def test_composed_advance_is_the_exact_flow(S):
    st, flows, unit = _family()
    h, n = st.h, st.model.n_dofs
    rng = np.random.default_rng(1)
    X = rng.standard_normal(n) * 1e-6
    b = rng.standard_normal((flows.degree + 1, flows.G.shape[1]))
    K, E, _ = flows.generator(S)
    for tau0, tau1 in ((0.0, 37 * unit / 16), (0.3 * h, 0.3 * h + 2.37 * unit)):
        X1, P1 = flows.advance(S, X, tau0, tau1, b, unit)
        ref = Flow(K, E, n, tau1 - tau0, flows.degree)
        Xr, Pr = ref(X, shift(b, tau0 / h, (tau1 - tau0) / h))
        # exact up to the dropped remainder (below unit 2^LEVEL_MIN) and round-off
        assert np.max(np.abs(X1 - Xr)) <= 1e-9 * np.max(np.abs(Xr))
        if S:
            assert P1 == pytest.approx(Pr, rel=1e-9, abs=1e-18)


def test_first_zero_past_a_bump():
    # f rises before it falls through zero (the gap of a tip pushed away first): the first
    # zero is found to the tolerance, from the Hermite start, in few evaluations
    root, calls = 0.7, []

    def f(x):
        return (root - x) * (1.0 + 40.0 * x * (1.0 - x)), -(1.0 + 40.0 * x * (1.0 - x)) + (
            root - x
        ) * 40.0 * (1.0 - 2.0 * x)

    def at(x):
        calls.append(x)
        return None, None, *f(x)

    tol = 1e-12
    for df_lo in (f(0.0)[1], None):
        calls.clear()
        x, _, _ = first_zero(at, f(0.0)[0], 0.0, 1.0, tol, df_lo)
        assert 0.0 <= x - root <= 3 * tol and f(x)[0] <= 0.0
        assert len(calls) < 20


def test_swept_gap_rows_in_one_call():
    angles = np.linspace(0.0, 2.0, 5)
    gap, rate = swept_gap(
        casing_profile("lobed", clearance=2e-5, depth=5e-5, lobes=3), angles, 1500.0
    )
    t = np.linspace(0.0, 1e-3, 7)
    assert np.allclose(gap.over_times(t), np.array([gap(ti) for ti in t]), rtol=0, atol=1e-18)
    assert np.allclose(rate.over_times(t), np.array([rate(ti) for ti in t]), rtol=1e-14)
    assert math.isclose(float(gap.over_times(t)[3, 2]), float(gap(t[3])[2]))
