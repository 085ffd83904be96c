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
3. **The CoM box.** ``G`` is a quadratic in ``c``. In scaled coordinates ``u in [-1, 1]^n`` of
   the link's uncertain CoM axes, ``m_hi G = q(u) = alpha + beta . u + u^T K u / 2``, and its
   maximum over the box is attained at a vertex or at the stationary point of ``q`` restricted to
   a face (edge, square, cube) on which ``q`` is strictly concave
   (:mod:`urpc.bounds.com_box`): the exact maximum, from the vertex values and at most 19 small
   solves, most of them skipped because the face's interpolation bound (its vertex maximum plus
   ``sum_k max(0, -K_kk) / 2``, the margin of the ``vertex-plain`` variant) is already below the
   best value. ``Gmin`` is the mirror image (``-q``). Barycentric link boxes are linear, handled
   as in ``hull``.

Everything before the maxima is linear in ``Y_SL``: per (joint, link), one product ``B_l^T y``
gives ``alpha, beta, K``, the linear part and the radius terms; maxima and sums follow. One
compiled call (:func:`vertex_extent`, numba) does all of it for every (joint, link) pair, skipping the links a joint does not carry:
on a 7-joint arm it costs a few microseconds per control step, where the same work done by about
15 vectorized numpy calls cost 10-20 us in call overhead alone.

