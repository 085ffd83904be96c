"""``vertex``: a tight enclosure of ``w`` over physical link boxes (mass, CoM, inertia about the CoM).

The proof is in ``docs/bounds.md`` ("The vertex method"); in short:

1. **Separation.** Links' parameters are independent and ``w_i = sum_l f_il(p_l)``, so the range
   of ``w_i`` is the (exact) sum of the ranges of the per-(joint, link) terms ``f_il``: one small
   problem per (joint, link), cost ``O(N^2)``, never ``2^(10 N)``.
2. **One link.** With ``y`` the joint's regressor row for the link's own standard parameters
   ``pi = [m, m c, I_C + m (|c|^2 1 - c c^T)]`` (link frame)::

       f = y . pi - y . pi0 = m G(c) + b . I_C - y . pi0,   b = y[4:10]
       G(c) = y . phi(c),   phi(c) = pi(m = 1, c, I_C = 0)      (a unit point mass at c)

   ``I_C`` enters linearly: ``b . I_C`` ranges over ``b . I_center +- |b| . I_radius``. For fixed
   ``c``, ``f`` is linear in ``m >= 0``: ``max m G = max(m_lo Gmax, m_hi Gmax)`` with ``Gmax`` the
   maximum of ``G`` over the CoM box (``min m G = min(m_lo Gmin, m_hi Gmin)``), and
   ``t -> max(m_lo t, m_hi t)`` is non-decreasing, so an upper bound of ``Gmax`` may replace it.
3. **The CoM box.** ``G`` is a quadratic in ``c`` with constant second derivatives
   ``G_xx = 2 (b_yy + b_zz)``, ``G_yy = 2 (b_xx + b_zz)``, ``G_zz = 2 (b_xx + b_yy)``. The error of
   multilinear interpolation at the 8 vertices (telescoped as
   ``(1 - P1) + P1 (1 - P2) + P1 P2 (1 - P3)``, each ``P_k`` a positive operator) gives::

       Gmax <= max over vertices + sum_k (w_k^2 / 8) max(0, -G_kk)
       Gmin >= min over vertices - sum_k (w_k^2 / 8) max(0, +G_kk)

   (``w_k`` the box widths). The margins vanish along directions where ``G`` is convex (for the
   maximum) or concave (for the minimum). Barycentric link boxes are linear, handled as in
   ``hull``.

Everything before the maxima is linear in ``Y_SL``: one batched product ``Y_SL @ B`` gives, for
every (joint, link), the 8 vertex values of ``G`` (with both signs), the curvature terms, the linear
part and the radius terms; a handful of vectorized operations on preallocated buffers finish the
bound (about 15 numpy calls per evaluation, whatever the number of links).

Rounding: the result is inflated by ``base.ROUNDING_RELATIVE`` times ``sum_j |Y_ij| p_j``, where
``p_j`` bounds ``|pi_j| + |pi0_j|`` over the box in body coordinates (every term of every sum above
is a product bounded by one of those), plus ``base.ROUNDING_ABSOLUTE``.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..errors import InputError
from ..regressor import SlotineLiRegressor
from ..robot import Robot
from ..uncertainty import LinkBox, ParameterBox, barycentric_from_physical
from .base import ROUNDING_ABSOLUTE, ROUNDING_RELATIVE, BoundMethod, link_body_placement
from .hull import barycentric_enclosure

#: Standard-parameter indices of I_xx, I_yy, I_zz (Pinocchio order m, h, xx, xy, yy, xz, yz, zz).
_XX, _YY, _ZZ = 4, 6, 9
#: Rows of the per-link matrix: ``G'(v)`` and ``-G'(v)`` interleaved (row ``2 v + sign``), so that
#: halving the rows three times takes the maximum over the 8 vertices for both signs at once.
_VERTEX_ROWS = 16


def unit_mass_parameters(com: np.ndarray) -> np.ndarray:
    """``phi(c)``: standard parameters of a unit point mass at ``com`` [m] (link frame), so that
    ``y . pi = m y . phi(c) + y[4:10] . I_C``."""
    return barycentric_from_physical(np.concatenate([[1.0], com, np.zeros(6)]))


def curvature_directions(com_width: np.ndarray) -> np.ndarray:
    """``(3, 10)`` rows ``d_k`` with ``y . d_k = (w_k^2 / 8) G_kk`` for the CoM widths ``w`` [m]
    (``G_xx = 2 (y_yy + y_zz)``, ``G_yy = 2 (y_xx + y_zz)``, ``G_zz = 2 (y_xx + y_yy)``)."""
    d = np.zeros((3, 10))
    for k, (first, second) in enumerate(((_YY, _ZZ), (_XX, _ZZ), (_XX, _YY))):
        d[k, first] = d[k, second] = 2.0 * com_width[k] ** 2 / 8.0
    return d


class VertexBound(BoundMethod):
    """Vertex enumeration plus a curvature margin over physical boxes; exact over barycentric.

    Physical link boxes need ``mass >= 0`` [kg]. Not thread-safe (one instance per controller):
    evaluations reuse preallocated buffers.

    Args:
        robot: The robot.
        box: The parameter box (physical and barycentric link boxes may be mixed).

    Raises:
        InputError: a physical link box allows a negative mass.
    """

    name = "vertex"

    def __init__(self, robot: Robot, box: ParameterBox):
        super().__init__(robot, box)
        self._scaled_regressor = self.regressor.scaled
        links = box.uncertain_links
        placements = [link_body_placement(self.robot, b.link) for b in links]
        # The exactly linear parts with a radius (inertia about the CoM, or every barycentric
        # coordinate) go to |Y| @ weight when the link frame is its body frame (Y's own columns);
        # other links need rows of their own, after the placement matrix.
        in_body_frame = [np.array_equal(A, np.eye(10)) for _, A in placements]
        n_curvature = max((_com_axes(b).size for b in links), default=0)
        n_radius = max(
            (
                0 if plain else _radius_coordinates(b).size
                for b, plain in zip(links, in_body_frame, strict=True)
            ),
            default=0,
        )
        layout = _Layout(n_curvature, n_radius)
        scale = 1.0 / SlotineLiRegressor.SCALE  # everything acts on Y4 = SCALE * Y_SL
        n_bodies = self.robot.model.njoints - 1
        self._weight = np.zeros(10 * n_bodies)  # |Y4| @ weight: plain radii, rounding margin
        matrices = np.zeros((len(links), 10, layout.n_rows))
        mass_ends = np.zeros((2, len(links)))
        for l, (link_box, (body, A), plain) in enumerate(
            zip(links, placements, in_body_frame, strict=True)
        ):
            columns, mass_ends[:, l], plain_radius = _link_columns(link_box, layout, plain, box)
            matrices[l] = scale * (A @ columns)
            self._weight[10 * body : 10 * body + 10] += scale * plain_radius
            # Rounding margin (base.ROUNDING_RELATIVE): terms bounded by |Y_j| (|A| p)_j.
            box_lower, box_upper = barycentric_enclosure(link_box)
            nominal = link_box.standard_parameters(link_box.nominal)
            magnitude = np.maximum(np.abs(box_lower), np.abs(box_upper)) + np.abs(nominal)
            self._weight[10 * body : 10 * body + 10] += (
                scale * ROUNDING_RELATIVE * (np.abs(A) @ magnitude)
            )
        self._constant = ROUNDING_ABSOLUTE + (self.disturbance_bound or 0.0)
        self._allocate(layout, [body for body, _ in placements], matrices, mass_ends)

    def _allocate(
        self, layout: _Layout, bodies: list[int], matrices: np.ndarray, mass_ends: np.ndarray
    ) -> None:
        """Preallocate the buffers of an evaluation and the views into them. Every numpy call of
        :meth:`_evaluate` then runs on contiguous operands of equal shapes (numpy's fast path,
        about half the cost of a call that also slices, broadcasts or strides)."""
        dof, n_links = self.robot.dof, len(bodies)
        n_bodies = self.robot.model.njoints - 1
        points = n_links * dof  # one column per (link, joint)
        self._n_links = n_links
        self._Y4 = np.zeros((dof, 10 * n_bodies))
        # The link rows of the regressor, (links, dof, 10): a view when the bodies are consecutive.
        per_body = self._Y4.reshape(dof, n_bodies, 10)
        first = bodies[0] if bodies else 0
        if bodies == list(range(first, first + n_links)):
            self._gather = None
            self._rows = per_body[:, first : first + n_links].transpose(1, 0, 2)
        else:
            self._gather = (per_body, np.array(bodies, dtype=int), np.zeros((dof, n_links, 10)))
            self._rows = self._gather[2].transpose(1, 0, 2)
        # Z[row, link, joint], rows outermost so that every row block is contiguous.
        self._Z = np.zeros((layout.n_rows, n_links, dof))
        Z = self._Z.reshape(layout.n_rows, points)
        if n_links == 1:  # a plain 2-D product is cheaper than a batched one
            self._single = (np.ascontiguousarray(matrices[0].T), self._rows[0].T, Z)
        else:
            self._single = None
            self._matrices = matrices
            self._Z_out = self._Z.transpose(1, 2, 0)
        E = Z[layout.summed : layout.summed + 2]  # (2, points), the first pair of the summed block
        self._halves = []
        source = Z[:_VERTEX_ROWS]
        for size in (8, 4, 2):
            target = np.zeros((size, points)) if size > 2 else E
            self._halves.append((source[:size], source[size:], target))
            source = target
        self._E = E
        c0 = layout.curvature
        self._curvature = Z[c0 : c0 + 2 * layout.n_curvature]
        self._curvature_pairs = [Z[c0 + 2 * k : c0 + 2 * k + 2] for k in range(layout.n_curvature)]
        r0 = layout.summed + 4
        self._radius = Z[r0 : r0 + 2 * layout.n_radius] if layout.n_radius else None
        self._mass_low = np.tile(mass_ends[0].repeat(dof), (2, 1))
        self._mass_high = np.tile(mass_ends[1].repeat(dof), (2, 1))
        self._low_products = np.zeros((2, points))
        # Sum over (row pair b, link) of the summed block: [upper, -lower] per joint.
        self._summed = Z[layout.summed :].reshape(-1)  # index ((2 b + s) links + l) dof + i
        n_pairs = (layout.n_rows - layout.summed) // 2
        picks = np.eye(2 * dof).reshape(2, 1, dof, 2 * dof)  # (s, ., i) -> unit vector (s, i)
        self._sum_matrix = np.ascontiguousarray(
            np.tile(picks, (n_pairs, 1, n_links, 1)).reshape(-1, 2 * dof).T
        )
        self._extent = np.zeros((2, dof))
        self._extent_flat = self._extent.reshape(-1)

    # ------------------------------------------------------------------------------ evaluation
    def _evaluate(self) -> np.ndarray:
        """``[upper, -lower]`` (``2 x dof``, before the rounding margin) from ``self._Y4``."""
        if not self._n_links:
            return self._extent
        if self._gather is not None:
            per_body, bodies, rows = self._gather
            np.take(per_body, bodies, axis=1, out=rows)
        if self._single is not None:
            matrix, rows, out = self._single
            matrix.dot(rows, out=out)
        else:
            np.matmul(self._rows, self._matrices, out=self._Z_out)
        for first, second, target in self._halves:  # max over the vertices, both signs
            np.maximum(first, second, out=target)
        E = self._E  # now [max_v G'(v), max_v -G'(v)]
        if self._curvature_pairs:  # + sum_k |curvature term k|: bounds of [Gmax, -Gmin]
            np.abs(self._curvature, out=self._curvature)
            for pair in self._curvature_pairs:
                E += pair
        # max(m_lo t, m_hi t) for t = Gmax and t = -Gmin.
        np.multiply(E, self._mass_low, out=self._low_products)
        E *= self._mass_high
        np.maximum(E, self._low_products, out=E)
        if self._radius is not None:
            np.abs(self._radius, out=self._radius)
        return self._sum_matrix.dot(self._summed, out=self._extent_flat).reshape(2, -1)

    def enclose(self, q, qd, qd_a, qdd_a):
        self._scaled_regressor(q, qd, qd_a, qdd_a, out=self._Y4)
        return self._enclosure()

    def enclose_regressor(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        np.multiply(Y, SlotineLiRegressor.SCALE, out=self._Y4)
        return self._enclosure()

    def _enclosure(self) -> tuple[np.ndarray, np.ndarray]:
        extent = self._evaluate()
        margin = np.abs(self._Y4).dot(self._weight)
        margin += ROUNDING_ABSOLUTE
        return self._add_disturbance(-extent[1] - margin, extent[0] + margin)

    def rho(self, q, qd, qd_a, qdd_a):
        Y4 = self._scaled_regressor(q, qd, qd_a, qdd_a, out=self._Y4)
        upper, minus_lower = self._evaluate()
        rho = np.maximum(upper, minus_lower)
        rho += np.abs(Y4).dot(self._weight)
        rho += self._constant
        return rho


class _Layout:
    """Rows of the per-link matrix, sign ``s`` (0: upper, 1: minus lower) innermost:

    * ``2 v + s`` for ``v < 8``: ``(-1)^s G'(v)`` at the CoM vertices ``v``;
    * ``curvature + 2 k + s``: curvature term ``k`` (both signs alike, taken absolute);
    * ``summed + 2 b + s``: the block summed over links into ``[upper, -lower]``: ``b = 0`` is
      filled after the maxima, ``b = 1`` is the linear part ``(-1)^s l``, ``b >= 2`` are radius
      terms (taken absolute).
    """

    def __init__(self, n_curvature: int, n_radius: int):
        self.n_curvature = n_curvature
        self.n_radius = n_radius
        self.curvature = _VERTEX_ROWS
        self.summed = _VERTEX_ROWS + 2 * n_curvature
        self.n_rows = self.summed + 2 * (2 + n_radius)


def _link_columns(
    link_box: LinkBox, layout: _Layout, plain: bool, box: ParameterBox
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The matrix of one link in link coordinates (a regressor row ``y`` times it gives the
    link's rows of :class:`_Layout`), its mass ends ``[m_lo, m_hi]`` [kg] (zeros for a barycentric
    box, all linear) and, for a link in its body frame (``plain``), the radius weights of ``|y|``.
    """
    columns = np.zeros((10, layout.n_rows))
    lower, upper = link_box.lower, link_box.upper
    center, radius = 0.5 * (lower + upper), 0.5 * (upper - lower)
    nominal = link_box.standard_parameters(link_box.nominal)
    mass_ends = np.zeros(2)
    if link_box.kind == "physical":
        if lower[0] < 0:
            raise InputError(
                f"mass interval [{lower[0]:.6g}, {upper[0]:.6g}] kg of '{link_box.link}' must "
                "be non-negative",
                source=box.source,
                field=f"links.{link_box.link}.mass",
            )
        mass_ends[:] = lower[0], upper[0]
        d = curvature_directions(upper[1:4] - lower[1:4])
        shift = 0.5 * d.sum(axis=0)  # G' = G - sum_k (y . d_k) / 2
        corners = itertools.product(*zip(lower[1:4], upper[1:4], strict=True))
        for v, corner in enumerate(corners):
            vertex = unit_mass_parameters(np.array(corner)) - shift
            columns[:, 2 * v] = vertex
            columns[:, 2 * v + 1] = -vertex
        for k, axis in enumerate(_com_axes(link_box)):
            start = layout.curvature + 2 * k
            columns[:, start] = columns[:, start + 1] = 0.5 * d[axis]
        linear = np.concatenate([np.zeros(4), center[4:]]) - nominal
    else:
        linear = center - nominal
    columns[:, layout.summed + 2] = linear
    columns[:, layout.summed + 3] = -linear
    coordinates = _radius_coordinates(link_box)
    plain_radius = np.zeros(10)
    if plain:
        plain_radius[coordinates] = radius[coordinates]
    else:
        for j, k in enumerate(coordinates):
            start = layout.summed + 4 + 2 * j
            columns[k, start] = columns[k, start + 1] = radius[k]
    return columns, mass_ends, plain_radius


def _com_axes(link_box: LinkBox) -> np.ndarray:
    """Axes (0, 1, 2) along which a physical box's center of mass is uncertain."""
    if link_box.kind != "physical":
        return np.zeros(0, dtype=int)
    return np.flatnonzero(link_box.upper[1:4] > link_box.lower[1:4])


def _radius_coordinates(link_box: LinkBox) -> np.ndarray:
    """Standard-parameter indices that enter linearly with a radius: the uncertain components of
    the inertia about the CoM (physical) or every uncertain coordinate (barycentric)."""
    uncertain = link_box.upper > link_box.lower
    if link_box.kind == "physical":
        return 4 + np.flatnonzero(uncertain[4:])
    return np.flatnonzero(uncertain)
