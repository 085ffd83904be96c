"""Ball arithmetic against exact rational arithmetic: every product, sum and cross-product
matrix encloses the exact result of every point of its operands (corners and interior draws),
for the compiled batched product, its shared-matrix form and numpy's fallback alike."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from urpc.model.ball_arithmetic import Ball, matmul, skew


def _exact_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` of 2-D float arrays in exact rational arithmetic, as Fractions."""
    rows, terms = a.shape
    columns = b.shape[1]
    return np.array(
        [
            [
                sum(Fraction(a[i, k]) * Fraction(b[k, j]) for k in range(terms))
                for j in range(columns)
            ]
            for i in range(rows)
        ],
        dtype=object,
    )


def _inside(ball_mid: float, ball_rad: float, exact: Fraction) -> bool:
    return abs(exact - Fraction(ball_mid)) <= Fraction(ball_rad)


def _points(ball: Ball, rng, count: int):
    """Corners (each entry at either end) and interior draws of a ball, pulled in by 1e-9 of
    the radius so that rounding ``mid + s rad`` cannot put them outside."""
    for k in range(count):
        if k < count // 2:
            signs = rng.choice([-1.0, 1.0], size=ball.mid.shape)
        else:
            signs = rng.uniform(-1.0, 1.0, size=ball.mid.shape)
        yield ball.mid + signs * ball.rad * (1 - 1e-9)


def _random_ball(rng, shape, scale=1.0, radius=1e-3):
    mid = rng.normal(size=shape) * scale * 10.0 ** rng.integers(-3, 4, size=shape)
    return Ball(mid, np.abs(rng.normal(size=shape)) * radius * np.abs(mid))


@pytest.mark.parametrize(
    "shape_a, shape_b",
    [
        ((4, 3, 5), (4, 5, 2)),  # same batch: the compiled kernel
        ((2, 3, 4, 3), (2, 3, 3, 3)),  # same batch, two batch axes
        ((3, 4), (5, 4, 2)),  # one matrix for the whole batch: the compiled kernel
        ((4, 3, 5), (5, 2)),  # a batch times one matrix: numpy's product
        ((3, 5), (5, 2)),  # plain matrices
    ],
)
def test_matmul_encloses_the_exact_product_of_every_point(shape_a, shape_b):
    rng = np.random.default_rng(hash((shape_a, shape_b)) % 2**32)
    A, B = _random_ball(rng, shape_a), _random_ball(rng, shape_b)
    C = matmul(A, B)
    batch = np.broadcast_shapes(shape_a[:-2], shape_b[:-2])
    assert C.mid.shape == batch + (shape_a[-2], shape_b[-1])
    assert np.all(C.rad >= 0)
    for a, b in zip(_points(A, rng, 6), _points(B, rng, 6), strict=True):
        a_full = np.broadcast_to(a, batch + a.shape[-2:])
        b_full = np.broadcast_to(b, batch + b.shape[-2:])
        for index in np.ndindex(batch):
            exact = _exact_product(a_full[index], b_full[index])
            for (i, j), value in np.ndenumerate(exact):
                assert _inside(C.mid[index][i, j], C.rad[index][i, j], value)


def test_matmul_of_point_matrices_bounds_its_own_rounding():
    """With no radius at all, the radius still covers the rounding of the midpoint: terms of
    1e16 that cancel leave a floating-point sum off the exact one by whole units."""
    rng = np.random.default_rng(7)
    a = rng.normal(size=(50, 3, 6)) * 1e16
    a[..., 1::2] = -a[..., 0::2] + rng.normal(size=(50, 3, 3))  # pairs that nearly cancel
    b = np.ones((50, 6, 2)) + rng.normal(size=(50, 6, 2)) * 1e-17
    C = matmul(Ball.point(a), Ball.point(b))
    off = 0
    for index in range(50):
        exact = _exact_product(a[index], b[index])
        for (i, j), value in np.ndenumerate(exact):
            assert _inside(C.mid[index, i, j], C.rad[index, i, j], value)
            off += Fraction(C.mid[index, i, j]) != value
    assert off > 0  # the midpoints are rounded: the radius is what makes the product sound


def test_sum_and_difference_enclose_every_point():
    rng = np.random.default_rng(3)
    x, y = _random_ball(rng, (40,)), _random_ball(rng, (40,))
    for op in (lambda p, q: p + q, lambda p, q: p - q):
        ball = op(x, y)
        for a, b in zip(_points(x, rng, 6), _points(y, rng, 6), strict=True):
            for k in range(40):
                exact = op(Fraction(a[k]), Fraction(b[k]))
                assert _inside(ball.mid[k], ball.rad[k], exact)


def test_skew_is_the_cross_product_matrix_with_non_negative_radii():
    rng = np.random.default_rng(5)
    x = _random_ball(rng, (6, 3))
    S = skew(x)
    y = rng.normal(size=3)
    for k in range(6):
        np.testing.assert_allclose(S.mid[k] @ y, np.cross(x.mid[k], y), rtol=1e-12, atol=1e-12)
        a, b, c = x.rad[k]
        expected = np.array([[0, c, b], [c, 0, a], [b, a, 0]])
        np.testing.assert_array_equal(S.rad[k], expected)  # |S(v) - S(mid)| <= S's radius
