"""pymodal.linear_sum_assignment against scipy.optimize.linear_sum_assignment."""

import itertools

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment as scipy_lsa

import pymodal

METHODS = ["jv", "hungarian", "simplex"]


def total(cost, r, c):
    return cost[r, c].sum() if len(r) else 0.0


def check_against_scipy(cost, maximize=False):
    cost = np.asarray(cost)
    sr, sc = scipy_lsa(cost, maximize=maximize)
    expected = total(cost.astype(float), sr, sc)
    scale = float(max(1.0, np.abs(cost[np.isfinite(cost)]).max(initial=0.0)))
    for method in METHODS:
        r, c = pymodal.linear_sum_assignment(cost, maximize, solver=method)
        assert r.dtype == np.int64 and c.dtype == np.int64
        assert r.shape == c.shape == (min(cost.shape),)
        assert np.all(np.diff(r) > 0), "row_ind must be sorted"
        assert len(set(c.tolist())) == len(c), "columns used twice"
        got = total(cost.astype(float), r, c)
        assert got == pytest.approx(expected, rel=1e-12, abs=1e-9 * scale * cost.size), method
        if not maximize:
            assert np.all(np.isfinite(cost[r, c].astype(float)))


def random_cases():
    rng = np.random.default_rng(20261122)
    cases = []
    for _ in range(25):
        n, m = rng.integers(1, 40, size=2)
        cases.append(("uniform", rng.random((n, m))))
        cases.append(("ties", rng.integers(0, 3, size=(n, m))))
        cases.append(("ints", rng.integers(1, 101, size=(n, m))))
        c = rng.random((n, m)) * 10
        c[rng.random((n, m)) < 0.3] = np.inf
        cases.append(("inf", c))
        cases.append(("large", rng.normal(size=(n, m)) * 1e12))
        cases.append(("tiny", rng.random((n, m)) * 1e-9))
    for n, m in [(100, 100), (60, 150), (150, 60), (200, 200)]:
        cases.append(("uniform-big", rng.random((n, m))))
        cases.append(("ties-big", rng.integers(0, 4, size=(n, m)).astype(float)))
        p, q = rng.random((n, 2)), rng.random((m, 2))
        cases.append(("euclid", np.linalg.norm(p[:, None] - q[None], axis=2)))
    return cases


CASES = random_cases()


@pytest.mark.parametrize("maximize", [False, True])
@pytest.mark.parametrize("idx", range(len(CASES)), ids=[f"{k}-{c.shape[0]}x{c.shape[1]}-{i}" for i, (k, c) in enumerate(CASES)])
def test_random_against_scipy(idx, maximize):
    kind, cost = CASES[idx]
    if maximize and kind == "inf":
        cost = np.where(np.isinf(cost), -np.inf, cost)
    try:
        scipy_lsa(cost, maximize=maximize)
    except ValueError as e:
        # Infeasible patterns of forbidden entries: every method must agree.
        assert "infeasible" in str(e)
        for method in METHODS:
            with pytest.raises(ValueError, match="cost matrix is infeasible"):
                pymodal.linear_sum_assignment(cost, maximize, solver=method)
        return
    check_against_scipy(cost, maximize)


def test_scipy_doc_example():
    cost = np.array([[4, 1, 3], [2, 0, 5], [3, 2, 2]])
    for method in METHODS:
        r, c = pymodal.linear_sum_assignment(cost, solver=method)
        assert r.tolist() == [0, 1, 2]
        assert c.tolist() == [1, 0, 2]
        assert cost[r, c].sum() == 5


def test_brute_force_small():
    rng = np.random.default_rng(3)
    for _ in range(50):
        n = int(rng.integers(1, 6))
        cost = rng.integers(0, 5, size=(n, n)).astype(float)
        best = min(sum(cost[i, p[i]] for i in range(n)) for p in itertools.permutations(range(n)))
        for method in METHODS:
            r, c = pymodal.linear_sum_assignment(cost, solver=method)
            assert cost[r, c].sum() == best


