"""Bounds over one cell of the certificate (:mod:`urpc.control.cells`): the norms a link's
mismatch enters the floor with, the Coriolis matrix of every plant of the box as a centered form,
and the parameter box of each link. The inertia models they go through are
:mod:`urpc.control.cell_inertia`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..model.ball_arithmetic import concatenate, stack
from ..model.regressor_balls import Ball, BallRegressor
from ..model.verified_norms import spectral_norm
from .cell_inertia import LAPACK_MARGIN, InertiaModel, safe_cholesky
from .parameter_sets import LinkParameters, PlantParameters


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
        mismatch = link_mismatch(W, G, link)
        return self._combine(
            link_bound(self.inverse, mismatch),
            link_bound(self.to_metric, mismatch),
            link_bound(self.law.inverse_factor, mismatch),
            link_bound(self.identity, mismatch),
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


@dataclasses.dataclass(frozen=True)
class OverCell:
    """A matrix function ``X(q)`` over a cell's region of ``q`` (``q_c + dq``, ``|x_l| <= r_l``
    along the reference and ``||e|| <= rho`` across it, ``dq = x + e``): either a ball that holds
    it over the cell's box (``slopes`` ``None``), or, by the mean value theorem, its value at the
    centre ``q_c`` (a ball of rounding width) and its derivatives ``dX/dq_l`` over the box (the
    axis after the cells), ``X(q) = X(q_c) + sum_l dq_l dX/dq_l(xi)``. The second keeps the
    structure that a ball of the whole box loses through ``|P|`` (its radius is first-order in
    the box's width; only the derivatives' radii, times ``|dq_l|``, go through ``|P|`` now)."""

    value: Ball
    slopes: Ball | None = None

    def select(self, index: tuple) -> OverCell:
        """The entries ``index`` of the axes after the cells (and the slopes' direction)."""
        slopes = None if self.slopes is None else self.slopes[(slice(None), slice(None)) + index]
        return OverCell(self.value[(slice(None),) + index], slopes)


def combined(X: OverCell, combination: tuple, before: tuple) -> OverCell:
    """``sum_i c_i X[..., row_i, ...]`` for ``combination = ((row_i, c_i), ...)`` with ``c_i =
    +-1`` (the row's axis after the axes ``before``), in ball arithmetic."""

    def term(row: int, sign: float) -> OverCell:
        part = X.select(before + (row,))
        return (
            part
            if sign > 0
            else OverCell(-part.value, None if part.slopes is None else -part.slopes)
        )

    out = term(*combination[0])
    for row, sign in combination[1:]:
        other = term(row, sign)
        out = OverCell(
            out.value + other.value, None if out.slopes is None else out.slopes + other.slopes
        )
    return out


class CenteredCoriolis:
    """The Christoffel matrix ``C(q, v; pi)`` over boxes of ``q``, ``v`` and a parameter set
    ``pi = pi_c + sum_j s_j w_j d_j`` (:class:`~urpc.control.parameter_sets.PlantParameters`) in a
    form that keeps the structure of each term for norms ``sup ||P C P^T||``: ``C`` is linear in
    ``v`` and in ``pi``, so with ``v = v_c + dv``::

        C = C(q; v_c, pi_c) + sum_k dv_k C(q; e_k, pi_c) + sum_j s_j w_j C(q; v_c, d_j)
            + sum_kj dv_k s_j w_j C(q; e_k, d_j)

    each term over the cell's region of ``q`` (:class:`OverCell`: the value at the centre and
    the derivatives over the box, for the first three; a ball of the box for the last, a product
    of two radii), its centre through ``P`` exactly and its radius with absolute values
    (``|dv_k|`` at most the velocity box's radii, ``|s_j| <= 1``). The bound is affine in the
    velocity radii: :meth:`coefficients` gives ``(A, B)`` with ``sup ||P C P^T|| <= A + B dv``
    for every velocity box of centre ``v_c`` and radii ``dv``, so that a wider velocity box (a
    larger ``r_max``) costs no new enclosure."""

    def __init__(
        self,
        weights: np.ndarray,
        center: OverCell,
        per_velocity: OverCell,
        per_parameter: OverCell | None,
        per_both: OverCell | None,
    ):
        """The four terms over the cells, as :meth:`sharing` encloses them: ``weights`` the
        set's weights ``w_j`` along the shared directions ``d_j`` (zero where it has none),
        ``center`` ``C(q; v_c, pi_c)`` (cells, n, n), ``per_velocity`` ``C(q; e_k, pi_c)`` (cells,
        k, n, n), ``per_parameter`` ``C(q; v_c, d_j)`` (cells, j, n, n) and ``per_both`` ``C(q;
        e_k, d_j)`` (cells, k, j, n, n) (``None`` without directions)."""
        self.pi_rad = weights
        self.center, self.per_velocity = center, per_velocity
        self.per_parameter, self.per_both = per_parameter, per_both

    @classmethod
    def sharing(
        cls,
        regressor: BallRegressor,
        q: Ball,
        forms: list[tuple[np.ndarray, PlantParameters]],
    ) -> list[CenteredCoriolis]:
        """One form per ``(v_center, parameters)`` over the same box of ``q`` (sets of any
        centres and weights: the plant's and the mismatch's, of each piece of the box). The terms
        that do not depend on a set's centre or weights are enclosed once for all: ``C(q; e_k,
        d_j)`` along the union of the sets' directions, ``C(q; e_k, pi_c)`` of every centre in
        one call, and ``C(q; v_c, .)`` of every centre and direction in one call per distinct
        ``v_c`` (each row is computed as it would be alone, up to the order of rounding). The
        first three terms by their value at the box's centre and their derivatives over the box
        (:class:`OverCell`), the fourth by a ball of the box."""
        keys, directions = shared_directions([parameters for _, parameters in forms])
        # The centres' rows: a shifted set's centre is its base's minus the shift, and every
        # term is linear in the parameters, so it is formed from theirs (rows shared).
        rows: list[Ball] = []

        def row(x: Ball) -> int:
            for index, known in enumerate(rows):
                if np.array_equal(known.mid, x.mid) and np.array_equal(known.rad, x.rad):
                    return index
            rows.append(x)
            return len(rows) - 1

        combinations = [
            ((row(p.shift[0]), 1.0), (row(Ball.point(p.shift[1])), -1.0))
            if p.shift is not None
            else ((row(p.centre), 1.0),)
            for _, p in forms
        ]
        centres = stack(rows, 0)
        # Each of the first three terms by its value at the box's centre and its derivatives
        # along every coordinate over the box (the regressor's slopes: one pass of jets whose
        # directions share the value).
        centre = Ball.point(q.mid)
        # C(q; e_k, pi_c) of every centre by its Taylor form; C(q; e_k, d_j), which enters
        # times the velocity's and the parameters' radii both, by a ball of the box.
        each = OverCell(
            regressor.christoffel_matrices(centre, centres),
            regressor.christoffel_slopes(q, centres),
        )
        per_both = OverCell(regressor.christoffel_matrices(q, directions)) if keys else None
        by_velocity: dict[bytes, tuple[list[int], np.ndarray]] = {}
        for index, (v_center, _) in enumerate(forms):
            key = np.ascontiguousarray(v_center).tobytes()
            by_velocity.setdefault(key, ([], v_center))[0].append(index)
        centre_terms: dict[int, tuple[OverCell, OverCell | None]] = {}
        count = len(rows)
        chosen = concatenate([centres, directions], 0)  # every centre's row, then the directions
        for indices, v_center in by_velocity.values():
            values = OverCell(
                regressor.coriolis_matrices(centre, Ball.point(v_center), chosen),
                regressor.coriolis_slopes(q, v_center, chosen),
            )
            along = values.select((slice(count, None),)) if keys else None
            for index in indices:
                centre_terms[index] = (combined(values, combinations[index], ()), along)
        return [
            cls(
                parameters.weights_along(keys), centre_terms[index][0],
                combined(each, combinations[index], (slice(None),)), centre_terms[index][1],
                per_both,
            )
            for index, (_, parameters) in enumerate(forms)
        ]  # fmt: skip

    def coefficients(
        self, P: np.ndarray, radii: np.ndarray, ball: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(A, B)``, shapes (cells,) and (cells, n): ``sup ||P C P^T||_2 <= A + B dv`` per cell
        over the cells' regions (``P``: (cells, n, n); ``dv``: the velocity radii, (cells, n);
        ``radii``: the half-widths of the reference along each coordinate, (cells, n), and
        ``ball`` the tube's radius: ``sum_l |dq_l| s_l <= sum_l r_l s_l + rho ||s||_2``)."""
        absolute = np.abs(P)

        def congruent(Q: np.ndarray, X: np.ndarray) -> np.ndarray:
            index = (slice(None),) + (None,) * (X.ndim - 3)
            return Q[index] @ X @ np.swapaxes(Q, -1, -2)[index]

        def through(Q: np.ndarray, X: np.ndarray) -> np.ndarray:
            return spectral_norm(congruent(Q, X))

        def entrywise(X: Ball) -> np.ndarray:
            """``|P X P^T| <= |P X.mid P^T| + |P| X.rad |P|^T`` for every matrix of the ball."""
            return np.abs(congruent(P, X.mid)) + congruent(absolute, X.rad)

        def spread(N: np.ndarray) -> np.ndarray:
            """``sup ||P sum_l dq_l X_l P^T||`` over the region, for ``|P X_l P^T| <= N_l``
            entrywise (``N``: (cells, l, ..., n, n)): entrywise ``sum_l |dq_l| N_l <= sum_l r_l
            N_l + rho (sum_l N_l^2)^(1/2)`` (Cauchy-Schwarz on the tube's ball), and one norm,
            since the spectral norm is monotone on non-negative matrices. (Per coordinate,
            ``sum_l r_l ||N_l|| + rho ||(||N_l||)_l||`` costs ``n`` norms and was never smaller on
            the UR5.)"""
            r = radii.reshape(radii.shape + (1,) * (N.ndim - 2))
            return spectral_norm(np.sum(r * N, axis=1) + ball * np.sqrt(np.sum(N * N, axis=1)))

        def structured(X: OverCell) -> np.ndarray:
            out = through(P, X.value.mid) + through(absolute, X.value.rad)
            if X.slopes is not None:
                out = out + spread(entrywise(X.slopes))
            return out

        def summed_ball(X: Ball, weights: np.ndarray, triangle: bool) -> np.ndarray:
            """``sup ||P sum_j dpi_j X_j P^T||`` over ``|dpi_j| <= weights_j`` (axis -3 is j).
            The centres: ``|sum_j dpi_j Y_j| <= sum_j w_j |Y_j|`` entrywise (``Y_j = P X_j
            P^T``), and the spectral norm is monotone on non-negative matrices (``||A|| <= |||A|||
            <= ||B||`` for ``|A| <= B``), so one norm bounds them all; with ``triangle`` and few
            directions the triangle inequality ``sum_j w_j ||Y_j||`` is also tried, the smaller
            kept. The (non-negative) radii are summed first, ``|| |P| sum_j w_j R_j |P|^T ||``."""
            Y = congruent(P, X.mid)
            centres = spectral_norm(np.einsum("...jab,j->...ab", np.abs(Y), weights))
            if triangle and len(weights) <= TRIANGLE_DIRECTIONS:
                centres = np.minimum(centres, spectral_norm(Y) @ weights)
            radius = np.einsum("...jab,j->...ab", X.rad, weights)
            return centres + through(absolute, radius)

        def summed(X: OverCell, weights: np.ndarray, triangle: bool) -> np.ndarray:
            out = summed_ball(X.value, weights, triangle)
            if X.slopes is not None:
                # |P sum_j dpi_j X_lj P^T| <= sum_j w_j |P X_lj P^T| entrywise, per coordinate l.
                out = out + spread(np.einsum("...jab,j->...ab", entrywise(X.slopes), weights))
            return out

        constant = structured(self.center)
        per_velocity = structured(self.per_velocity)
        if self.per_parameter is not None:
            constant = constant + summed(self.per_parameter, self.pi_rad, triangle=True)
            # (cells, k); the triangle inequality there would cost k norms per direction, and
            # this term multiplies two radii: it moved no floor by more than 1e-8 (below).
            per_velocity = per_velocity + summed(self.per_both, self.pi_rad, triangle=False)
        return constant * (1 + LAPACK_MARGIN), per_velocity * (1 + LAPACK_MARGIN)


#: Up to this many parameter directions, a Coriolis form's parameter part ``C(q; v_c, d_j)`` is
#: also bounded by the triangle inequality (one norm per direction; it can beat the entrywise
#: sum for a few). Not for ``C(q; e_k, d_j)``, whose ``n`` times as many norms were 38 % of a
#: UR5 certificate's and changed no floor or period of the RR arm, the UR5, the Panda or the
#: demo arms by more than 1e-8 relative (2026-12-06).
TRIANGLE_DIRECTIONS = 24

#: The Coriolis forms are enclosed over at most this many bytes of recursion at a time (their
#: Christoffel batch grows as ``n^4`` per cell, and ``n^5`` with its derivatives).
CORIOLIS_CHUNK_BYTES = 2**28


def coriolis_coefficients(
    regressor: BallRegressor,
    q: Ball,
    radii: np.ndarray,
    ball: float,
    forms: list[tuple[np.ndarray, PlantParameters, np.ndarray]],
) -> list[tuple[np.ndarray, np.ndarray]]:
    """:meth:`CenteredCoriolis.coefficients` of each form ``(v_center, parameters, P)`` of
    :meth:`CenteredCoriolis.sharing` through its factor ``P`` ((cells, n, n)) over the cells'
    regions (``q`` their boxes, ``radii`` the reference's half-widths, ``ball`` the tube),
    computed over chunks of cells so that memory stays bounded whatever the arm (every cell's
    enclosure is independent of the others'): ``out[form] = (A, B)``."""
    cells, n = q.mid.shape
    rows = len(forms) + len(shared_directions([parameters for _, parameters, _ in forms])[0])
    per_cell = n * (n + 1) // 2 * rows * n * 3 * 8 * 4  # the backward pass's force rows
    per_cell *= 2 * (n + 1)  # and the derivatives along each coordinate
    chunk = max(1, int(CORIOLIS_CHUNK_BYTES // max(per_cell, 1)))
    parts: list[list[tuple[np.ndarray, np.ndarray]]] = []
    for start in range(0, cells, chunk):
        part = slice(start, min(cells, start + chunk))
        chunk_forms = [(v[part], parameters) for v, parameters, _ in forms]
        shared = CenteredCoriolis.sharing(regressor, q[part], chunk_forms)
        parts.append(
            [
                form.coefficients(P[part], radii[part], ball)
                for form, (_, _, P) in zip(shared, forms, strict=True)
            ]
        )
    return [
        tuple(np.concatenate([p[f][i] for p in parts]) for i in range(2)) for f in range(len(forms))
    ]


def shared_directions(
    sets: list[PlantParameters],
) -> tuple[tuple[tuple[str, str], ...], Ball]:
    """The union of the sets' directions (keys, and the direction of each: balls (p, 10 dof)), in
    the order they first appear (a key names the same direction in every set)."""
    keys, mids, rads = [], [], []
    for parameters in sets:
        for k, key in enumerate(parameters.keys):
            if key not in keys:
                keys.append(key)
                mids.append(parameters.directions.mid[k])
                rads.append(parameters.directions.rad[k])
    size = sets[0].centre.mid.shape[0]
    if not keys:
        return (), Ball.point(np.zeros((0, size)))
    return tuple(keys), Ball(np.array(mids), np.array(rads))


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


#: At most this many generators of a link's parameter set are enumerated at their vertices; the
#: others enter by the triangle inequality (sound either way; cost 2^VERTEX_COORDINATES).
VERTEX_COORDINATES = 5


@dataclasses.dataclass(frozen=True)
class LinkMismatch:
    """One link's ``w = W A delta + G(delta) e`` as :func:`link_bound` takes it: the products
    and radii that do not depend on the matrix ``X`` the norm is taken through, formed once for
    the four norms of :meth:`MismatchNorms.link` (:func:`link_mismatch`)."""

    link: LinkParameters
    WA: np.ndarray  # W.mid @ A, (cells, n, 10)
    radius: np.ndarray  # what the balls' radii add to |W A delta| per row, (cells, n)
    GA: np.ndarray | None  # G.mid @ A, (cells, k, n, 10)
    spread: np.ndarray | None  # what the radii add to ||G(delta)|| per row, (cells, n)


def link_mismatch(W: Ball, G: Ball | None, link: LinkParameters) -> LinkMismatch:
    """:class:`LinkMismatch` of ``W``: (cells, n, 10), ``G``: (cells, k, n, 10) (the Jacobian
    along the tube) or ``None``, and the link's parameter set."""
    A = link.A
    magnitude, residual, absolute_A = link.magnitude, link.residual, np.abs(A)
    radius = (W.rad + 40 * 2.0**-53 * np.abs(W.mid)) @ (absolute_A @ magnitude)  # (cells, n)
    radius = radius + np.abs(W.mid) @ (absolute_A @ residual)
    GA = spread = None
    if G is not None:
        GA = G.mid @ A
        spread = (G.rad + 40 * 2.0**-53 * np.abs(G.mid)) @ (absolute_A @ magnitude)
        spread = spread + np.abs(G.mid) @ (absolute_A @ residual)
        spread = np.sqrt(np.sum(spread * spread, axis=1))  # (cells, n)
    return LinkMismatch(link, W.mid @ A, radius, GA, spread)


def link_bound(X: np.ndarray, mismatch: LinkMismatch) -> np.ndarray:
    """Per cell, ``(c, g)`` with ``||X w|| <= c + rho g`` over ``w = W A delta + G(delta) e`` for
    every ``delta`` of the link's set, every ``W``, ``G`` in their balls and ``||e|| <= rho``
    (``X``: (cells, m, n); ``mismatch``: :func:`link_mismatch` of ``W``, ``G`` (the Jacobian
    along the tube, enclosed over a tube at least as wide as ``rho``) and the link). Shape (2,
    cells).

    ``||X W A delta||`` is convex in ``delta``: its maximum over the set (a zonotope,
    :class:`~urpc.control.parameter_sets.LinkParameters`) is at a vertex. The
    :data:`VERTEX_COORDINATES` generators that move it most are enumerated at their vertices,
    the others enter by the triangle inequality (``||X W A w_i d_i||``); the radii of the balls
    (``W``, ``G``, the set's centre and directions) enter with ``|delta|`` bounded per
    coordinate."""
    link = mismatch.link
    XW = X @ mismatch.WA  # (cells, m, 10)
    generators = link.generators  # (10, p)
    norms = column_norm(XW @ generators)  # (cells, p)
    order = np.argsort(np.max(norms, axis=0) if len(norms) else norms.sum(0))[::-1]
    chosen, rest = order[:VERTEX_COORDINATES], order[VERTEX_COORDINATES:]
    corners = np.array(np.meshgrid(*[(-1.0, 1.0)] * len(chosen), indexing="ij")).reshape(
        len(chosen), -1
    )
    vertices = link.centre.mid[:, None] + generators[:, chosen] @ corners  # (10, V)
    bound = column_norm(XW @ vertices).max(-1) + norms[:, rest].sum(-1)
    absolute = np.abs(X)
    bound = bound + column_norm(absolute @ mismatch.radius[..., None])[:, 0]
    per_tube = np.zeros_like(bound)
    if mismatch.GA is not None:
        XG = X[:, None] @ mismatch.GA  # (cells, k, m, 10)
        spectral = spectral_norm(np.moveaxis(XG, -1, 1))  # (cells, 10): ||X G_j||_2
        triangle = spectral @ link.magnitude
        # Frobenius norm of X G(delta) at the enumerated vertices (a quadratic form in delta),
        # the other generators by the triangle inequality.
        flat = XG.reshape(XG.shape[0], -1, XG.shape[-1])
        H = np.swapaxes(flat, -1, -2) @ flat  # (cells, 10, 10)
        quadratic = np.sum((H @ vertices) * vertices, axis=-2)  # (cells, V)
        frobenius = np.sqrt(np.maximum(quadratic, 0.0)).max(-1) * (1 + 1e-10)
        others = generators[:, rest]
        along = np.sqrt(np.maximum(np.sum((H @ others) * others, axis=-2), 0.0))
        frobenius = frobenius + along.sum(-1) * (1 + 1e-10)
        per_tube = (
            np.minimum(triangle, frobenius)
            + column_norm(absolute @ mismatch.spread[..., None])[:, 0]
        )
    return np.stack([bound, per_tube]) * (1 + 1e-10)
