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

Everything before the maxima is linear in ``Y_SL``: per (joint, link), one product ``B_l^T y``
gives the vertex values of ``G``, the curvature terms, the edge differences, the linear part and
the radius terms; maxima, margins and sums follow. One compiled call (:func:`vertex_extent`,
numba) does all of it for every (joint, link) pair, skipping the links a joint does not carry:
on a 7-joint arm it costs a few microseconds per control step, where the same work done by about
15 vectorized numpy calls cost 10-20 us in call overhead alone.

Rounding: the result is inflated by ``base.ROUNDING_RELATIVE`` times ``sum_j |Y_ij| p_j``, where
``p_j`` bounds ``|pi_j| + |pi0_j|`` over the box in body coordinates (every term of every sum above
is a product bounded by one of those), plus ``base.ROUNDING_RECURSION E sum_j p_j`` for the
rounding inside the regressor (``E`` its envelope, which follows ``|qd|^2``), plus
``base.ROUNDING_ABSOLUTE``.
"""

from __future__ import annotations

import itertools

import numba
import numpy as np

from ..errors import InputError
from ..model.regressor import SlotineLiRegressor
from ..model.robot import Robot
from ..model.uncertainty import LinkBox, ParameterBox, barycentric_from_physical
from .base import (
    ROUNDING_ABSOLUTE,
    ROUNDING_RELATIVE,
    BoundMethod,
    envelope_weights,
    link_body_placement,
)
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
            when a CoM interval is wide, a few more operations per evaluation).

    Raises:
        InputError: a physical link box allows a negative mass.
    """

    name = "vertex"

    def __init__(self, robot: Robot, box: ParameterBox, slope_margin: bool = True):
        super().__init__(robot, box)
        self._regressor = self.regressor
        self._scaled_regressor = self.regressor.scaled
        links = box.uncertain_links
        placements = [link_body_placement(self.robot, b.link) for b in links]
        # The exactly linear parts with a radius (inertia about the CoM, or every barycentric
        # coordinate) go to |Y| . weight when the link frame is its body frame (Y's own columns);
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
        # |Y4| . weight: the radii of links in their body frame and the relative rounding margin.
        self._weight = np.zeros(10 * n_bodies)
        self._matrices = np.zeros((len(links), 10, layout.n_products))
        self._mass_ratio = np.zeros(len(links))
        magnitudes = np.zeros(10 * n_bodies)  # p_j per column, body coordinates
        for l, (link_box, (body, A), plain) in enumerate(
            zip(links, placements, in_body_frame, strict=True)
        ):
            columns, self._mass_ratio[l], plain_radius = _link_columns(link_box, layout, plain, box)
            self._matrices[l] = scale * (A @ columns)
            self._weight[10 * body : 10 * body + 10] += scale * plain_radius
            # Rounding margin (base.ROUNDING_RELATIVE): terms bounded by |Y_j| (|A| p)_j.
            box_lower, box_upper = barycentric_enclosure(link_box)
            nominal = link_box.standard_parameters(link_box.nominal)
            magnitude = np.maximum(np.abs(box_lower), np.abs(box_upper)) + np.abs(nominal)
            self._weight[10 * body : 10 * body + 10] += (
                scale * ROUNDING_RELATIVE * (np.abs(A) @ magnitude)
            )
            magnitudes[10 * body : 10 * body + 10] += np.abs(A) @ magnitude
        # Rounding inside the regressor (base.ROUNDING_RECURSION), per unit envelope and joint.
        self._envelope_weight = scale * envelope_weights(self.robot, magnitudes)
        self._bodies = np.array([body for body, _ in placements], dtype=np.int64)
        self._sizes = layout.sizes()
        self._products = np.zeros(layout.n_products)
        self._Y4 = np.zeros((self.robot.dof, 10 * n_bodies))
        # Rows: upper, -lower, rho (written by the kernel).
        self._extent = np.zeros((3, self.robot.dof))

    def _evaluate(self, envelope: float) -> np.ndarray:
        """``[upper, -lower, rho]`` per joint from ``self._Y4`` (one compiled call)."""
        vertex_extent(
            self._Y4,
            envelope,
            self._envelope_weight,
            self._bodies,
            self._matrices,
            self._mass_ratio,
            self._weight,
            self._sizes,
            self._products,
            self._extent,
        )
        return self._extent

    def enclose(self, q, qd, qd_a, qdd_a):
        self._scaled_regressor(q, qd, qd_a, qdd_a, out=self._Y4)
        return self.add_joint_terms(*self._enclosure(self._regressor.envelope), qd, qdd_a)

    def enclose_regressor(
        self, Y: np.ndarray, envelope: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        envelope = self._envelope(Y, envelope)
        np.multiply(Y, SlotineLiRegressor.SCALE, out=self._Y4)
        return self._enclosure(envelope)

    def _enclosure(self, envelope: float) -> tuple[np.ndarray, np.ndarray]:
        extent = self._evaluate(envelope)
        return self._add_disturbance(-extent[1], extent[0].copy())

    def rho(self, q, qd, qd_a, qdd_a):
        if self.joints is not None:
            return super().rho(q, qd, qd_a, qdd_a)
        self._scaled_regressor(q, qd, qd_a, qdd_a, out=self._Y4)
        rho = self._evaluate(self._regressor.envelope)[2]
        return rho + self.disturbance_bound if self.disturbance_bound else rho.copy()


class _Layout:
    """The product rows of one link (``z = B^T y`` for the joint's regressor row ``y`` of the
    link's body; each row is the upper-bound sign, the lower bound takes it negated):

    * ``v < n_vertices = 2^n_axes``: ``m_hi G`` at the CoM vertex ``v`` (bit ``j`` of ``v``
      picks the end of the link's ``j``-th uncertain CoM axis);
    * ``edges + e n_axes + k``: ``m_hi D / 4`` for the ``e``-th edge along axis ``k`` (slope
      margin only);
    * ``curvature + k``: ``-m_hi (w_k^2 / 8) G_kk``, whose positive part is ``M_k``;
    * ``linear``: the exactly linear part ``l`` (inertia about the CoM at its center, minus the
      nominal);
    * ``radius + j``: the radius terms of a link off its body frame (taken absolute).
    """

    def __init__(self, n_axes: int, n_radius: int, slope_margin: bool):
        self.n_axes = n_axes  # uncertain CoM axes (at most 3)
        self.n_vertices = 2**n_axes
        self.n_radius = n_radius
        self.slope_margin = slope_margin
        self.edges = self.n_vertices
        n_edge_rows = (self.n_vertices // 2) * n_axes if slope_margin else 0
        self.curvature = self.edges + n_edge_rows
        self.linear = self.curvature + n_axes
        self.radius = self.linear + 1
        self.n_products = self.radius + n_radius

    def sizes(self) -> np.ndarray:
        """The layout as the kernel reads it (:func:`vertex_extent`)."""
        return np.array(
            [
                self.n_vertices,
                self.n_axes,
                int(self.slope_margin),
                self.edges,
                self.curvature,
                self.linear,
                self.radius,
                self.n_radius,
            ],
            dtype=np.int64,
        )


@numba.njit(
    "void(f8[:, ::1], f8, f8[::1], i8[::1], f8[:, :, ::1], f8[::1], f8[::1], i8[::1], f8[::1], "
    "f8[:, ::1])",
    cache=True,
    nogil=True,
    boundscheck=False,
)
def vertex_extent(
    Y4, envelope, envelope_weight, bodies, matrices, mass_ratio, weight, sizes, z, out
):
    """The vertex bound from ``Y4 = SCALE * Y_SL``: ``out = [upper, -lower, rho]`` per joint.

    Compiled (numba, cached on disk; IEEE arithmetic, no fast-math). For joint ``i`` and link
    ``l`` (rows of :class:`_Layout` in ``z``), the upper bound adds, with ``t = Gmax`` bound::

        max(m_lo/m_hi t, t) + l + sum_j |r_j|,   t = max_v z_v + sum_k max(0, c_k + slope_k)

    and the lower bound the same with ``-z`` (``slope_k = min(0, max_e D, max_e -D) / 4`` is
    sign-free); both add ``|Y4_i| . weight + envelope envelope_weight_i + ROUNDING_ABSOLUTE``
    (the rounding margins of ``docs/bounds.md`` section 7). A link whose body joint ``i``
    does not carry has an all-zero regressor row: its terms are exactly zero and are skipped.
    """
    n_vertices, n_axes, slope_margin = sizes[0], sizes[1], sizes[2]
    edges, curvature, linear, radius, n_radius = sizes[3], sizes[4], sizes[5], sizes[6], sizes[7]
    dof, n_columns = Y4.shape
    n_products = matrices.shape[2]
    for i in range(dof):
        absolute = ROUNDING_ABSOLUTE + envelope * envelope_weight[i]
        for c in range(n_columns):
            absolute += abs(Y4[i, c]) * weight[c]
        upper = absolute
        minus_lower = absolute
        for l in range(bodies.shape[0]):
            base = 10 * bodies[l]
            carried = False
            for k in range(10):
                if Y4[i, base + k] != 0.0:
                    carried = True
                    break
            if not carried:
                continue
            for r in range(n_products):
                z[r] = 0.0
            for k in range(10):
                y = Y4[i, base + k]
                for r in range(n_products):
                    z[r] += y * matrices[l, k, r]
            high = z[0]
            low = z[0]
            for v in range(1, n_vertices):
                high = max(high, z[v])
                low = min(low, z[v])
            high_margin = 0.0
            low_margin = 0.0
            for k in range(n_axes):
                slope = 0.0
                if slope_margin:
                    rise = z[edges + k]
                    fall = z[edges + k]
                    for e in range(1, n_vertices // 2):
                        rise = max(rise, z[edges + e * n_axes + k])
                        fall = min(fall, z[edges + e * n_axes + k])
                    slope = min(0.0, min(rise, -fall))
                high_margin += max(0.0, z[curvature + k] + slope)
                low_margin += max(0.0, -z[curvature + k] + slope)
            ratio = mass_ratio[l]
            top = high + high_margin  # bounds m_hi Gmax
            bottom = -low + low_margin  # bounds -m_hi Gmin
            spread = 0.0
            for j in range(n_radius):
                spread += abs(z[radius + j])
            upper += max(top, ratio * top) + z[linear] + spread
            minus_lower += max(bottom, ratio * bottom) - z[linear] + spread
        out[0, i] = upper
        out[1, i] = minus_lower
        out[2, i] = max(upper, minus_lower)


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
        columns[:, : layout.n_vertices] = vertices.T
        if layout.slope_margin:
            for k, e in itertools.product(range(layout.n_axes), range(layout.n_vertices // 2)):
                low = _insert_bit(e, k, 0)
                columns[:, layout.edges + e * layout.n_axes + k] = 0.25 * (
                    vertices[low + (1 << k)] - vertices[low]
                )
        d = high_mass * curvature_directions(upper[1:4] - lower[1:4])
        for j, axis in enumerate(axes):
            columns[:, layout.curvature + j] = -d[axis]
        linear = np.concatenate([np.zeros(4), center[4:]]) - nominal
    else:
        linear = center - nominal
    columns[:, layout.linear] = linear
    coordinates = _radius_coordinates(link_box)
    plain_radius = np.zeros(10)
    if plain:
        plain_radius[coordinates] = radius[coordinates]
    else:
        for j, k in enumerate(coordinates):
            columns[k, layout.radius + j] = radius[k]
    return columns, mass_ratio, plain_radius


def _insert_bit(value: int, position: int, bit: int) -> int:
    """``value`` with ``bit`` inserted at ``position`` (the vertex of edge ``value`` along axis
    ``position``)."""
    low = value & ((1 << position) - 1)
    return ((value >> position) << (position + 1)) | (bit << position) | low


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
