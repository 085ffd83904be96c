"""Minimal vectorized interval arithmetic on ``(lower, upper)`` numpy pairs, outward-rounded.

Used to enclose a physical box (mass, center of mass, inertia about the CoM) in barycentric
coordinates. Every result is widened by one ulp in each direction (``np.nextafter``), which covers
the rounding of the single floating-point operation that produced each end.
"""

from __future__ import annotations

import numpy as np

Interval = tuple[np.ndarray, np.ndarray]


def _out(lo: np.ndarray, hi: np.ndarray) -> Interval:
    return np.nextafter(lo, -np.inf), np.nextafter(hi, np.inf)


def add(a: Interval, b: Interval) -> Interval:
    return _out(a[0] + b[0], a[1] + b[1])


def sub(a: Interval, b: Interval) -> Interval:
    return _out(a[0] - b[1], a[1] - b[0])


def mul(a: Interval, b: Interval) -> Interval:
    products = np.stack([a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]])
    return _out(products.min(axis=0), products.max(axis=0))


def square(a: Interval) -> Interval:
    lo2, hi2 = a[0] * a[0], a[1] * a[1]
    upper = np.maximum(lo2, hi2)
    lower = np.where((a[0] <= 0) & (a[1] >= 0), 0.0, np.minimum(lo2, hi2))
    return _out(lower, upper)
