"""The one-period bound's closed forms against direct evaluation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from urpc.control.period_bound import disturbance_response, response_sum


def _direct(a: float, terms: int = 200_000) -> float:
    """``sum_j max_{a <= x <= 1} x (1 - x)^j`` by a dense grid of ``x`` on each early term (the
    maximum over the grid is a lower bound of each term, so the sum is a lower bound of S) and
    the tail past ``terms`` left out (also a lower bound)."""
    total = 0.0
    grid = np.linspace(a, 1.0, 20001)
    for j in range(200):
        total += float(np.max(grid * (1 - grid) ** j))
    j = np.arange(200, terms, dtype=float)
    x = np.maximum(a, 1.0 / (j + 1))  # the exact maximiser of x (1 - x)^j on [a, 1]
    return total + float(np.sum(x * (1 - x) ** j))


@pytest.mark.parametrize("a", [1.0, 0.9, 0.5, 0.27, 0.1, 1 / 30, 0.01, 1e-3, 3e-4])
def test_response_sum_bounds_the_direct_sum_and_is_close_to_it(a):
    value = float(response_sum(np.array([a]))[0])
    direct = _direct(a)
    assert value >= direct
    assert value <= direct * (1 + 1e-3) + (1 - a) ** 200_000  # the direct sum's missing tail


def test_response_sum_is_infinite_below_the_table_and_decreasing_in_a():
    assert math.isinf(float(response_sum(np.array([1e-4]))[0]))
    a = np.linspace(1 / 4096, 1.0, 5000)
    values = response_sum(a)
    assert np.all(np.diff(values) <= 1e-12 * values[1:])


def _worst_response(Phi: list[np.ndarray], starts: list[np.ndarray]) -> float:
    """A lower bound of ``sup ||sum_j Phi_j d_j||`` over ``||d_j|| <= 1``: for a unit ``x`` the
    history ``d_j = Phi_j x / ||Phi_j x||`` reaches ``x^T r_d = sum_j ||Phi_j x||``, which is
    convex in ``x``; it is raised by the fixed-point ascent ``x <- sum_j Phi_j^2 x / ||Phi_j
    x||`` (normalized) from each start."""
    best = 0.0
    for x in starts:
        x = x / np.linalg.norm(x)
        for _ in range(200):
            images = [P @ x for P in Phi]
            norms = [np.linalg.norm(y) for y in images]
            best = max(best, float(sum(norms)))
            step = sum(P @ y / max(n, 1e-300) for P, y, n in zip(Phi, images, norms, strict=True))
            x = step / np.linalg.norm(step)
    return best


def _loop(rng, lightest: np.ndarray, heavy: float, n: int = 4, T=1e-3, D=1e6):
    """A frozen loop: a plant ``M = Q diag(lam) Q^T`` with the given light eigenvalues and heavy ones, the law's
    ``M_L = M^1/2 B M^1/2 <= M`` (``B`` in [0.3, 1]), the implicit law's ``K`` at gain ``D``;
    the arguments of :func:`disturbance_response` and the matrices ``Phi_j``."""
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    lam = np.concatenate([lightest, np.full(n - len(lightest), heavy)])
    root = (Q * np.sqrt(lam)) @ Q.T
    U, _ = np.linalg.qr(rng.standard_normal((n, n)))
    B = (U * rng.uniform(0.3, 1.0, n)) @ U.T
    M_L = root @ B @ root
    K = D * np.linalg.solve(M_L + D * T * np.eye(n), M_L)
    K = 0.5 * (K + K.T)
    inverse_root = (Q / np.sqrt(lam)) @ Q.T
    A = inverse_root @ (T * K) @ inverse_root
    a = float(np.linalg.eigvalsh(A)[0])
    J = int(np.ceil(np.log(1e-9) / np.log(1 - a)))
    step = np.eye(n) - A
    Phi, power = [], np.eye(n)
    for _ in range(J):
        Phi.append(T * inverse_root @ power @ inverse_root)
        power = power @ step
    args = (
        T, 1.0, D, np.trace(np.linalg.inv(M_L)), float(np.linalg.eigvalsh(M_L)[0]),
        float(lam.min()), a, n,
    )  # fmt: skip
    starts = [rng.standard_normal(n) for _ in range(6)] + list(np.eye(n))
    return args, Phi, starts


@pytest.mark.parametrize(
    "lightest",
    [[0.01], [0.01, 0.012, 0.015], [0.02, 0.02, 0.02, 0.02], [0.005, 0.05]],
    ids=["one light mode", "three light modes", "all alike", "two apart"],
)
def test_disturbance_response_bounds_the_worst_history(lightest):
    """Both bounds (the trace, Cauchy-Schwarz) hold against the worst history found by ascent, on
    random frozen loops; with several light modes the second is the smaller."""
    rng = np.random.default_rng(len(lightest))
    for _ in range(5):
        args, Phi, starts = _loop(rng, np.array(lightest), heavy=2.0)
        bound = float(disturbance_response(*args))
        worst = _worst_response(Phi, starts)
        assert worst <= bound * (1 + 1e-9)
        T, _, D, trace, *_ = args
        trace_bound = T * (trace + args[-1] / (D * T))
        assert bound <= trace_bound
        if len(lightest) >= 3:
            assert bound < 0.9 * trace_bound


def test_disturbance_response_falls_back_to_the_trace_where_a_model_fails():
    value = disturbance_response(1e-3, 1.0, 1e6, np.array([10.0]), np.array([0.1]),
                                 np.array([0.1]), np.array([np.nan]), 2)  # fmt: skip
    assert np.isclose(value[0], 1e-3 * (10.0 + 2 / 1e3))
