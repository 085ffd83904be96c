"""``hull``: the exact hull of ``w`` over a barycentric box, and a sound enclosure otherwise.

``w = Y (pi - pi0)`` is linear in the standard parameters ``pi``, so over a box
``pi in [pi_c - pi_r, pi_c + pi_r]`` its exact range per joint is::

    center = Y (pi_c - pi0),   radius = |Y| pi_r

A physical box (mass, CoM, inertia about the CoM) is first enclosed in barycentric coordinates by
interval arithmetic (``h = m c``, ``I_O = I_C + m S(c)^T S(c)``); that is sound but looser, because
the enclosure forgets that ``m``, ``h`` and ``I_O`` are coupled (``docs/bounds.md`` reports how much).

A link whose frame is its joint's frame (the child link of a URDF joint) has its parameters in
``Y``'s own columns, so its radius is a plain ``|Y| pi_r``. Other links (a payload, a hand fixed to
the flange) see ``Y A``, with ``A`` the placement matrix of :func:`~urpc.model.regressor.placement_matrix`,
and take one small batched product per control step.
"""

from __future__ import annotations

import numpy as np

from ..model.regressor import SlotineLiRegressor
from ..model.uncertainty import LinkBox
from . import interval as ia
from .base import (
    ROUNDING_ABSOLUTE,
    ROUNDING_RELATIVE,
    RegressorBound,
    envelope_weights,
    link_body_placement,
)


def barycentric_enclosure(box: LinkBox) -> tuple[np.ndarray, np.ndarray]:
    """``(lower, upper)`` of the standard parameters over a link box (exact for barycentric
    boxes, an outward-rounded interval enclosure for physical ones)."""
    if box.kind == "barycentric":
        return box.lower.copy(), box.upper.copy()
    lo, hi = box.lower, box.upper
    m = (lo[0:1], hi[0:1])
    c = [(lo[k : k + 1], hi[k : k + 1]) for k in (1, 2, 3)]
    ic = {
        name: (lo[k : k + 1], hi[k : k + 1])
        for k, name in zip(range(4, 10), ("xx", "xy", "yy", "xz", "yz", "zz"), strict=True)
    }
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


class HullBound(RegressorBound):
    """Exact hull over barycentric boxes; interval-enclosed physical boxes (sound, looser)."""

    name = "hull"

    def __init__(self, robot, box):
        super().__init__(robot, box)
        n_columns = 10 * (self.robot.model.njoints - 1)
        # Weights act on Y4 = SCALE * Y_SL (SlotineLiRegressor.scaled), hence the factor.
        scale = 1.0 / SlotineLiRegressor.SCALE
        center_weight = np.zeros(n_columns)  # center = Y4 @ center_weight
        radius_weight = np.zeros(n_columns)  # body-frame links' radii and all rounding margins
        placed = []  # links off their body frame: radius += sum |Y4 @ (A diag(pi_r))|
        magnitudes = np.zeros(n_columns)  # p_j per column, body coordinates
        for link_box in box.uncertain_links:
            lower, upper = barycentric_enclosure(link_box)
            nominal = link_box.standard_parameters(link_box.nominal)
            center, radius = 0.5 * (lower + upper), 0.5 * (upper - lower)
            body, A = link_body_placement(self.robot, link_box.link)
            columns = slice(10 * body, 10 * body + 10)
            center_weight[columns] += scale * (A @ (center - nominal))
            # Rounding (base.ROUNDING_RELATIVE): every term of the sums is bounded by
            # |Y_j| (|A| (|center| + |nominal| + radius))_j.
            magnitude = np.abs(A) @ (np.abs(center) + np.abs(nominal) + radius)
            radius_weight[columns] += scale * ROUNDING_RELATIVE * magnitude
            magnitudes[columns] += magnitude
            if np.array_equal(A, np.eye(10)):
                radius_weight[columns] += scale * radius
            else:
                placed_columns = np.zeros((n_columns, 10))
                placed_columns[columns] = scale * A * radius
                placed.append(placed_columns[:, radius > 0])
        # Y4 @ linear = center, or [center, the placed links' radius terms] (one product).
        self._linear = np.column_stack([center_weight, *placed]) if placed else center_weight
        self._ones = np.ones(self._linear.shape[1]) if placed else None
        self._radius_weight = radius_weight
        # Rounding inside the regressor (base.ROUNDING_RECURSION): K_i per unit envelope, plus
        # the absolute margin (and the known disturbance bound, in rho) per joint.
        # Below the floor (4 times the envelope at rest: gravity and rates up to about 10 rad/s)
        # the margin is the constant floor K_i, so ordinary states cost no array operation.
        self._envelope_weight = scale * envelope_weights(self.robot, magnitudes)
        self._envelope_floor = 4.0 * self.regressor.envelope_at_rest()
        self._offset = ROUNDING_ABSOLUTE + self._envelope_floor * self._envelope_weight
        self._constant = self._offset + (self.disturbance_bound or 0.0)
        self._regressor = self.regressor
        self._scaled_regressor = self.regressor.scaled

    def _center_radius(self, Y4: np.ndarray, envelope: float) -> tuple[np.ndarray, np.ndarray]:
        """Center and radius (with the rounding margins) from ``Y4 = SCALE * Y_SL``."""
        linear = Y4.dot(self._linear)
        radius = np.abs(Y4).dot(self._radius_weight)
        radius += self._offset  # max(envelope, floor) K_i + ROUNDING_ABSOLUTE
        if envelope > self._envelope_floor:
            radius += (envelope - self._envelope_floor) * self._envelope_weight
        if self._ones is None:
            return linear, radius
        radius += np.abs(linear[:, 1:]).sum(axis=1)
        return linear[:, 0], radius

    def enclose(self, q, qd, qd_a, qdd_a):
        Y4 = self._scaled_regressor(q, qd, qd_a, qdd_a)
        center, radius = self._center_radius(Y4, self._regressor.envelope)
        lower, upper = self._add_disturbance(center - radius, center + radius)
        return self.add_joint_terms(lower, upper, qd, qd_a, qdd_a)

    def enclose_regressor(
        self, Y: np.ndarray, envelope: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        envelope = self._envelope(Y, envelope)
        center, radius = self._center_radius(SlotineLiRegressor.SCALE * Y, envelope)
        return self._add_disturbance(center - radius, center + radius)

    def rho(self, q, qd, qd_a, qdd_a):
        """``|center| + radius`` (= ``max(|lower|, |upper|)``) [N m]. ``ndarray.dot`` rather than
        ``@``: the same BLAS call with half the Python overhead."""
        if self.joints is not None:
            return super().rho(q, qd, qd_a, qdd_a)
        Y4 = self._scaled_regressor(q, qd, qd_a, qdd_a)
        rho = np.abs(Y4).dot(self._radius_weight)
        linear = np.abs(Y4.dot(self._linear))  # |center| (and the placed radius terms)
        rho += linear if self._ones is None else linear.dot(self._ones)
        rho += self._constant
        envelope = self._regressor.envelope
        if envelope > self._envelope_floor:
            rho += (envelope - self._envelope_floor) * self._envelope_weight
        return rho