def test_array_likes_and_bools():
    for method in METHODS:
        r, c = pymodal.linear_sum_assignment([[1, 2], [3, 0]], solver=method)
        assert (r.tolist(), c.tolist()) == ([0, 1], [0, 1])
        b = np.array([[True, False], [False, True]])
        r, c = pymodal.linear_sum_assignment(b, solver=method)
        assert c.tolist() == [1, 0]
        r, c = pymodal.linear_sum_assignment(b, maximize=True, solver=method)
        assert c.tolist() == [0, 1]
        # Non-contiguous and non-float64 views.
        big = np.arange(36, dtype=np.float32).reshape(6, 6)[::2, ::3]
        check_against_scipy(big)
        check_against_scipy(np.asfortranarray(np.random.default_rng(1).random((5, 7))))
        check_against_scipy(np.array([[1, 2], [3, 4]], dtype=np.uint8), maximize=True)


@pytest.mark.parametrize("shape", [(0, 0), (0, 3), (3, 0)])
def test_empty(shape):
    cost = np.zeros(shape)
    sr, sc = scipy_lsa(cost)
    for method in METHODS:
        r, c = pymodal.linear_sum_assignment(cost, solver=method)
        assert r.shape == c.shape == sr.shape == (0,)
        assert r.dtype == np.int64


@pytest.mark.parametrize("method", METHODS)
def test_errors_like_scipy(method):
    cases = [
        (np.array([1.0, 2.0]), False, "expected a matrix"),
        (np.zeros((2, 2, 2)), False, "expected a matrix"),
        (np.array([[np.nan, 1.0], [1.0, 2.0]]), False, "invalid numeric entries"),
        (np.array([[-np.inf, 1.0], [1.0, 2.0]]), False, "invalid numeric entries"),
        (np.array([[np.inf, 1.0], [1.0, 2.0]]), True, "invalid numeric entries"),
        (np.array([[np.inf, 1.0], [np.inf, 2.0]]), False, "infeasible"),
        (np.full((3, 2), np.inf), False, "infeasible"),
    ]
    for cost, maximize, msg in cases:
        with pytest.raises(ValueError, match=msg):
            scipy_lsa(cost, maximize=maximize)
        with pytest.raises(ValueError, match=msg):
            pymodal.linear_sum_assignment(cost, maximize, solver=method)


@pytest.mark.parametrize("method", METHODS)
def test_non_numeric_like_scipy(method):
    for cost in [np.array([["a", "b"], ["c", "d"]]), np.array([[1 + 1j, 2], [3, 4]])]:
        with pytest.raises(TypeError, match="Cannot cast"):
            scipy_lsa(cost)
        with pytest.raises(TypeError, match="Cannot cast"):
            pymodal.linear_sum_assignment(cost, solver=method)


def test_unknown_solver():
    with pytest.raises(ValueError, match="solver = auction: expected one of jv, hungarian, simplex"):
        pymodal.linear_sum_assignment([[1.0]], solver="auction")


def test_method_is_a_deprecated_alias_of_solver():
    cost = np.array([[4.0, 1.0], [2.0, 0.0]])
    with pytest.warns(DeprecationWarning, match="solver="):
        r, c = pymodal.linear_sum_assignment(cost, method="hungarian")
    assert cost[r, c].sum() == 3.0
    with pytest.raises(ValueError, match="solver= only"):
        pymodal.linear_sum_assignment(cost, solver="jv", method="jv")


def test_threshold():
    cost = np.array([[1.0, 9.0], [2.0, 8.0]])
    for method in METHODS:
        r, c = pymodal.linear_sum_assignment_threshold(cost, 3.0, solver=method)
        assert (r.tolist(), c.tolist()) == ([0], [0])
        r, c = pymodal.linear_sum_assignment_threshold(cost, 100.0, solver=method)
        assert cost[r, c].sum() == 9.0
    # Against the explicit (n+m)x(n+m) padding of docs/method.md §6.2 solved by scipy.
    rng = np.random.default_rng(5)
    for _ in range(30):
        n, m = rng.integers(1, 12, size=2)
        cost = rng.random((n, m))
        tau = float(rng.random())
        big = np.full((n + m, n + m), np.inf)
        big[:n, :m] = cost
        big[:n, m:][np.arange(n), np.arange(n)] = tau / 2
        big[n:, :m][np.arange(m), np.arange(m)] = tau / 2
        big[n:, m:] = 0.0
        br, bc = scipy_lsa(big)
        expected = big[br, bc].sum()
        for method in METHODS:
            r, c = pymodal.linear_sum_assignment_threshold(cost, tau, solver=method)
            assert np.all(cost[r, c] <= tau)
            got = cost[r, c].sum() + tau / 2 * (n + m - 2 * len(r))
            assert got == pytest.approx(expected, abs=1e-12)
