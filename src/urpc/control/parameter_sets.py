"""The parameter sets the certificate bounds over (:mod:`urpc.control.cells`): each uncertain
link's standard parameters as a zonotope, ``delta = c + sum_i s_i w_i d_i`` with ``s`` in
``[-1, 1]^p``, and the whole plant's as their sum placed into the joint bodies.

A physical box whose centre of mass is exact (``mass: 10%``, a payload of known geometry) maps
its mass and its inertia about the centre of mass linearly to the standard parameters::

    pi = m v(c) + (0, 0, 0, 0, I_C),    v(c) = (1, c, c_y^2 + c_z^2, -c_x c_y, c_x^2 + c_z^2,
                                                 -c_x c_z, -c_y c_z, c_x^2 + c_y^2)

(``I_O = I_C + m (|c|^2 1 - c c^T)``, Pinocchio's order ``xx, xy, yy, xz, yz, zz``): a segment
along ``v(c)`` plus the axes of ``I_C``'s intervals, exactly, where its barycentric enclosure
(a box, one axis per coordinate that moves) holds up to ``2^5`` times as many corners and
directions that no plant takes. Any other box is its barycentric enclosure: one generator per
moving coordinate. The centre ``c`` and the directions ``d_i`` are balls that hold the exact
values (the products of ``v(c)`` round); the weights ``w_i`` are exact.

A direction is identified by its link and kind (``"mass"``, or the coordinate's index), so that
the pieces of a box (:mod:`urpc.control.box_pieces`, cut along mass intervals) share their
directions and differ in their weights only.

In the whole plant's set, a body into which many uncertain links are merged (20 directions or
more: Baxter's hands) keeps its 10 coordinate axes instead, weighted by the interval hull of its
part of the zonotope: sound, at the price of that part's correlations, and what keeps the
Coriolis forms' cost (one matrix per direction) at 10 per body at most (470 directions become
150 on Baxter; the shipped arms, with 13 at most, are unchanged).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..bounds.base import link_body_placement
from ..bounds.hull import barycentric_enclosure
from ..model.ball_arithmetic import U, stack
from ..model.regressor_balls import Ball, matvec, parameters_of
from ..model.uncertainty import LinkBox, ParameterBox

#: Relative margin on the rounding of a centre or a direction computed in floating point (a few
#: operations of relative error ``u`` each).
ROUNDING = 16 * U


@dataclasses.dataclass(frozen=True)
class LinkParameters:
    """One link's parameters relative to its nominal, in its link frame: ``delta = c + sum_i s_i
    w_i d_i``, ``|s_i| <= 1`` (module docstring); ``A`` places them in their body, whose columns of
    ``Y_SL`` are ``columns``.

    Attributes:
        columns: The body's 10 columns of the regressor.
        A: ``pi_body = A pi_link``.
        centre: ``c``, a ball (10,).
        directions: ``d_i``, balls (p, 10).
        weights: ``w_i >= 0`` (p,).
        keys: What each direction is (its link and kind), to share it between pieces.
    """

    columns: slice
    A: np.ndarray
    centre: Ball
    directions: Ball
    weights: np.ndarray
    keys: tuple[tuple[str, str], ...]

    @property
    def generators(self) -> np.ndarray:
        """``w_i d_i`` (midpoints), as columns (10, p)."""
        return self.directions.mid.T * self.weights

    @property
    def magnitude(self) -> np.ndarray:
        """``|delta|`` over the set, per coordinate (10,)."""
        return np.abs(self.centre.mid) + self.residual + self.weights @ np.abs(self.directions.mid)

    @property
    def residual(self) -> np.ndarray:
        """What the balls' radii add to ``|delta|`` per coordinate (10,)."""
        return self.centre.rad + self.weights @ self.directions.rad