Rounding: the result is inflated by ``base.ROUNDING_RELATIVE`` times ``sum_j |Y_ij| p_j``, where
``p_j`` bounds ``|pi_j| + |pi0_j|`` over the box in body coordinates (every term of every sum above
is a product bounded by one of those), plus ``base.ROUNDING_RECURSION E sum_j p_j`` for the
rounding inside the regressor (``E`` its envelope, which follows ``|qd|^2``), plus
``base.ROUNDING_ABSOLUTE``.
"""

from __future__ import annotations

import numba
import numpy as np

from ..errors import InputError
from ..model.regressor import SlotineLiRegressor
from ..model.robot import Robot
from ..model.uncertainty import LinkBox, ParameterBox
from .base import (
    ROUNDING_ABSOLUTE,
    ROUNDING_RELATIVE,
    RegressorBound,
    envelope_weights,
    link_body_placement,
)
from .com_box import N_QUADRATIC, box_maximum, quadratic_columns, vertex_values
from .hull import barycentric_enclosure


class VertexBound(RegressorBound):
    """The exact range of each link's term over physical boxes (mass, CoM, inertia about the
    CoM), exact over barycentric ones; sound up to the rounding margins.

    Physical link boxes need ``mass >= 0`` [kg]. Not thread-safe (one instance per controller):
    evaluations reuse preallocated buffers.

    Args:
        robot: The robot.
        box: The parameter box (physical and barycentric link boxes may be mixed).
        exact_com: Maximize each link's CoM quadratic exactly over its CoM box (faces and
            stationary points); if false, bound it by its vertex values plus the interpolation
            margin ``sum_k max(0, -K_kk) / 2`` (cheaper, looser when a CoM interval is wide).

    Raises:
        InputError: a physical link box allows a negative mass.
    """

    name = "vertex"

    def __init__(self, robot: Robot, box: ParameterBox, exact_com: bool = True):
        super().__init__(robot, box)
        self._regressor = self.regressor
        self._scaled_regressor = self.regressor.scaled
        links = box.uncertain_links
        placements = [link_body_placement(self.robot, b.link) for b in links]
        # The exactly linear parts with a radius (inertia about the CoM, or every barycentric
        # coordinate) go to |Y| . weight when the link frame is its body frame (Y's own columns);
        # other links need rows of their own, after the placement matrix.
        in_body_frame = [np.array_equal(A, np.eye(10)) for _, A in placements]
        physical = [b.kind == "physical" for b in links]
        n_radius = max(
            (
                0 if plain else _radius_coordinates(b).size
                for b, plain in zip(links, in_body_frame, strict=True)
            ),
            default=0,
        )
        layout = _Layout(N_QUADRATIC if any(physical) else 0, n_radius)
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
        self._sizes = np.array([layout.linear, int(exact_com), n_radius], dtype=np.int64)
        self._products = np.zeros(layout.n_products + 8)  # and the 8 vertex values
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
        return self.add_joint_terms(*self._enclosure(self._regressor.envelope), qd, qd_a, qdd_a)

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
    link's body):

    * ``0 .. linear``: ``alpha, beta_k, K_kk, K_jk`` of ``q(u) = m_hi G`` in the scaled CoM
      coordinates (:func:`urpc.bounds.com_box.quadratic_columns`; none if no link is physical);
    * ``linear``: the exactly linear part ``l`` (inertia about the CoM at its center, minus the
      nominal);
    * ``radius + j``: the radius terms of a link off its body frame (taken absolute).
    """

    def __init__(self, n_quadratic: int, n_radius: int):
        self.linear = n_quadratic
        self.radius = self.linear + 1
        self.n_products = self.radius + n_radius


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
    ``l`` (rows of :class:`_Layout` in ``z``), the upper bound adds::

        max(m_lo/m_hi t, t) + l + sum_j |r_j|,   t >= max over the CoM box of q = m_hi G

    (:func:`urpc.bounds.com_box.box_maximum`; ``t = 0`` for a barycentric link, whose
    ``mass_ratio`` is -1) and the lower bound the same with ``-q`` and ``-l``; both add
    ``|Y4_i| . weight + envelope envelope_weight_i + ROUNDING_ABSOLUTE`` (the rounding margins of
    ``docs/bounds.md`` section 7). A link whose body joint ``i`` does not carry has an all-zero
    regressor row: its terms are exactly zero and are skipped. ``z`` holds the products, then the
    8 vertex values.
    """
    linear, exact, n_radius = sizes[0], sizes[1] != 0, sizes[2]
    radius = linear + 1
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
            spread = 0.0
            for j in range(n_radius):
                spread += abs(z[radius + j])
            upper += z[linear] + spread
            minus_lower += spread - z[linear]
            ratio = mass_ratio[l]
            if ratio >= 0.0:  # physical
                high, low = vertex_values(z, n_products)
                top = box_maximum(z, 1.0, exact, n_products, high)  # bounds m_hi Gmax
                bottom = box_maximum(z, -1.0, exact, n_products, -low)  # bounds -m_hi Gmin
                upper += max(top, ratio * top)
                minus_lower += max(bottom, ratio * bottom)
        out[0, i] = upper
        out[1, i] = minus_lower
        out[2, i] = max(upper, minus_lower)


def _link_columns(
    link_box: LinkBox, layout: _Layout, plain: bool, box: ParameterBox
) -> tuple[np.ndarray, float, np.ndarray]:
    """The matrix of one link in link coordinates (a link regressor row ``y`` times it gives the
    link's product rows of :class:`_Layout`), its mass ratio ``m_lo / m_hi`` (-1 marks a
    barycentric box, all linear) and, for a link in its body frame (``plain``), the radius weights of ``|y|``.
    """
    columns = np.zeros((10, layout.n_products))
    lower, upper = link_box.lower, link_box.upper
    center, radius = 0.5 * (lower + upper), 0.5 * (upper - lower)
    nominal = link_box.standard_parameters(link_box.nominal)
    mass_ratio = -1.0
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
        columns[:, : layout.linear] = high_mass * quadratic_columns(center[1:4], radius[1:4])
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


def _radius_coordinates(link_box: LinkBox) -> np.ndarray:
    """Standard-parameter indices that enter linearly with a radius: the uncertain components of
    the inertia about the CoM (physical) or every uncertain coordinate (barycentric)."""
    uncertain = link_box.upper > link_box.lower
    if link_box.kind == "physical":
        return 4 + np.flatnonzero(uncertain[4:])
    return np.flatnonzero(uncertain)
