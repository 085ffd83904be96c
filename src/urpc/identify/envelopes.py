"""Interval bounds of a physical link's quantities (``m``, ``c``, ``h = m c``, ``w = m c c^T``,
``I_C``, the standard parameters), from which the McCormick envelopes of
:mod:`urpc.identify.problem` are built; every interval is widened for its rounding."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.parameter_box import LinkBox


def _mul(a, b):
    products = [a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]]
    return min(products), max(products)


def _square(a):
    lo, hi = a
    top = max(lo * lo, hi * hi)
    return (0.0 if lo <= 0 <= hi else min(lo * lo, hi * hi)), top


def _add(*intervals):
    return sum(i[0] for i in intervals), sum(i[1] for i in intervals)


def _outward(interval):
    """An interval computed in floating point, widened for its rounding (relative 1e-12); an
    exact zero (a product with an exactly known zero) stays exact."""
    lo, hi = interval
    if lo == hi == 0.0:
        return 0.0, 0.0
    slack = 1e-12 * (abs(lo) + abs(hi)) + 1e-300
    return lo - slack, hi + slack


@dataclass
class LinkBounds:
    """Current bounds of a physical link's ``m``, ``c``, ``h`` and ``I_C`` (prior, then tightened
    by identification rounds)."""

    mass: tuple[float, float]
    com: list[tuple[float, float]]
    inertia: list[tuple[float, float]]
    h: list[tuple[float, float]]

    @classmethod
    def of_prior(cls, box: LinkBox) -> LinkBounds:
        lo, hi = box.lower, box.upper
        mass = (float(lo[0]), float(hi[0]))
        com = [(float(lo[1 + k]), float(hi[1 + k])) for k in range(3)]
        inertia = [(float(lo[4 + k]), float(hi[4 + k])) for k in range(6)]
        h = [_outward(_mul(mass, c)) for c in com]
        return cls(mass, com, inertia, h)

    def w_bounds(self, j: int, k: int) -> tuple[float, float]:
        """Bounds of ``w_jk = m c_j c_k``: the tighter of ``[h_j] [c_k]`` and ``[m][c_j][c_k]``."""
        direct = _mul(self.h[j], self.com[k])
        triple = _mul(self.mass, _square(self.com[j]) if j == k else _mul(self.com[j], self.com[k]))
        lo, hi = max(direct[0], triple[0]), min(direct[1], triple[1])
        if j == k:
            lo = max(lo, 0.0)
        return _outward((lo, max(lo, hi)))

    def standard(self) -> tuple[np.ndarray, np.ndarray]:
        """Interval enclosure of the standard parameters ``[m, h, I_O]``."""
        lo, hi = np.empty(10), np.empty(10)
        lo[0], hi[0] = self.mass
        for k in range(3):
            lo[1 + k], hi[1 + k] = self.h[k]
        w = {(j, k): self.w_bounds(j, k) for j in range(3) for k in range(3)}
        extra = {
            0: _add(w[1, 1], w[2, 2]),
            1: (-w[0, 1][1], -w[0, 1][0]),
            2: _add(w[0, 0], w[2, 2]),
            3: (-w[0, 2][1], -w[0, 2][0]),
            4: (-w[1, 2][1], -w[1, 2][0]),
            5: _add(w[0, 0], w[1, 1]),
        }
        for n in range(6):
            lo[4 + n], hi[4 + n] = _outward(_add(self.inertia[n], extra[n]))
        return lo, hi