def link_parameters(robot, box: LinkBox) -> LinkParameters:
    """The zonotope of one link box, relative to its nominal (module docstring)."""
    body, A = link_body_placement(robot, box.link)
    nominal = box.standard_parameters(box.nominal)
    lower, upper = np.asarray(box.lower, dtype=float), np.asarray(box.upper, dtype=float)
    directions, weights, keys = [], [], []
    if box.kind == "physical" and np.array_equal(lower[1:4], upper[1:4]):
        cx, cy, cz = lower[1:4]
        v = np.array(
            [1.0, cx, cy, cz, cy * cy + cz * cz, -cx * cy, cx * cx + cz * cz, -cx * cz, -cy * cz,
             cx * cx + cy * cy]
        )  # fmt: skip
        v_rad = ROUNDING * np.abs(v)
        m_mid, m_rad = _middle(lower[0], upper[0])
        i_mid, i_rad = _middle(lower[4:], upper[4:])
        centre = m_mid * v + np.r_[np.zeros(4), i_mid] - nominal
        centre_rad = abs(m_mid) * v_rad + ROUNDING * (
            np.abs(m_mid * v) + np.abs(centre) + np.abs(nominal)
        )
        if m_rad > 0:
            directions.append(Ball(v, v_rad))
            weights.append(m_rad)
            keys.append((box.link, "mass"))
        for k in np.flatnonzero(i_rad > 0):
            directions.append(Ball.point(np.eye(10)[4 + k]))
            weights.append(float(i_rad[k]))
            keys.append((box.link, str(4 + k)))
    else:
        lo, hi = barycentric_enclosure(box)
        mid, rad = _middle(lo, hi)
        centre = mid - nominal
        centre_rad = ROUNDING * (np.abs(centre) + np.abs(nominal) + np.abs(mid))
        for k in np.flatnonzero(rad > 0):
            directions.append(Ball.point(np.eye(10)[k]))
            weights.append(float(rad[k]))
            keys.append((box.link, str(k)))
    stacked = stack(directions, 0) if directions else Ball.point(np.zeros((0, 10)))
    return LinkParameters(
        slice(10 * body, 10 * body + 10), A, Ball(centre, centre_rad), stacked,
        np.asarray(weights, dtype=float), tuple(keys),
    )  # fmt: skip


