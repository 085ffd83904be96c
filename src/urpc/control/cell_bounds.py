"""Bounds over one cell of the certificate (:mod:`urpc.control.cells`): the norms a link's
mismatch enters the floor with, the Coriolis matrix of every plant of the box as a centered form,
and the parameter box of each link. The inertia models they go through are
:mod:`urpc.control.cell_inertia`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..bounds.base import link_body_placement
from ..bounds.hull import barycentric_enclosure
from ..model.regressor_balls import Ball, BallRegressor, parameters_of
from ..model.uncertainty import ParameterBox
from .cell_inertia import LAPACK_MARGIN, InertiaModel, safe_cholesky, spectral_norm


def column_norm(x: np.ndarray, axis=-2) -> np.ndarray:
    return np.sqrt(np.sum(x * x, axis=axis))


class MismatchNorms:
    """The norms a mismatch ``w`` enters the floor with, for one piece: ``||M_L^-1 w||`` (the
    law's ``M_L`` over the cell, by ``M_L^-1 x = M_c^-1 x + O(kappa ||L^-1 x||)``),
    ``||M^{1/2} M_L^-1 w||`` for every plant of the piece (``M <= M_U <= (1 + eps_U) U U^T``),
    ``||M_L^-1/2 w||`` and ``||w||``."""

    def __init__(self, law: InertiaModel, upper: InertiaModel):
        self.law = law
        self.inverse = law.inverse
        self.kappa = law.kappa()
        self.root_eps = np.sqrt(1 - np.minimum(law.eps, 0.999999))
        UT = np.swapaxes(safe_cholesky(upper.center, upper.valid), -1, -2)
        self.to_metric = UT @ self.inverse
        self.metric_factor = np.sqrt(1 + upper.eps) * (1 + LAPACK_MARGIN)
        self.root_U = np.sqrt(upper.lam_max)
        cells, n = self.inverse.shape[:2]
        self.identity = np.broadcast_to(np.eye(n), (cells, n, n))

    def _combine(self, equilibrium, metric, scaled, magnitude):
        equilibrium = equilibrium + self.kappa * scaled
        metric = (metric + self.root_U * self.kappa * scaled) * self.metric_factor
        return equilibrium, metric, scaled / self.root_eps, magnitude

    def link(self, W: Ball, G: Ball | None, link: LinkParameters):
        """The four bounds for one link's ``w = W A delta + G(delta) e`` (pairs, (2, cells))."""
        return self._combine(
            link_bound(self.inverse, W, G, link),
            link_bound(self.to_metric, W, G, link),
            link_bound(self.law.inverse_factor, W, G, link),
            link_bound(self.identity, W, G, link),
        )

    def vector(self, x: np.ndarray):
        """The four bounds for any ``w`` with ``|w_i| <= x_i`` (pairs with no tube part)."""
        column = x[..., None]

        def bound(X):
            value = column_norm(np.abs(X) @ column)[:, 0]
            return np.stack([value, np.zeros_like(value)])

        return self._combine(
            bound(self.inverse), bound(self.to_metric), bound(self.law.inverse_factor),
            bound(self.identity),
        )  # fmt: skip


class CenteredCoriolis:
    """The Christoffel matrix ``C(q, v; pi)`` over boxes of ``q``, ``v`` and ``pi`` in a form
    that keeps the structure of each term for norms ``sup ||P C P^T||``: ``C`` is linear in ``v``
    and in ``pi``, so with ``v = v_c + dv``, ``pi = pi_c + dpi``::

        C = C(q; v_c, pi_c) + sum_k dv_k C(q; e_k, pi_c) + sum_j dpi_j C(q; v_c, e_j)
            + sum_kj dv_k dpi_j C(q; e_k, e_j)

    each term enclosed over the box of ``q`` alone (``|dv_k|``, ``|dpi_j|`` at most the boxes'
    radii), its centre through ``P`` exactly and its (first-order in ``q``) radius with absolute
    values. The bound is affine in the velocity radii: :meth:`coefficients` gives ``(A, B)`` with
    ``sup ||P C P^T|| <= A + B dv`` for every velocity box of centre ``v_c`` and radii ``dv``, so
    that a wider velocity box (a larger ``r_max``) costs no new enclosure."""

    def __init__(
        self,
        radii: np.ndarray,
        center: Ball,
        per_velocity: Ball,
        per_parameter: Ball | None,
        per_both: Ball | None,
    ):
        """The four terms over the cells, as :meth:`sharing` encloses them: ``radii`` the
        parameter box's radii along the shared directions ``e_j`` (zero where this box is exact),
        ``center`` ``C(q; v_c, pi_c)`` (cells, n, n), ``per_velocity`` ``C(q; e_k, pi_c)`` (cells,
        k, n, n), ``per_parameter`` ``C(q; v_c, e_j)`` (cells, j, n, n) and ``per_both`` ``C(q;
        e_k, e_j)`` (cells, k, j, n, n) (``None`` without directions)."""
        self.pi_rad = radii
        self.center, self.per_velocity = center, per_velocity
        self.per_parameter, self.per_both = per_parameter, per_both

    @classmethod
    def sharing(
        cls, regressor: BallRegressor, q: Ball, forms: list[tuple[np.ndarray, Ball]]
    ) -> list[CenteredCoriolis]:
        """One form per ``(v_center, parameters)`` over the same box of ``q`` (boxes of any
        centres and radii: the plant's hull and the mismatch, of each piece of the box). The
        terms that do not depend on a box's centre or radii are enclosed once for all: ``C(q;
        e_k, e_j)`` along the union of the boxes' directions, with every centre's ``C(q; e_k,
        pi_c)``, in one call, and ``C(q; v_c, .)`` of every centre and direction in one call per
        distinct ``v_c`` (each row is computed as it would be alone, up to the order of
        rounding)."""
        free = free_directions([parameters for _, parameters in forms])
        size = forms[0][1].mid.shape[0]
        directions = np.zeros((len(free), size))
        directions[np.arange(len(free)), free] = 1.0
        count = len(forms)
        centres = np.stack([parameters.mid for _, parameters in forms])
        each = regressor.christoffel_matrices(q, Ball.point(np.concatenate([centres, directions])))
        per_both = each[:, :, count:] if len(free) else None
        by_velocity: dict[bytes, tuple[list[int], Ball]] = {}
        for index, (v_center, _) in enumerate(forms):
            key = np.ascontiguousarray(v_center).tobytes()
            by_velocity.setdefault(key, ([], v_center))[0].append(index)
        centre_terms: dict[int, tuple[Ball, Ball | None]] = {}
        for indices, v_center in by_velocity.values():
            rows = np.concatenate([centres[indices], directions])
            values = regressor.coriolis_matrices(q, Ball.point(v_center), Ball.point(rows))
            along = values[:, len(indices) :] if len(free) else None
            for position, index in enumerate(indices):
                centre_terms[index] = (values[:, position], along)
        return [
            cls(
                parameters.rad[free], centre_terms[index][0], each[:, :, index],
                centre_terms[index][1], per_both,
            )
            for index, (_, parameters) in enumerate(forms)
        ]  # fmt: skip

    def coefficients(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(A, B)``, shapes (cells,) and (cells, n): ``sup ||P C P^T||_2 <= A + B dv`` per cell
        over the boxes (``P``: (cells, n, n); ``dv``: the velocity radii, (cells, n))."""
        absolute = np.abs(P)

        def congruent(Q: np.ndarray, X: np.ndarray) -> np.ndarray:
            index = (slice(None),) + (None,) * (X.ndim - 3)
            return Q[index] @ X @ np.swapaxes(Q, -1, -2)[index]

        def through(Q: np.ndarray, X: np.ndarray) -> np.ndarray:
            return spectral_norm(congruent(Q, X))

        def structured(X: Ball) -> np.ndarray:
            return through(P, X.mid) + through(absolute, X.rad)

        def summed(X: Ball, weights: np.ndarray) -> np.ndarray:
            """``sup ||P sum_j dpi_j X_j P^T||`` over ``|dpi_j| <= weights_j`` (axis -3 is j).
            The centres: ``|sum_j dpi_j Y_j| <= sum_j w_j |Y_j|`` entrywise (``Y_j = P X_j
            P^T``), and the spectral norm is monotone on non-negative matrices (``||A|| <= |||A|||
            <= ||B||`` for ``|A| <= B``), so one norm bounds them all; with few directions the
            triangle inequality ``sum_j w_j ||Y_j||`` is also tried, the smaller kept. The
            (non-negative) radii are summed first, ``|| |P| sum_j w_j R_j |P|^T ||``."""
            Y = congruent(P, X.mid)
            centres = spectral_norm(np.einsum("...jab,j->...ab", np.abs(Y), weights))
            if len(weights) <= TRIANGLE_DIRECTIONS:
                centres = np.minimum(centres, spectral_norm(Y) @ weights)
            radius = np.einsum("...jab,j->...ab", X.rad, weights)
            return centres + through(absolute, radius)

        constant = structured(self.center)
        per_velocity = structured(self.per_velocity)
        if self.per_parameter is not None:
            constant = constant + summed(self.per_parameter, self.pi_rad)
            per_velocity = per_velocity + summed(self.per_both, self.pi_rad)  # (cells, k)
        return constant * (1 + LAPACK_MARGIN), per_velocity * (1 + LAPACK_MARGIN)


#: Up to this many parameter directions, a Coriolis form's parameter part is also bounded by the
#: triangle inequality (one norm per direction; it can beat the entrywise sum for a few).
TRIANGLE_DIRECTIONS = 24

#: The Coriolis forms are enclosed over at most this many bytes of recursion at a time (their
#: Christoffel batch grows as ``n^4`` per cell: a 10-link chain holds 5 MB per cell).
CORIOLIS_CHUNK_BYTES = 2**28


def coriolis_coefficients(
    regressor: BallRegressor, q: Ball, forms: list[tuple[np.ndarray, Ball, np.ndarray]]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """:meth:`CenteredCoriolis.coefficients` of each form ``(v_center, parameters, P)`` of
    :meth:`CenteredCoriolis.sharing` through its factor ``P`` ((cells, n, n)), computed over
    chunks of cells so that memory stays bounded whatever the arm (every cell's enclosure is
    independent of the others'): ``out[form] = (A, B)``."""
    cells, n = q.mid.shape
    rows = len(forms) + len(free_directions([parameters for _, parameters, _ in forms]))
    per_cell = n * (n + 1) // 2 * rows * n * 3 * 8 * 4  # the backward pass's force rows
    chunk = max(1, int(CORIOLIS_CHUNK_BYTES // max(per_cell, 1)))
    parts: list[list[tuple[np.ndarray, np.ndarray]]] = []
    for start in range(0, cells, chunk):
        part = slice(start, min(cells, start + chunk))
        chunk_forms = [(v[part], parameters) for v, parameters, _ in forms]
        shared = CenteredCoriolis.sharing(regressor, q[part], chunk_forms)
        parts.append(
            [form.coefficients(P[part]) for form, (_, _, P) in zip(shared, forms, strict=True)]
        )
    return [
        tuple(np.concatenate([p[f][i] for p in parts]) for i in range(2)) for f in range(len(forms))
    ]


def free_directions(boxes: list[Ball]) -> np.ndarray:
    """The parameters with a non-zero radius in any of the boxes (their indices)."""
    return np.flatnonzero(np.any([box.rad > 0 for box in boxes], axis=0))


def velocity_bound(
    constant: np.ndarray,
    per_velocity: np.ndarray,
    box: np.ndarray,
    components: np.ndarray,
    norm: float,
    weights: np.ndarray | float = 1.0,
) -> np.ndarray:
    """``sup (constant + sum_k |dv_k| B_k)`` per cell over ``dv = x + y`` with ``|x_k| <= box_k``
    and ``y = weights * z``, ``|y_k| <= components_k``, ``||z||_2 <= norm``: the box part
    componentwise, the ball part by the better of its componentwise bound and Cauchy-Schwarz
    ``sum_k |w_k z_k| B_k <= ||z|| ||w B||`` (the error's rate and the tube are balls in the
    2-norm, which a box over-states by up to ``sqrt(n)``). ``B``: (cells, n)."""
    ball = np.minimum(
        np.sum(per_velocity * components, axis=-1),
        norm * np.sqrt(np.sum((per_velocity * weights) ** 2, axis=-1)),
    )
    return (constant + np.sum(per_velocity * box, axis=-1) + ball) * (1 + 1e-12)


def plant_hull(robot, box: ParameterBox) -> Ball:
    """The standard parameters of the joint bodies over the box (nominal plus each uncertain
    link's barycentric enclosure placed into its body), a ball ``(10 dof,)``."""
    lower = parameters_of(robot).copy()
    upper = lower.copy()
    for link_box in box.uncertain_links:
        body, A = link_body_placement(robot, link_box.link)
        lo, hi = barycentric_enclosure(link_box)
        nominal = link_box.standard_parameters(link_box.nominal)
        mid, rad = A @ (0.5 * (lo + hi) - nominal), np.abs(A) @ (0.5 * (hi - lo))
        rad = rad * (1 + 1e-12) + 1e-15 * (np.abs(mid) + np.abs(A) @ np.abs(nominal))
        columns = slice(10 * body, 10 * body + 10)
        lower[columns] += mid - rad
        upper[columns] += mid + rad
    return Ball.hull(lower, upper)


#: At most this many coordinates of a link's parameter box are enumerated at their vertices;
#: the others enter by the triangle inequality (sound either way; cost 2^VERTEX_COORDINATES).
VERTEX_COORDINATES = 5


@dataclasses.dataclass(frozen=True)
class LinkParameters:
    """Where a link enters ``Y_SL`` and its barycentric hull relative to the nominal:
    ``delta = mid + rad * s``, ``s in [-1, 1]^10`` (link frame; ``A`` places it in its body)."""

    columns: slice
    A: np.ndarray
    mid: np.ndarray
    rad: np.ndarray


def link_parameters(robot, box) -> LinkParameters:
    body, A = link_body_placement(robot, box.link)
    lower, upper = barycentric_enclosure(box)
    nominal = box.standard_parameters(box.nominal)
    mid = 0.5 * (lower + upper) - nominal
    rad = (0.5 * (upper - lower)) * (1 + 1e-12) + 1e-15 * (np.abs(mid) + np.abs(nominal))
    rad[upper == lower] = 0.0
    return LinkParameters(slice(10 * body, 10 * body + 10), A, mid, rad)


def link_bound(X: np.ndarray, W: Ball, G: Ball | None, link: LinkParameters) -> np.ndarray:
    """Per cell, ``(c, g)`` with ``||X w|| <= c + rho g`` over ``w = W A delta + G(delta) e`` for
    every ``delta`` of the link's box, every ``W``, ``G`` in their balls and ``||e|| <= rho``
    (``X``: (cells, m, n); ``W``: (cells, n, 10); ``G``: (cells, k, n, 10), the Jacobian along the
    tube, enclosed over a tube at least as wide as ``rho``). Shape (2, cells).

    ``||X W A delta||`` is convex in ``delta``: its maximum over the box is at a vertex. The
    :data:`VERTEX_COORDINATES` coordinates that move it most are enumerated at their vertices,
    the others enter by the triangle inequality (``rad_j ||X W A e_j||``); the radii of the balls
    enter with ``|delta| <= |mid| + rad``."""
    XW = X @ (W.mid @ link.A)  # (cells, m, 10)
    column_norms = column_norm(XW)  # (cells, 10)
    score = np.max(column_norms, axis=0) * link.rad
    free = np.flatnonzero(link.rad > 0)
    chosen = free[np.argsort(score[free])[::-1][:VERTEX_COORDINATES]]
    rest = np.setdiff1d(free, chosen)
    corners = np.array(np.meshgrid(*[(-1.0, 1.0)] * len(chosen), indexing="ij")).reshape(
        len(chosen), -1
    )
    vertices = np.repeat(link.mid[:, None], corners.shape[1], axis=1)
    vertices[chosen] += link.rad[chosen, None] * corners
    bound = column_norm(XW @ vertices).max(-1) + column_norms[:, rest] @ link.rad[rest]
    magnitude = np.abs(link.mid) + link.rad
    absolute = np.abs(X)
    radius = (W.rad + 40 * 2.0**-53 * np.abs(W.mid)) @ (np.abs(link.A) @ magnitude)  # (cells, n)
    bound = bound + column_norm(absolute @ radius[..., None])[:, 0]
    per_tube = np.zeros_like(bound)
    if G is not None:
        XG = X[:, None] @ (G.mid @ link.A)  # (cells, k, m, 10)
        spectral = spectral_norm(np.moveaxis(XG, -1, 1))  # (cells, 10): ||X G_j||_2
        triangle = spectral @ magnitude
        # Frobenius norm of X G(delta) at the enumerated vertices (a quadratic form in delta).
        H = np.einsum("ckmj,ckml->cjl", XG, XG)
        quadratic = np.einsum("cjl,jv,lv->cv", H, vertices, vertices)
        frobenius = np.sqrt(np.maximum(quadratic, 0.0)).max(-1) * (1 + 1e-10)
        frobenius = frobenius + spectral[:, rest] @ link.rad[rest]
        spread = (G.rad + 40 * 2.0**-53 * np.abs(G.mid)) @ (np.abs(link.A) @ magnitude)
        spread = np.sqrt(np.sum(spread * spread, axis=1))  # (cells, n)
        per_tube = np.minimum(triangle, frobenius) + column_norm(absolute @ spread[..., None])[:, 0]
    return np.stack([bound, per_tube]) * (1 + 1e-10)
