"""The one-period bound's closed forms against direct evaluation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from urpc.control.period_bound import response_sum


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