def _middle(lower, upper) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint and a radius (rounded up) with ``[lower, upper]`` in ``[mid - rad, mid + rad]``."""
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    mid = 0.5 * (lower + upper)
    rad = np.maximum(upper - mid, mid - lower) * (1 + 4 * U)
    return mid, rad


@dataclasses.dataclass(frozen=True)
class PlantParameters:
    """The standard parameters of the joint bodies over a box, ``pi = c + sum_i s_i w_i d_i``,
    ``|s_i| <= 1``: the nominal plus each uncertain link's :class:`LinkParameters` placed into
    its body (balls (10 dof,) and (p, 10 dof), weights (p,), the directions' keys)."""

    centre: Ball
    directions: Ball
    weights: np.ndarray
    keys: tuple[tuple[str, str], ...]
    #: For a shifted set, the centre it was shifted from and the shift (``centre = base - by``),
    #: so that quantities linear in the parameters can be formed from those of the two.
    shift: tuple[Ball, np.ndarray] | None = None

    def shifted(self, by: np.ndarray) -> PlantParameters:
        """The set minus ``by`` (exact parameters, e.g. the nominal: the mismatch's set)."""
        mid = self.centre.mid - by
        rad = self.centre.rad + ROUNDING * (np.abs(mid) + np.abs(by))
        return dataclasses.replace(self, centre=Ball(mid, rad), shift=(self.centre, by))

    def weights_along(self, keys: tuple[tuple[str, str], ...]) -> np.ndarray:
        """The weights of ``keys``' directions in this set (0 where it has none of them)."""
        own = dict(zip(self.keys, self.weights, strict=True))
        return np.array([own.get(key, 0.0) for key in keys])

    def magnitude(self, Y: Ball) -> np.ndarray:
        """``max |Y pi|`` over the set, for balls ``Y`` (..., m, 10 dof): ``|Y c| + sum_i w_i
        |Y d_i|`` in ball arithmetic (..., m)."""
        out = matvec(Y, self.centre).magnitude
        for k, w in enumerate(self.weights):
            out = out + w * matvec(Y, self.directions[k]).magnitude
        return out * (1 + ROUNDING)


#: A body with at least this many directions (several uncertain links merged into it, as on
#: Baxter, whose hands carry cameras, sensors and grippers) has them replaced by its 10
#: coordinate axes (module docstring).
HULL_DIRECTIONS = 20


def plant_parameters(robot, box: ParameterBox) -> PlantParameters:
    """:class:`PlantParameters` of a box (or a piece of one)."""
    nominal = parameters_of(robot)
    size = len(nominal)
    centre, centre_rad = nominal.copy(), np.zeros(size)
    rows, row_rads, weights, keys, bodies = [], [], [], [], []
    for link_box in box.uncertain_links:
        link = link_parameters(robot, link_box)
        A, absolute, columns = link.A, np.abs(link.A), link.columns
        placed = A @ link.centre.mid
        centre[columns] += placed
        centre_rad[columns] += absolute @ link.centre.rad + ROUNDING * (
            absolute @ np.abs(link.centre.mid) + np.abs(centre[columns])
        )
        for k, key in enumerate(link.keys):
            d = link.directions[k]
            row, row_rad = np.zeros(size), np.zeros(size)
            row[columns] = A @ d.mid
            row_rad[columns] = absolute @ d.rad + ROUNDING * (absolute @ np.abs(d.mid))
            rows.append(row)
            row_rads.append(row_rad)
            weights.append(link.weights[k])
            keys.append(key)
            bodies.append(columns.start)
    rows, row_rads, weights, keys = _hull_crowded_bodies(rows, row_rads, weights, keys, bodies)
    directions = (
        Ball(np.array(rows), np.array(row_rads)) if rows else Ball.point(np.zeros((0, size)))
    )
    return PlantParameters(
        Ball(centre, centre_rad), directions, np.asarray(weights, dtype=float), tuple(keys)
    )


def _hull_crowded_bodies(rows, row_rads, weights, keys, bodies):
    """Each body with :data:`HULL_DIRECTIONS` directions or more keeps, instead of them, its 10
    coordinate axes ``e_k`` (exact) with the weights ``sum_i w_i (|d_i,k| + rad d_i,k)``: the
    interval hull of that part of the zonotope, which contains it (``|sum_i s_i w_i d_i,k| <=
    sum_i w_i |d_i,k|`` for ``|s_i| <= 1`` and any ``d_i`` of its ball). The Coriolis forms cost
    one matrix per direction; the hull loses the correlation between those directions only."""
    starts, counts = np.unique(bodies, return_counts=True) if bodies else ((), ())
    crowded = {int(b) for b, c in zip(starts, counts, strict=True) if c >= HULL_DIRECTIONS}
    if not crowded:
        return rows, row_rads, weights, keys
    kept = [i for i, b in enumerate(bodies) if b not in crowded]
    out = (
        [rows[i] for i in kept],
        [row_rads[i] for i in kept],
        [weights[i] for i in kept],
        [keys[i] for i in kept],
    )
    size = len(rows[0])
    for start in sorted(crowded):
        members = [i for i, b in enumerate(bodies) if b == start]
        spread = sum(weights[i] * (np.abs(rows[i]) + row_rads[i]) for i in members)
        spread = spread * (1 + ROUNDING * (len(members) + 1))
        for k in range(start, start + 10):
            if spread[k] > 0:
                axis = np.zeros(size)
                axis[k] = 1.0
                out[0].append(axis)
                out[1].append(np.zeros(size))
                out[2].append(float(spread[k]))
                out[3].append((f"body at column {start}", f"axis {k - start}"))
    return out
