"""Tests for femrub.contact.lcp: exact LCP solver (Lemke + semi-smooth Newton fallback)."""

import itertools

import numpy as np
import pytest

from femrub.contact.lcp import LCPError, LCPResult, solve_lcp


def brute_force(M, q):
    """Distinct solutions found by enumerating the 2^n active sets (small n only)."""
    n = q.size
    sols = []
    for bits in itertools.product([False, True], repeat=n):
        S = np.array(bits)
        z = np.zeros(n)
        if S.any():
            z[S] = np.linalg.solve(M[np.ix_(S, S)], -q[S])
        w = M @ z + q
        scale = np.abs(M).max() * np.abs(z).max() + np.abs(q).max()
        new = all(not np.allclose(z, s, rtol=1e-9, atol=1e-9 * scale) for s in sols)
        if z.min() >= -1e-9 * scale and w.min() >= -1e-9 * scale and new:
            sols.append(z)  # degenerate q: several active sets may give the same z
    return sols


def assert_lcp_solution(M, q, res, rtol=1e-10):
    assert isinstance(res, LCPResult) and res.converged
    z, w = res.z, res.w
    assert z.shape == w.shape == q.shape
    np.testing.assert_allclose(w, M @ z + q, rtol=0, atol=1e-12 * (1 + np.abs(q).max()))
    scale = np.abs(M).max() * np.abs(z).max() + np.abs(q).max()
    assert z.min() >= 0.0
    assert w.min() >= -rtol * scale
    assert abs(z @ w) <= rtol * scale * np.abs(z).sum()
    assert res.residual <= 1e-12


def random_matrix(kind, n, rng):
    A = rng.standard_normal((n, n))
    if kind == "spd":
        return A @ A.T / n + 0.1 * np.eye(n)
    if kind == "spd+skew":  # non-symmetric positive definite => P-matrix
        return A @ A.T / n + 0.1 * np.eye(n) + 2.0 * (A - A.T)
    if kind == "diag-dominant":  # strictly row diagonally dominant, positive diagonal
        return A + np.diag(np.abs(A).sum(axis=1) + 0.1)
    if kind == "triangular":  # P-matrix that is far from positive definite
        return 5.0 * np.triu(A, 1) + np.diag(rng.uniform(0.1, 2.0, n))
    raise AssertionError(kind)


def naive_lemke_cycles(M, q, max_pivots=200):
    """Lemke with smallest-index tie-breaking; True if a (basis, leaving) state repeats."""
    n = q.size
    T = np.hstack([np.eye(n), -M, -np.ones((n, 1)), q[:, None]])
    basis, seen = list(range(n)), set()
    r, entering = int(np.argmin(q)), 2 * n
    for _ in range(max_pivots):
        T[r] /= T[r, entering]
        T -= np.outer(np.where(np.arange(n) == r, 0.0, T[:, entering]), T[r])
        leaving, basis[r] = basis[r], entering
        if leaving == 2 * n:
            return False
        if (state := (tuple(sorted(basis)), leaving)) in seen:
            return True
        seen.add(state)
        entering = leaving + n if leaving < n else leaving - n
        rows = np.flatnonzero(T[:, entering] > 1e-12)
        ratios = T[rows, -1] / T[rows, entering]
        r = int(rows[ratios <= ratios.min() + 1e-12][0])
    return True


@pytest.mark.parametrize(
    ("m", "q", "z", "method"),
    [(2.0, -3.0, 1.5, "closed-form"), (2.0, 3.0, 0.0, "trivial"), (2.0, 0.0, 0.0, "trivial")],
)
def test_one_by_one(m, q, z, method):
    res = solve_lcp([[m]], [q])
    assert res.method == method and res.converged and res.pivots == 0
    np.testing.assert_allclose(res.z, [z], rtol=1e-15)
    np.testing.assert_allclose(res.w, [m * z + q], atol=1e-15)


def test_one_by_one_infeasible_and_empty():
    with pytest.raises(LCPError, match="no solution"):
        solve_lcp([[-1.0]], [-1.0])
    res = solve_lcp(np.zeros((0, 0)), np.zeros(0))
    assert res.z.shape == (0,) and res.converged


@pytest.mark.parametrize("kind", ["spd", "spd+skew", "diag-dominant", "triangular"])
@pytest.mark.parametrize("seed", range(4))
def test_random_p_matrices(kind, seed):
    rng = np.random.default_rng(seed)
    for n in range(2, 31):
        M, q = random_matrix(kind, n, rng), rng.standard_normal(n)
        if kind != "spd":
            assert not np.allclose(M, M.T)
        res = solve_lcp(M, q)
        assert res.method in ("lemke", "trivial")
        assert_lcp_solution(M, q, res)
        if n <= 8:
            (z_ref,) = brute_force(M, q)  # P-matrix: exactly one solution
            np.testing.assert_allclose(res.z, z_ref, rtol=1e-9, atol=1e-12)


def test_scaling_invariance_stiff_units():
    rng = np.random.default_rng(7)
    M, q = random_matrix("spd+skew", 12, rng), rng.standard_normal(12)
    ref = solve_lcp(M, q)
    res = solve_lcp(1e9 * M, 1e-4 * q)  # e.g. N/m against metres
    np.testing.assert_allclose(res.z, 1e-13 * ref.z, rtol=1e-9, atol=1e-25)
    assert res.pivots == ref.pivots and res.residual <= 1e-12


