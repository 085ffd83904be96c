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
   ``(1 - P1) + P1 (1 - P2) + P1 P2 (1 - P3)``, each ``P_k`` a positive operator) gives, with
   ``M_k = (w_k^2 / 8) max(0, -G_kk)`` (``w_k`` the box widths)::

       Gmax <= max over vertices + sum_k M_k

   and, refined by the slopes (``slope_margin=True``, the default): if the 4 vertex differences
   ``D_e`` along the edges of axis ``k`` all have one sign, ``G`` rises towards one face at least
   as steeply as ``sigma_k = min_e |D_e|`` allows, and ``M_k`` shrinks to ``max(0, M_k - sigma_k/4)``
   (``0`` once ``sigma_k >= 4 M_k``). ``Gmin`` is the mirror image (``-G``). Barycentric link boxes
   are linear, handled as in ``hull``.

Everything before the maxima is linear in ``Y_SL``: one batched product ``Y_SL @ B`` gives, for
every (joint, link), the vertex values of ``G`` (both signs), the curvature terms, the edge
differences, the linear part and the radius terms; about 15 vectorized numpy calls on
preallocated buffers finish the bound, whatever the number of links.

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
        slope_margin: Shrink the curvature margin by the slopes along the box edges (tighter
            when a CoM interval is wide, a few more array operations per evaluation).

    Raises:
        InputError: a physical link box allows a negative mass.
    """

    name = "vertex"

    def __init__(self, robot: Robot, box: ParameterBox, slope_margin: bool = True):
        super().__init__(robot, box)
        self._scaled_regressor = self.regressor.scaled
        # Links ordered so that runs of them sit on consecutive bodies (see _allocate).
        links, placements = _ordered(box.uncertain_links, self.robot)
        # The exactly linear parts with a radius (inertia about the CoM, or every barycentric
        # coordinate) go to |Y| @ weight when the link frame is its body frame (Y's own columns);
        # other links need rows of their own, after the placement matrix.
        in_body_frame = [np.array_equal(A, np.eye(10)) for _, A in placements]
        n_axes = max((_com_axes(b).size for b in links), default=0)
        n_radius = max(
            (
                0 if plain else _radius_coordinates(b).size
                for b, plain in zip(links, in_body_frame, strict=True)
            ),
            default=0,
        )
        layout = _Layout(n_axes, n_radius, slope_margin and n_axes > 0)
        scale = 1.0 / SlotineLiRegressor.SCALE  # everything acts on Y4 = SCALE * Y_SL
        n_bodies = self.robot.model.njoints - 1
        # |Y4| @ weight: the radii of links in their body frame and the relative rounding margin.
        self._weight = np.zeros(10 * n_bodies)
        matrices = np.zeros((len(links), 10, layout.n_products))
        mass_ratio = np.zeros(len(links))
        for l, (link_box, (body, A), plain) in enumerate(
            zip(links, placements, in_body_frame, strict=True)
        ):
            columns, mass_ratio[l], plain_radius = _link_columns(link_box, layout, plain, box)
            matrices[l] = scale * (A @ columns)
            self._weight[10 * body : 10 * body + 10] += scale * plain_radius
            # Rounding margin (base.ROUNDING_RELATIVE): terms bounded by |Y_j| (|A| p)_j.
            box_lower, box_upper = barycentric_enclosure(link_box)
            nominal = link_box.standard_parameters(link_box.nominal)
            magnitude = np.maximum(np.abs(box_lower), np.abs(box_upper)) + np.abs(nominal)
            self._weight[10 * body : 10 * body + 10] += (
                scale * ROUNDING_RELATIVE * (np.abs(A) @ magnitude)
            )
        self._layout = layout
        self._allocate([body for body, _ in placements], matrices, mass_ratio)

    def _allocate(self, bodies: list[int], matrices: np.ndarray, mass_ratio: np.ndarray) -> None:
        """Preallocate the buffers of an evaluation and the views into them. Every numpy call of
        :meth:`_evaluate` then runs on contiguous operands (numpy's fast path, about half the
        cost of a call that also slices or strides)."""
        layout = self._layout
        dof, n_links = self.robot.dof, len(bodies)
        n_bodies = self.robot.model.njoints - 1
        points = n_links * dof  # one column per (link, joint)
        self._n_links = n_links
        self._Y4 = np.zeros((dof, 10 * n_bodies))
        # Z[row, link, joint], rows outermost so that every row block is contiguous.
        self._Z = np.zeros((layout.n_rows, n_links, dof))
        Z = self._Z.reshape(layout.n_rows, points)
        # The products Z[:n_products, l] = B_l^T y_l. The first run of links on consecutive
        # bodies (links were sorted for that) reads its regressor rows as a view of Y4; the
        # other links, if any, have theirs gathered into a buffer: at most two batched products.
        per_body = self._Y4.reshape(dof, n_bodies, 10)
        self._gather, self._single, self._runs = None, None, []
        if n_links == 1:  # a plain 2-D product is cheaper than a batched one
            rows = per_body[:, bodies[0]].T
            self._single = (np.ascontiguousarray(matrices[0].T), rows, Z[: layout.n_products])
        elif n_links > 1:
            products = self._Z[: layout.n_products].transpose(1, 2, 0)  # (links, dof, rows)
            first, stop = _runs(bodies)[0]
            run = per_body[:, bodies[first] : bodies[first] + stop].transpose(1, 0, 2)
            self._runs = [(run, matrices[:stop], products[:stop])]
            if stop < n_links:
                gathered = np.zeros((dof, n_links - stop, 10))
                self._gather = (per_body, np.array(bodies[stop:]), gathered)
                rest = gathered.transpose(1, 0, 2)
                self._runs.append((rest, matrices[stop:], products[stop:]))
        self._E = Z[layout.extreme : layout.extreme + 2]
        # E = m_hi [max_v G(v), max_v -G(v)] + sum_k (margin pair k): the vertex maxima (by
        # halving) and the margin pairs sit in one block, summed over its first axis into E.
        self._terms = np.zeros((1 + layout.n_axes, 2, points))
        self._margins = self._terms[1:]
        vertex_maxima = self._terms[0]
        self._vertex_halves, maxima = _halving(Z[: 2 * layout.n_vertices], vertex_maxima)
        # A single vertex (exact CoM): its rows are copied instead.
        self._single_vertex = None if maxima is vertex_maxima else (maxima, vertex_maxima)
        n_edges = layout.n_vertices // 2
        if layout.slope_margin:
            edges = Z[layout.edges : layout.edges + 2 * n_edges * layout.n_axes]
            # [max_e D/4, max_e -D/4]: with 0, their minimum is -sigma_k / 4.
            self._edge_halves, self._steepest = _halving(
                edges.reshape(2 * n_edges, layout.n_axes * points),
                np.zeros((2, layout.n_axes * points)),
            )
            self._slope = np.zeros((layout.n_axes, 1, points))  # -sigma_k / 4
            self._slope_flat = self._slope.reshape(-1)
            self._slope_zeros = np.zeros_like(self._slope)  # array operands: no scalar boxing
        curvature = Z[layout.curvature : layout.curvature + 2 * layout.n_axes]
        self._curvature = curvature.reshape(layout.n_axes, 2, points)
        self._curvature_zeros = np.zeros_like(self._curvature)
        r0 = layout.radius
        self._radius = Z[r0 : r0 + 2 * layout.n_radius] if layout.n_radius else None
        self._mass_ratio = np.tile(mass_ratio.repeat(dof), (2, 1))
        self._low_mass = np.zeros((2, points))
        # The constant pair: ROUNDING_ABSOLUTE once per joint (in the first link's columns).
        Z[layout.constant : layout.constant + 2, :dof] = ROUNDING_ABSOLUTE
        # Sum over (row pair b, link) of the summed block: [upper, -lower] per joint.
        self._summed = Z[layout.summed :].reshape(-1)  # index ((2 b + s) links + l) dof + i
        n_pairs = (layout.n_rows - layout.summed) // 2
        picks = np.eye(2 * dof).reshape(2, 1, dof, 2 * dof)  # (s, ., i) -> unit vector (s, i)
        self._sum_matrix = np.ascontiguousarray(
            np.tile(picks, (n_pairs, 1, n_links, 1)).reshape(-1, 2 * dof).T
        )
        self._extent = np.zeros(2 * dof)
        self._upper, self._minus_lower = self._extent.reshape(2, dof)

    # ------------------------------------------------------------------------------ evaluation
    def _evaluate(self) -> None:
        """``self._upper``, ``self._minus_lower`` from ``self._Y4``, but for ``|Y4| @ weight``
        (the radii of links in their body frame and the relative rounding margin)."""
        if not self._n_links:
            self._extent[:] = ROUNDING_ABSOLUTE
            return
        if self._single is not None:
            matrix, rows, out = self._single
            matrix.dot(rows, out=out)
        if self._gather is not None:
            per_body, bodies, gathered = self._gather
            np.take(per_body, bodies, axis=1, out=gathered)
        for rows, matrices, out in self._runs:
            np.matmul(rows, matrices, out=out)
        E = self._E
        for first, second, target in self._vertex_halves:
            np.maximum(first, second, out=target)
        if self._single_vertex is not None:
            rows, vertex_maxima = self._single_vertex
            np.copyto(vertex_maxima, rows)
        if self._layout.n_axes:
            # Margin pairs: m_hi max(0, M_k - sigma_k / 4) for both signs.
            curvature = self._curvature
            if self._layout.slope_margin:
                for first, second, target in self._edge_halves:
                    np.maximum(first, second, out=target)
                np.minimum(self._steepest[0], self._steepest[1], out=self._slope_flat)
                np.minimum(self._slope, self._slope_zeros, out=self._slope)
                curvature += self._slope
            np.maximum(curvature, self._curvature_zeros, out=self._margins)
        # E = m_hi [Gmax, -Gmin] upper bounds.
        np.add.reduce(self._terms, axis=0, out=E)
        # max(m_lo t, m_hi t) = max(E, (m_lo / m_hi) E) for t = Gmax and t = -Gmin.
        np.multiply(E, self._mass_ratio, out=self._low_mass)
        np.maximum(E, self._low_mass, out=E)
        if self._radius is not None:
            np.abs(self._radius, out=self._radius)
        self._sum_matrix.dot(self._summed, out=self._extent)

    def enclose(self, q, qd, qd_a, qdd_a):
        self._scaled_regressor(q, qd, qd_a, qdd_a, out=self._Y4)
        return self._enclosure()

    def enclose_regressor(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        np.multiply(Y, SlotineLiRegressor.SCALE, out=self._Y4)
        return self._enclosure()

    def _enclosure(self) -> tuple[np.ndarray, np.ndarray]:
        self._evaluate()
        absolute = np.abs(self._Y4).dot(self._weight)
        return self._add_disturbance(-self._minus_lower - absolute, self._upper + absolute)

    def rho(self, q, qd, qd_a, qdd_a):
        Y4 = self._scaled_regressor(q, qd, qd_a, qdd_a, out=self._Y4)
        self._evaluate()
        rho = np.maximum(self._upper, self._minus_lower)
        rho += np.abs(Y4).dot(self._weight)
        if self.disturbance_bound:
            rho += self.disturbance_bound
        return rho


class _Layout:
    """Rows of the per-link products (sign ``s``: 0 for the upper bound, 1 for minus the lower):

    * ``2 v + s``, ``v < n_vertices = 2^n_axes``: ``(-1)^s m_hi G`` at the CoM vertex ``v`` (bit
      ``j`` of ``v`` picks the end of the link's ``j``-th uncertain CoM axis);
    * ``edges + (2 e + s) n_axes + k``: ``(-1)^s m_hi D / 4`` for the ``e``-th edge along axis
      ``k`` (slope margin only);
    * ``curvature + 2 k + s``: ``-(-1)^s m_hi (w_k^2 / 8) G_kk``, whose positive part is ``M_k``;
    * ``summed + 2 b + s``: the block summed over links into ``[upper, -lower]``: the linear part
      ``(-1)^s l``, the radius terms (taken absolute), then, after the products, the extreme
      ``max(m_lo t, m_hi t)`` and a constant pair ``ROUNDING_ABSOLUTE``.
    """

    def __init__(self, n_axes: int, n_radius: int, slope_margin: bool):
        self.n_axes = n_axes  # uncertain CoM axes (at most 3)
        self.n_vertices = 2**n_axes
        self.n_radius = n_radius
        self.slope_margin = slope_margin
        self.edges = 2 * self.n_vertices
        n_edge_rows = self.n_vertices * n_axes if slope_margin else 0  # 2 (n_vertices / 2) n_axes
        self.curvature = self.edges + n_edge_rows
        self.summed = self.curvature + 2 * n_axes
        self.radius = self.summed + 2
        self.n_products = self.radius + 2 * n_radius  # rows written by the product
        self.extreme = self.n_products
        self.constant = self.extreme + 2
        self.n_rows = self.constant + 2


def _link_columns(
    link_box: LinkBox, layout: _Layout, plain: bool, box: ParameterBox
) -> tuple[np.ndarray, float, np.ndarray]:
    """The matrix of one link in link coordinates (a link regressor row ``y`` times it gives the
    link's product rows of :class:`_Layout`), its mass ratio ``m_lo / m_hi`` (0 for a barycentric
    box, all linear) and, for a link in its body frame (``plain``), the radius weights of ``|y|``.
    """
    columns = np.zeros((10, layout.n_products))
    lower, upper = link_box.lower, link_box.upper
    center, radius = 0.5 * (lower + upper), 0.5 * (upper - lower)
    nominal = link_box.standard_parameters(link_box.nominal)
    mass_ratio = 0.0
    if link_box.kind == "physical":
        low_mass, high_mass = lower[0], upper[0]
        if low_mass < 0:
            raise InputError(
                f"mass interval [{low_mass:.6g}, {high_mass:.6g}] kg of '{link_box.link}' must "
                "be non-negative",
                source=box.source,
                field=f"links.{link_box.link}.mass",
            )
        mass_ratio = low_mass / high_mass if high_mass > 0 else 0.0
        axes = _com_axes(link_box)  # slot j < axes.size is the link's axis axes[j]
        vertices = np.empty((layout.n_vertices, 10))
        for v in range(layout.n_vertices):
            com = lower[1:4].copy()  # exact axes: lower == upper
            for j, axis in enumerate(axes):
                com[axis] = upper[1 + axis] if (v >> j) & 1 else lower[1 + axis]
            vertices[v] = high_mass * unit_mass_parameters(com)
        columns[:, 0 : 2 * layout.n_vertices : 2] = vertices.T
        columns[:, 1 : 2 * layout.n_vertices : 2] = -vertices.T
        if layout.slope_margin:
            for k, e in itertools.product(range(layout.n_axes), range(layout.n_vertices // 2)):
                low = _insert_bit(e, k, 0)
                difference = 0.25 * (vertices[low + (1 << k)] - vertices[low])
                row = layout.edges + 2 * e * layout.n_axes + k
                columns[:, row] = difference
                columns[:, row + layout.n_axes] = -difference
        d = high_mass * curvature_directions(upper[1:4] - lower[1:4])
        for j, axis in enumerate(axes):
            columns[:, layout.curvature + 2 * j] = -d[axis]
            columns[:, layout.curvature + 2 * j + 1] = d[axis]
        linear = np.concatenate([np.zeros(4), center[4:]]) - nominal
    else:
        linear = center - nominal
    columns[:, layout.summed] = linear
    columns[:, layout.summed + 1] = -linear
    coordinates = _radius_coordinates(link_box)
    plain_radius = np.zeros(10)
    if plain:
        plain_radius[coordinates] = radius[coordinates]
    else:
        for j, k in enumerate(coordinates):
            row = layout.radius + 2 * j
            columns[k, row] = columns[k, row + 1] = radius[k]
    return columns, mass_ratio, plain_radius


def _halving(
    rows: np.ndarray, target: np.ndarray
) -> tuple[list[tuple[np.ndarray, np.ndarray, np.ndarray]], np.ndarray]:
    """Steps ``(first, second, out)`` such that ``np.maximum(first, second, out=out)`` in order
    takes the maxima over the ``rows`` of equal parity (even: sign 0, odd: sign 1), for a
    power-of-two number of row pairs, and the 2-row array that then holds them: ``target``, or
    ``rows`` itself when it is a single pair (no step)."""
    steps, size = [], rows.shape[0] // 2
    while size > 1:
        out = target if size == 2 else np.zeros((size, rows.shape[1]))
        steps.append((rows[:size], rows[size:], out))
        rows, size = out, size // 2
    return steps, rows


def _insert_bit(value: int, position: int, bit: int) -> int:
    """``value`` with ``bit`` inserted at ``position`` (the vertex of edge ``value`` along axis
    ``position``)."""
    low = value & ((1 << position) - 1)
    return ((value >> position) << (position + 1)) | (bit << position) | low


def _ordered(
    links: tuple[LinkBox, ...], robot: Robot
) -> tuple[list[LinkBox], list[tuple[int, np.ndarray]]]:
    """Link boxes and their (body, placement matrix), the first link of every body first, in body
    order, then the second ones, and so on."""
    placed = [(b, link_body_placement(robot, b.link)) for b in links]
    slots: dict[int, int] = {}
    keys = []
    for _, (body, _) in placed:
        keys.append((slots.get(body, 0), body))
        slots[body] = slots.get(body, 0) + 1
    order = sorted(range(len(placed)), key=keys.__getitem__)
    return [placed[k][0] for k in order], [placed[k][1] for k in order]


def _runs(bodies: list[int]) -> list[tuple[int, int]]:
    """``(start, stop)`` of the maximal runs of consecutive bodies in ``bodies`` (in order)."""
    runs, start = [], 0
    for k in range(1, len(bodies) + 1):
        if k == len(bodies) or bodies[k] != bodies[k - 1] + 1:
            runs.append((start, k))
            start = k
    return runs


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
