"""``hull``: the exact hull of ``w`` over a barycentric box, and a sound enclosure otherwise.

``w = Y (pi - pi0)`` is linear in the standard parameters ``pi``, so over a box
``pi in [pi_c - pi_r, pi_c + pi_r]`` its exact range per joint is::

    center = Y (pi_c - pi0),   radius = |Y| pi_r

A physical box (mass, CoM, inertia about the CoM) is first enclosed in barycentric coordinates by
interval arithmetic (``h = m c``, ``I_O = I_C + m S(c)^T S(c)``); that is sound but looser, because
the enclosure forgets that ``m``, ``h`` and ``I_O`` are coupled (``docs/bounds.md`` reports how much).
"""

from __future__ import annotations

import numpy as np

from ..regressor import link_regressor_map
from ..uncertainty import LinkBox
from . import interval as ia
from .base import ROUNDING_ABSOLUTE, ROUNDING_RELATIVE, BoundMethod


def barycentric_enclosure(box: LinkBox) -> tuple[np.ndarray, np.ndarray]:
    """``(lower, upper)`` of the standard parameters over a link box (exact for barycentric
    boxes, an outward-rounded interval enclosure for physical ones)."""
    if box.kind == "barycentric":
        return box.lower.copy(), box.upper.copy()
    lo, hi = box.lower, box.upper
    m = (lo[0:1], hi[0:1])
    c = [(lo[k : k + 1], hi[k : k + 1]) for k in (1, 2, 3)]
    ic = {name: (lo[k : k + 1], hi[k : k + 1]) for k, name in zip(range(4, 10), ("xx", "xy", "yy", "xz", "yz", "zz"))}
    h = [ia.mul(m, ck) for ck in c]
    sq = [ia.square(ck) for ck in c]
    io = {
        "xx": ia.add(ic["xx"], ia.mul(m, ia.add(sq[1], sq[2]))),
        "yy": ia.add(ic["yy"], ia.mul(m, ia.add(sq[0], sq[2]))),
        "zz": ia.add(ic["zz"], ia.mul(m, ia.add(sq[0], sq[1]))),
        "xy": ia.sub(ic["xy"], ia.mul(m, ia.mul(c[0], c[1]))),
        "xz": ia.sub(ic["xz"], ia.mul(m, ia.mul(c[0], c[2]))),
        "yz": ia.sub(ic["yz"], ia.mul(m, ia.mul(c[1], c[2]))),
    }
    parts = [m, *h, io["xx"], io["xy"], io["yy"], io["xz"], io["yz"], io["zz"]]
    lower = np.concatenate([p[0] for p in parts])
    upper = np.concatenate([p[1] for p in parts])
    return lower, upper


class HullBound(BoundMethod):
    """Exact hull over barycentric boxes; interval-enclosed physical boxes (sound, looser)."""

    name = "hull"

    def __init__(self, robot, box):
        super().__init__(robot, box)
        links = box.uncertain_links
        self._map = link_regressor_map(self.robot, [b.link for b in links])
        lower = np.concatenate([barycentric_enclosure(b)[0] for b in links]) if links else np.zeros(0)
        upper = np.concatenate([barycentric_enclosure(b)[1] for b in links]) if links else np.zeros(0)
        nominal = (
            np.concatenate([b.standard_parameters(b.nominal) for b in links]) if links else np.zeros(0)
        )
        center, radius = 0.5 * (lower + upper), 0.5 * (upper - lower)
        self._offset = center - nominal
        # One matmul gives the radius plus the rounding margin (see base.ROUNDING_RELATIVE).
        self._weight = radius + ROUNDING_RELATIVE * (np.abs(center) + np.abs(nominal) + radius)

    def enclose_regressor(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        Y_links = Y @ self._map
        center = Y_links @ self._offset
        radius = np.abs(Y_links) @ self._weight + ROUNDING_ABSOLUTE
        return self._add_disturbance(center - radius, center + radius)
