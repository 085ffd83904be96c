"""The CoM quadratic of one (joint, link) pair and its maximum over the CoM box
(:mod:`urpc.bounds.com_box`), against references written here independently: the quadratic
evaluated through ``phi(c)`` directly, dense grids, and the maximum over every face of the box by
``numpy.linalg`` (27 faces: each axis at its lower end, its upper end, or free)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from urpc.bounds.com_box import (
    N_QUADRATIC,
    box_maximum,
    quadratic_columns,
    unit_mass_parameters,
    vertex_values,
)


def G(y: np.ndarray, com: np.ndarray) -> float:
    """``y . phi(c)``, the quantity the columns represent."""
    return float(y @ unit_mass_parameters(com))


def q_of(z: np.ndarray, u: np.ndarray) -> float:
    """``alpha + beta . u + u^T K u / 2`` from the coefficient vector."""
    K = np.diag(z[4:7])
    K[0, 1] = K[1, 0] = z[7]
    K[0, 2] = K[2, 0] = z[8]
    K[1, 2] = K[2, 1] = z[9]
    return float(z[0] + z[1:4] @ u + 0.5 * u @ K @ u)


def face_maximum(z: np.ndarray) -> float:
    """Exact ``max q`` over ``[-1, 1]^3``: the vertices and, on every face, the stationary point
    of ``q`` restricted to it when it lies in the face (numpy's solver; singular faces skipped,
    their maxima lie on smaller faces)."""
    K = np.diag(z[4:7])
    K[0, 1] = K[1, 0] = z[7]
    K[0, 2] = K[2, 0] = z[8]
    K[1, 2] = K[2, 1] = z[9]
    best = -np.inf
    for pattern in itertools.product((-1.0, 1.0, None), repeat=3):
        free = [k for k in range(3) if pattern[k] is None]
        u = np.array([0.0 if p is None else p for p in pattern])
        if free:
            gradient = z[1:4] + K @ u
            try:
                u[free] = np.linalg.solve(K[np.ix_(free, free)], -gradient[free])
            except np.linalg.LinAlgError:
                continue
            if np.any(np.abs(u) > 1.0):
                continue
        best = max(best, q_of(z, u))
    return best


def bounds(z: np.ndarray, exact: bool) -> tuple[float, float]:
    """``(max q, min q)`` bounds through the compiled functions."""
    buffer = np.concatenate([z, np.zeros(8)])
    high, low = vertex_values(buffer, N_QUADRATIC)
    top = box_maximum(buffer, 1.0, exact, N_QUADRATIC, high)
    bottom = box_maximum(buffer, -1.0, exact, N_QUADRATIC, -low)
    return top, -bottom


def random_coefficients(rng: np.random.Generator) -> tuple[np.ndarray, bool]:
    """Random ``alpha, beta, K``, often with exact axes (zero slope and curvature); and whether the
    Hessian was made rank one (singular on every face: the fallback's case)."""
    z = rng.normal(size=N_QUADRATIC)
    z[1:4] *= rng.choice([0.1, 1.0, 5.0])
    singular = rng.random() < 0.2
    if singular:
        a = rng.normal(size=3)
        H = -np.outer(a, a) * rng.choice([-1.0, 1.0])
        z[4:7] = np.diag(H)
        z[7], z[8], z[9] = H[0, 1], H[0, 2], H[1, 2]
    for k in range(3):
        if rng.random() < 0.15:  # an exact axis
            z[[1 + k, 4 + k]] = 0.0
            z[[6 + j + k for j in range(3) if j != k]] = 0.0  # K_jk sits at 6 + j + k
    return z, singular


def test_columns_give_the_quadratic_of_the_unit_mass_parameters():
    """``y . B`` are the coefficients of ``u -> G(center + h u)``: checked at random points."""
    rng = np.random.default_rng(31)
    for _ in range(30):
        y = rng.normal(size=10)
        center = rng.normal(scale=0.3, size=3)
        half_width = rng.uniform(0, 0.2, 3) * (rng.random(3) > 0.2)
        z = y @ quadratic_columns(center, half_width)
        for u in rng.uniform(-1.5, 1.5, (5, 3)):
            expected = G(y, center + half_width * u)
            assert q_of(z, u) == pytest.approx(expected, rel=1e-12, abs=1e-12)


def test_vertex_values_are_q_at_the_vertices():
    rng = np.random.default_rng(32)
    for _ in range(20):
        z = rng.normal(size=N_QUADRATIC)
        buffer = np.concatenate([z, np.zeros(8)])
        high, low = vertex_values(buffer, N_QUADRATIC)
        values = [
            q_of(z, np.array([1.0 if (v >> k) & 1 else -1.0 for k in range(3)])) for v in range(8)
        ]
        np.testing.assert_allclose(buffer[N_QUADRATIC:], values, rtol=1e-13, atol=1e-13)
        assert (high, low) == (max(buffer[N_QUADRATIC:]), min(buffer[N_QUADRATIC:]))


def test_exact_maximum_is_the_face_maximum_and_bounds_a_dense_grid():
    """The exact bound is never below a dense grid (soundness), equals the independent face
    enumeration (to rounding) unless the Hessian is singular (then a face may fall back to its
    interpolation bound), and the plain interpolation bound is never below it; interior and face
    maxima (beyond every vertex) occur, so the faces are exercised."""
    rng = np.random.default_rng(33)
    grid = np.array(list(itertools.product(np.linspace(-1, 1, 21), repeat=3)))
    beyond_vertices = 0
    for _ in range(300):
        z, singular = random_coefficients(rng)
        scale = 1e-12 * (1 + np.abs(z).sum())
        (top, bottom), (plain_top, plain_bottom) = bounds(z, True), bounds(z, False)
        values = np.array([q_of(z, u) for u in grid])
        reference_top, reference_bottom = face_maximum(z), -face_maximum(-z)
        assert top >= values.max() - scale and bottom <= values.min() + scale
        assert plain_top >= top - scale and plain_bottom <= bottom + scale
        if not singular:
            assert top == pytest.approx(reference_top, abs=scale)
            assert bottom == pytest.approx(reference_bottom, abs=scale)
        corners = values[np.all(np.abs(grid) == 1.0, axis=1)]
        beyond_vertices += reference_top > corners.max() + 1e-6
    assert beyond_vertices > 30


def test_exact_maximum_on_one_axis_is_the_parabola_maximum():
    """One uncertain axis: ``max = (a + b) / 2 + M + (b - a)^2 / (16 M)`` for a concave parabola
    whose vertex is inside (``|b - a| < 4 M``), else the larger end."""
    rng = np.random.default_rng(34)
    for _ in range(100):
        z = np.zeros(N_QUADRATIC)
        z[0], z[1], z[4] = rng.normal(size=3)
        u = np.linspace(-1, 1, 100001)
        values = z[0] + z[1] * u + 0.5 * z[4] * u**2
        top, bottom = bounds(z, True)
        assert top == pytest.approx(values.max(), abs=1e-9)
        assert bottom == pytest.approx(values.min(), abs=1e-9)


def test_near_singular_faces_stay_sound():
    """Hessians within rounding of singular (a flat valley across the box): the concavity test
    cannot decide and the face falls back to its interpolation bound; never below the grid."""
    rng = np.random.default_rng(35)
    grid = np.array(list(itertools.product(np.linspace(-1, 1, 41), repeat=2)))
    for _ in range(200):
        a = rng.normal(size=2)
        tilt = 10 ** rng.uniform(-8, -2) * rng.choice([-1.0, 1.0])
        H = -np.outer(a, a) - tilt * np.eye(2)
        z = np.zeros(N_QUADRATIC)
        z[0], z[1:3] = rng.normal(), rng.normal(scale=0.1, size=2) + H @ rng.uniform(-1, 1, 2)
        z[4], z[5], z[7] = H[0, 0], H[1, 1], H[0, 1]
        values = np.array([q_of(z, np.array([u0, u1, 0.0])) for u0, u1 in grid])
        top, bottom = bounds(z, True)
        scale = 1e-12 * (1 + np.abs(z).sum())
        assert top >= values.max() - scale
        assert bottom <= values.min() + scale
