"""Arb balls: the working precision, exact conversions from doubles and outward rounding back to
doubles, and 3-vector algebra on balls."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from flint import arb

from ...errors import InputError

#: Working precision of the Arb balls [bits]. Inputs are doubles (exact at any precision); 64 bits
#: keep the midpoints' rounding well below the double resolution of the result.
PRECISION = 64

Vec = tuple[arb, arb, arb]
Motion = tuple[Vec, Vec]  # (linear, angular)
Mat = tuple[Vec, Vec, Vec]  # rows

ZERO = arb(0)
HALF = arb(0.5)
ZERO3: Vec = (ZERO, ZERO, ZERO)
#: Symmetric 3x3 tensor components in Pinocchio's order: xx, xy, yy, xz, yz, zz.
SYM_INDEX = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))


# ============================================================================ conversions
def interval_ball(lower: float, upper: float) -> arb:
    """An Arb ball containing the whole interval ``[lower, upper]`` (both ends exactly)."""
    lo, hi = arb(float(lower)), arb(float(upper))
    if lower == upper:
        return lo
    if not lower < upper:
        raise InputError(f"empty interval [{lower}, {upper}]")
    return lo.union(hi)


def lower_float(ball: arb) -> float:
    """The largest double ``x`` with ``x <= ball`` as checked exactly (outward rounding down)."""
    if not ball.is_finite():
        return -np.inf
    bound = ball.lower()  # an exact ball (zero radius) below every point of ``ball``
    x = float(bound)
    while arb(x) > bound:
        x = float(np.nextafter(x, -np.inf))
    return x


def upper_float(ball: arb) -> float:
    """The smallest double ``x`` with ``x >= ball`` as checked exactly (outward rounding up)."""
    if not ball.is_finite():
        return np.inf
    bound = ball.upper()
    x = float(bound)
    while arb(x) < bound:
        x = float(np.nextafter(x, np.inf))
    return x


def to_vec(values: Sequence[float]) -> Vec:
    return (arb(float(values[0])), arb(float(values[1])), arb(float(values[2])))


def to_mat(matrix: np.ndarray) -> Mat:
    return tuple(to_vec(row) for row in np.asarray(matrix, dtype=float))  # type: ignore[return-value]


# ============================================================================ 3-vector algebra
def add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(s: arb, a: Vec) -> Vec:
    return (s * a[0], s * a[1], s * a[2])


def cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a: Vec, b: Vec) -> arb:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def rotate(R: Mat, v: Vec) -> Vec:
    return (dot(R[0], v), dot(R[1], v), dot(R[2], v))


def rotate_back(R: Mat, v: Vec) -> Vec:
    """``R^T v``."""
    return (
        R[0][0] * v[0] + R[1][0] * v[1] + R[2][0] * v[2],
        R[0][1] * v[0] + R[1][1] * v[1] + R[2][1] * v[2],
        R[0][2] * v[0] + R[1][2] * v[1] + R[2][2] * v[2],
    )


def sym_times(I: Sequence[arb], v: Vec) -> Vec:
    """Symmetric tensor (components xx, xy, yy, xz, yz, zz) times a vector."""
    xx, xy, yy, xz, yz, zz = I
    return (
        xx * v[0] + xy * v[1] + xz * v[2],
        xy * v[0] + yy * v[1] + yz * v[2],
        xz * v[0] + yz * v[1] + zz * v[2],
    )