# P-matrices with ties in q that make Lemke cycle under smallest-index tie-breaking
CYCLING = [
    ([[2, 2, -2], [-2, 1, 2], [3, -2, 1]], [-1, -1, -1]),  # also positive definite
    ([[3, 0, 2, 2], [2, 1, 3, 0], [-2, -1, 1, 2], [1, 3, -2, 1]], [0, -1, -1, -1]),
    ([[1, 3, -1], [0, 1, 3], [3, -1, 2]], [-1, -1, -1]),
]


@pytest.mark.parametrize(("M", "q"), CYCLING)
def test_degenerate_cycling_instances(M, q):
    M, q = np.array(M, dtype=float), np.array(q, dtype=float)
    assert naive_lemke_cycles(M, q)  # the instance really is a cycling one
    res = solve_lcp(M, q)
    assert res.method == "lemke" and res.pivots <= 2 * q.size
    assert_lcp_solution(M, q, res)
    (z_ref,) = brute_force(M, q)
    np.testing.assert_allclose(res.z, z_ref, rtol=1e-12, atol=1e-14)


def test_degenerate_duplicated_rows_psd():
    # singular PSD M with duplicated rows/columns and zeros in q: solutions not unique
    B = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.0, 1.0]])
    M = B @ B.T
    q = np.array([-1.0, -1.0, 0.0, 0.0, -2.0])
    res = solve_lcp(M, q)
    assert res.method == "lemke"
    assert_lcp_solution(M, q, res)


def test_newton_fallback_when_pivots_exhausted():
    rng = np.random.default_rng(5)
    for kind, n in itertools.product(["spd", "spd+skew", "diag-dominant"], (8, 30)):
        M, q = random_matrix(kind, n, rng), rng.standard_normal(n)
        ref = solve_lcp(M, q)
        res = solve_lcp(M, q, max_pivots=1)
        assert res.method == "newton-fb" and res.pivots == 1
        assert_lcp_solution(M, q, res)
        np.testing.assert_allclose(res.z, ref.z, rtol=1e-9, atol=1e-12)
        if n <= 8:
            (z_ref,) = brute_force(M, q)
            np.testing.assert_allclose(res.z, z_ref, rtol=1e-9, atol=1e-12)


def test_hundred_contacts():
    rng = np.random.default_rng(5)
    M, q = random_matrix("spd+skew", 100, rng), rng.standard_normal(100)
    res = solve_lcp(M, q)
    assert res.method == "lemke" and res.pivots > 50
    assert_lcp_solution(M, q, res)


def test_not_converged_flag_between_tol_and_sqrt_tol():
    rng = np.random.default_rng(0)
    M, q = random_matrix("spd+skew", 30, rng), rng.standard_normal(30)
    res = solve_lcp(M, q, tol=1e-30)
    assert not res.converged and 1e-30 < res.residual <= 1e-15
    assert res.z.min() >= 0 and np.isfinite(res.w).all()


def test_infeasible_raises_lcperror():
    with pytest.raises(LCPError, match="not solved") as info:
        solve_lcp(-np.eye(3), -np.ones(3))
    assert "\n" not in str(info.value)
    with pytest.raises(LCPError):
        solve_lcp(np.zeros((2, 2)), [1.0, -1.0])


def test_warm_start_same_answer():
    rng = np.random.default_rng(11)
    M, q = random_matrix("spd+skew", 16, rng), rng.standard_normal(16)
    first = solve_lcp(M, q)
    q_next = q + 1e-6 * rng.standard_normal(16)  # next time step: same active set
    cold = solve_lcp(M, q_next)
    warm = solve_lcp(M, q_next, warm_start=first.z > 0)
    assert warm.method == "warm-start" and warm.pivots == 0 and cold.method == "lemke"
    assert_lcp_solution(M, q_next, warm)
    np.testing.assert_allclose(warm.z, cold.z, rtol=1e-10, atol=1e-14)
    wrong = solve_lcp(M, q_next, warm_start=np.ones(16, dtype=bool))
    assert wrong.method == "lemke"
    np.testing.assert_allclose(wrong.z, cold.z, rtol=1e-10, atol=1e-14)


@pytest.mark.parametrize(
    ("M", "q", "kwargs", "match"),
    [
        (np.eye(3), np.ones(2), {}, "shape"),
        (np.ones((2, 3)), np.ones(2), {}, "shape"),
        (np.eye(2), np.ones((2, 1)), {}, "1-D"),
        (np.array([[1.0, np.nan], [0.0, 1.0]]), -np.ones(2), {}, "finite"),
        (np.eye(2), np.array([np.inf, -1.0]), {}, "finite"),
        (np.eye(2) * 1j, -np.ones(2), {}, "real"),
        ([["a", "b"], ["c", "d"]], -np.ones(2), {}, "numeric"),
        (np.eye(2), -np.ones(2), {"tol": -1.0}, "tol"),
        (np.eye(2), -np.ones(2), {"max_pivots": 0}, "max_pivots"),
        (np.eye(2), -np.ones(2), {"max_pivots": 2.5}, "max_pivots"),
        (np.eye(2), -np.ones(2), {"warm_start": [1, 0]}, "warm_start"),
        (np.eye(2), -np.ones(2), {"warm_start": [True]}, "warm_start"),
    ],
)
def test_bad_input_raises_valueerror(M, q, kwargs, match):
    with pytest.raises(ValueError, match=match) as info:
        solve_lcp(M, q, **kwargs)
    assert "\n" not in str(info.value)
