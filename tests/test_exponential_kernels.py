"""Compiled dyadic kernels of the exponential stepper (:mod:`femrub.steppers.exponential.kernels`).

They are the only implementation of the level squaring, the composed advance and the
composed work integrals: checked here against plain matrix exponentials and quadrature-free
identities, and run both compiled and as plain Python (``NUMBA_DISABLE_JIT=1``) on the paper
bar with a held contact, the two giving the same run.
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
from jit_child import child_json

from femrub.contact.jit import compiled
from femrub.steppers.exponential.flows import first_zero
from femrub.steppers.exponential.kernels import (
    compose,
    compose_integrals,
    double_integrals,
    first_zero_row,
    flight,
    integrals_over,
    open_end,
    quiet,
    square_levels,
)

ROOT = Path(__file__).resolve().parents[1]


def _generator(n=6, seed=0):
    rng = np.random.default_rng(seed)
    return rng.standard_normal((n, n)) - 2.0 * np.eye(n)


def test_square_levels_are_the_exponentials_of_doubled_durations():
    M, tau = _generator(), 1e-3
    D = sla.expm(tau * M) - np.eye(6)
    Z = square_levels(D.copy(), 12, 1e-150)
    for e in (0, 5, 11):
        ref = sla.expm(tau * 2.0**e * M)
        assert np.max(np.abs(Z[e] - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_square_levels_flush_tiny_entries():
    D = np.zeros((3, 3))
    D[0, 1] = 1e-200
    Z = square_levels(D, 1, 1e-150)
    assert Z[0, 0, 1] == 0.0 and np.array_equal(Z[0], np.eye(3))


def test_compose_is_the_flow_over_k_units():
    M, tau = _generator(), 1e-2
    Z = square_levels(sla.expm(tau * M) - np.eye(6), 8, 1e-150)
    z = np.arange(1.0, 7.0)
    for k in (0, 1, 37, 255):
        ref = sla.expm(k * tau * M) @ z
        assert np.max(np.abs(compose(Z, z, k) - ref)) <= 1e-11 * np.max(np.abs(ref))


def test_doubled_integrals_compose_to_van_loan():
    # Γ(τ) = ∫ e^{Mᵀσ} Q e^{Mσ} dσ and C J(τ): doubled from level 0, composed over k units
    M, tau, n = _generator(4, 2), 1e-2, 4
    Q = np.diag([1.0, 2.0, 0.5, 1.0])
    Cr = np.ones((2, n))
    big = np.zeros((2 * n, 2 * n))
    big[:n, :n], big[:n, n:], big[n:, n:] = -tau * M.T, tau * Q, tau * M
    g0 = sla.expm(tau * M).T @ sla.expm(big)[:n, n:]
    bj = np.zeros((2 * n, 2 * n))
    bj[:n, :n], bj[:n, n:] = tau * M, tau * np.eye(n)
    j0 = Cr @ sla.expm(bj)[:n, n:]
    Z = square_levels(sla.expm(tau * M) - np.eye(n), 6, 1e-150)
    Y = double_integrals(0.5 * (g0 + g0.T)[None].copy(), j0.copy(), Z, 1e-150)
    z = np.array([1.0, -0.5, 0.2, 0.3])
    k = 45
    wq, wl, zk, rest = compose_integrals(Y, Z, z.copy(), k, 0, 1)
    T = k * tau  # the reference over the whole duration (Van Loan)
    big[:n, :n], big[:n, n:], big[n:, n:] = -T * M.T, T * Q, T * M
    gT = sla.expm(T * M).T @ sla.expm(big)[:n, n:]
    bj[:n, :n], bj[:n, n:] = T * M, T * np.eye(n)
    assert rest == 0
    assert wq[0] == pytest.approx(z @ gT @ z, rel=1e-10)
    assert wl == pytest.approx(Cr @ sla.expm(bj)[:n, n:] @ z, rel=1e-10)
    assert zk == pytest.approx(sla.expm(T * M) @ z, rel=1e-10)
    # bits below lo are left to the caller
    *_, rest = compose_integrals(Y[2:], Z, z.copy(), 7, 2, 1)
    assert rest == 3


def _oscillator_levels(unit, count, lo=-36):
    """``z = [x, v]``, ``ẋ = v, v̇ = −x``: its flows over ``unit 2^e``, e = lo … lo + count − 1."""
    M = np.array([[0.0, 1.0], [-1.0, 0.0]])
    return M, square_levels(sla.expm(unit * 2.0**lo * M) - np.eye(2), count, 1e-150)


def test_first_zero_row_finds_the_first_crossing_as_first_zero_does():
    # x = cos t from (1, 0): the row event x − 1/2 first crosses zero at π/3, inside (0, 2]
    unit, tol = 0.1, 1e-12
    M, Z = _oscillator_levels(unit, 42)
    r, c0 = np.array([1.0, 0.0]), -0.5
    d_min = unit * 2.0**-36
    found, tau, z = first_zero_row(Z, np.array([1.0, 0.0]), r, r @ M, c0, 0.0, 2.0, tol, d_min)
    assert found and 0.0 <= tau - np.pi / 3 <= 3 * tol and r @ z + c0 <= 0.0
    # the state at τ less the remainder below the smallest level (unit 2^-36)
    assert z == pytest.approx([np.cos(tau), -np.sin(tau)], abs=2 * d_min)

    def at(t):  # the same flow, composed from the start, for the Python iteration
        zt = compose(Z, np.array([1.0, 0.0]), int(t / d_min * (1.0 + 1e-12)))
        return zt, None, r @ zt + c0, r @ M @ zt

    x, _, _ = first_zero(at, 0.5, 0.0, 2.0, tol, 0.0)
    assert tau == pytest.approx(x, abs=2 * tol)
    # at the surface at lo (f(lo) = 0, opening): the bracket is halved until f > 0 first
    z0 = np.array([0.5, 0.1])  # x = 1/2 rising: the next crossing is on the way down
    found, tau, _ = first_zero_row(Z, z0, r, r @ M, c0, 0.0, 2.0, tol, d_min)
    t_ref = 2.0 * np.arctan2(0.1, 0.5)  # x(t) = 1/2 again: symmetric about the maximum
    # (each evaluation composed from the latest open-side state drops its remainder below
    # the smallest level: a few d_min)
    assert found and tau == pytest.approx(t_ref, abs=3 * tol + 8 * d_min)
    # no sign change: nothing found
    found, *_ = first_zero_row(Z, np.array([1.0, 0.0]), r, r @ M, -3.0, 0.0, 2.0, tol, d_min)
    assert not found


def test_integrals_over_adds_the_series_below_the_levels():
    # ∫ x² dt and ∫ (x, v) dt of the oscillator over k units: levels from lo = 30, series below
    # (on the Krylov vectors of the state; the A_k, C M^k here only start the levels)
    unit, lo, n_lev = 0.01, 30, 42
    M, Z = _oscillator_levels(unit, n_lev)
    Q, Cr = np.array([[[1.0, 0.0], [0.0, 0.0]]]), np.eye(2)
    A, B = [Q], [Cr]  # Taylor coefficients A_{k+1} = Mᵀ A_k + A_k M, C M^k (8 terms)
    for _ in range(7):
        A.append(M.T @ A[-1] + A[-1] @ M)
        B.append(B[-1] @ M)
    A, B = np.stack(A), np.stack(B)
    c = (unit * 2.0 ** (lo - 36)) ** np.arange(1, 9) / np.cumprod(np.arange(1.0, 9.0))
    g0, j0 = np.tensordot(c, A, 1), np.tensordot(c, B, 1)
    Y = double_integrals(g0.copy(), j0.copy(), np.ascontiguousarray(Z[lo:]), 1e-150)
    z0, k = np.array([1.0, 0.0]), (5 << 36) + 123456789  # 5 units and a few small bits
    T = k * unit * 2.0**-36
    args = (Y, lo, Q, Cr, M, Z, z0.copy(), k, 8, unit * 2.0**-36)
    wq, wl, z = integrals_over(*args, True)
    assert wq[0] == pytest.approx(T / 2 + np.sin(2 * T) / 4, rel=1e-12)
    assert wl == pytest.approx([np.sin(T), np.cos(T) - 1.0], rel=1e-11)
    assert z == pytest.approx([np.cos(T), -np.sin(T)], rel=1e-11)
    assert integrals_over(*args, False)[2] == pytest.approx(compose(Z, z0, k >> lo << lo))


def test_quiet_flags_closings_and_releases_only():
    # two contacts then one held multiplier, grid of 3 points
    V = np.array([[1.0, -0.2, 5.0], [0.5, -0.1, 4.0], [0.2, -0.15, 3.0]])
    free = np.zeros(2, dtype=np.bool_)
    assert quiet(V, 2, free)  # gap 0 stays above min(g(0), 0); gap 1 rises from -0.2
    V2 = V.copy()
    V2[2, 0] = -1e-12  # a closing
    assert not quiet(V2, 2, free)
    held = np.array([True, False])
    assert quiet(V2, 2, held)  # a held contact's gap is not checked
    V3 = V.copy()
    V3[1, 2] = -1.0  # a held multiplier pulls: a release
    assert not quiet(V3, 2, held)


def test_flight_reads_state_integrals_and_grid_off_one_product():
    rng = np.random.default_rng(3)
    F, u = rng.standard_normal((3 + 2 * 4 + 2 + 2 * 2, 4)), rng.standard_normal(4)
    act, works = np.array([1, 3]), np.zeros(6)
    k = 3 + 2 * 4 + 2
    g0, off = np.full((2, 1), 10.0), np.array([0.5])
    free = np.zeros(1, dtype=np.bool_)
    y, V, calm, opened = flight(F, u, k, 1, g0, off, free, 3, act, True, works)
    ref = F @ u
    assert y[:k] == pytest.approx(ref[:k])  # (the rows past k: V, maybe shared)
    assert works[1] == pytest.approx(ref[3:7] @ u) and works[3] == pytest.approx(ref[7:11] @ u)
    assert works[4:] == pytest.approx(ref[11:13]) and works[0] == works[2] == 0.0
    assert V == pytest.approx(ref[k:].reshape(2, 2) + np.c_[g0, np.full(2, 0.5)])
    assert calm == quiet(V, 1, free) and opened == (calm and open_end(V, 1, free))


def test_open_end_reads_the_last_grid_row_of_free_contacts():
    V = np.array([[1.0, -0.2, 5.0], [0.5, 1e-3, -4.0]])  # two contacts, a held multiplier
    free, held = np.zeros(2, dtype=np.bool_), np.array([False, True])
    assert open_end(V, 2, free)  # both gaps open at the end (the multiplier is not a gap)
    V[1, 1] = 1e-13  # within round-off of the largest gap: not known open
    assert not open_end(V, 2, free) and open_end(V, 2, held)
    V[1, 0] = 0.0
    assert not open_end(V, 2, held)


_CHILD = """
import json, numpy as np, femrub as fr
from femrub.contact.jit import compiled
from femrub.steppers.exponential.flows import first_zero
st = fr.ExponentialMoreau(fr.bar_model(alpha=3.0, restitution=0.0), 1e-3)
r = st.run(0.02)
print(json.dumps({"jit": compiled(), "status": r.status, "X": st.X.tolist(),
                  "P": r.impulse.sum(axis=0).tolist(), "held": [int(i) for i in st._S],
                  "levels": len(st._flows._levels)}))
"""


@pytest.mark.skipif(not compiled(), reason="kernels not compiled (NUMBA_DISABLE_JIT)")
def test_the_stepper_runs_as_python_without_jit():
    py, jt = child_json(_CHILD, False), child_json(_CHILD, True)
    assert not py["jit"] and jt["jit"] and py["status"] == jt["status"] == "ok"
    assert py["levels"] == jt["levels"] >= 2  # free and held flows were composed
    X0, X1 = np.array(py["X"]), np.array(jt["X"])
    assert np.max(np.abs(X0 - X1)) <= 1e-9 * np.max(np.abs(X1))
    assert np.allclose(py["P"], jt["P"], rtol=1e-9, atol=0.0)
