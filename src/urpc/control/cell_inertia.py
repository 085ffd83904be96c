"""The inertia models of one cell of the certificate (:mod:`urpc.control.cells`): a symmetric
matrix (``M0``, the law's ``M_L``, each piece's ``M_L`` and ``M_U``) bounded over a cell of the
reference and the tube around it by a Taylor form.

From the matrix at the cell's centre (``M_c = L L^T``), its first derivatives there and its
second derivatives over a box that holds the cell, :func:`inertia_model` gives ``(1 - eps) M_c <=
M(q) <= (1 + eps) M_c``, from which every eigenvalue, generalized eigenvalue, trace and norm the
argument uses follows with one factorization of the centre matrix; ``M^-1 x = M_c^-1 x + L^-T ((1
+ F)^-1 - 1) L^-1 x`` with ``||F|| <= eps`` bounds the inverse applied to a vector. LAPACK's
rounding on the centre matrices (backward errors of order ``n u cond``) is covered by the relative
margin :data:`LAPACK_MARGIN` on each such figure.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..model.ball_arithmetic import concatenate
from ..model.regressor_balls import Ball, BallRegressor, Jet
from ..model.verified_norms import spectral_norm
from .cell_partition import inward, outward

#: Relative margin on every eigenvalue and norm computed by LAPACK from a cell's centre matrices.
LAPACK_MARGIN = 1e-9


#: The second derivatives are enclosed over at most this many bytes of their recursion at a time.
CURVATURE_CHUNK_BYTES = 2**28

#: The second-order terms keep the structure of the second derivatives (:func:`structured_terms`)
#: on the cells where the remainder's entrywise term exceeds this fraction of ``lambda_min``: on
#: the others it is too small for the extra norms to pay.
STRUCTURED_FROM = 0.05
#: :func:`structured_terms` takes at most this many bytes of products at a time.
STRUCTURE_CHUNK_BYTES = 2**26
#: The rounding of the products ``P mid_kj P^T`` in :func:`structured_terms`: each is off by at
#: most ``gamma_2n || |P| |mid_kj| |P|^T ||`` (two products of inner dimension ``n``), and each
#: such norm, weighted as in the sum, is at most the entrywise term (the spectral norm is
#: monotone on non-negative matrices), so the ``n (n + 1) / 2`` of them cost at most that many
#: times ``gamma_2n`` (about ``2 n u``) of it: this constant (``u`` with room to spare) times
#: ``2 n`` and the number of terms.
STRUCTURE_ROUNDING = 2 * 2.0**-53


@dataclasses.dataclass
class InertiaModel:
    """Per cell, a symmetric matrix model's centre ``M_c``, its Cholesky inverse ``P = L^-1`` and
    the relative radius ``eps``."""

    center: np.ndarray  # (cells, n, n)
    inverse_factor: np.ndarray  # P = L^-1, (cells, n, n)
    eps: np.ndarray  # (cells,)
    lam_min: np.ndarray  # lambda_min(M_c), (cells,)
    lam_max: np.ndarray  # lambda_max(M_c), (cells,)
    valid: np.ndarray  # M_c positive definite and eps < 1, (cells,)
    #: The part of ``eps`` that no narrower cell removes (the tube's first-order term), (cells,).
    eps_tube: np.ndarray

    @property
    def inverse(self) -> np.ndarray:
        P = self.inverse_factor
        return np.swapaxes(P, -1, -2) @ P

    def kappa(self) -> np.ndarray:
        """``||M^-1 x - M_c^-1 x|| <= kappa ||L^-1 x||`` over the enclosure."""
        eps = np.minimum(self.eps, 0.999999)
        return eps / (1 - eps) / np.sqrt(np.maximum(self.lam_min, 1e-300))


def inertia_model(
    center: Ball,
    slopes: Ball,
    radii: np.ndarray,
    ball: float,
    remainder: np.ndarray,
    slope_spread: np.ndarray,
    curvature: Curvature | None = None,
) -> tuple[InertiaModel, np.ndarray]:
    """The model of a symmetric matrix over the states ``q = q_c + x + e`` with ``|x_k| <= r_k``
    and ``||e||_2 <= ball`` (a cell of the reference and the tube around it), from its value at
    the centre (``center``, a ball of rounding width), its partial derivatives at the centre
    (``slopes``: (cells, k, n, n), ``D_k = dM/dq_k(q_c)``, a ball of rounding width) and bounds of
    its second derivatives over the region (:func:`taylor_terms`). By Taylor's theorem with the
    Lagrange remainder, ``M(q) - M_c = sum_k dq_k D_k + Z(dq)`` with ``|Z| <= remainder``
    entrywise, so that with ``P = L^-1``

        ||P (M(q) - M_c) P^T|| <= || |P| R_c |P|^T || + sum_k r_k s_k + ball ||s||_2
                                  + || |P| remainder |P|^T ||,
        s_k = ||P D_k P^T||_2 + || |P| rad(D_k) |P|^T ||_2

    (``sum_k |e_k| s_k <= ||e||_2 ||s||_2``: the tube is a ball, which its bounding box would
    over-state by up to ``sqrt(n)``). The first-order part keeps the structure of each
    derivative (an entrywise bound loses it through ``|P|`` where the lightest mode couples the
    joints). Over the region ``dM/dq_k`` differs from ``D_k`` by at most ``slope_spread`` (cells,
    k, n, n) entrywise, so the slopes returned for rates ``dM/dt = sum_k qd_k dM/dq_k`` are
    ``(s_k + || |P| spread_k |P|^T ||) / lambda_min(P M_c P^T)`` per cell (cells, k). The two
    second-order terms go through ``|P|`` entrywise, except on the cells where the remainder's
    term reaches :data:`STRUCTURED_FROM` of ``lambda_min(P M_c P^T)``: there, given the second
    derivatives themselves (``curvature``), they keep the structure of their centres too
    (:func:`structured_terms`), whichever bound is the smaller."""
    mid = center.mid
    eigenvalues = np.linalg.eigvalsh(mid)
    lam_min, lam_max = eigenvalues[..., 0], eigenvalues[..., -1]
    positive = lam_min > 1e-12 * np.maximum(lam_max, 1e-300)
    safe = np.where(positive[..., None, None], mid, np.eye(mid.shape[-1]))
    L = np.linalg.cholesky(safe)
    identity = np.broadcast_to(np.eye(mid.shape[-1]), mid.shape)
    P = np.linalg.solve(L, identity)  # L^-1, batched
    Pt = np.swapaxes(P, -1, -2)
    floor = np.linalg.eigvalsh(P @ safe @ Pt)[..., 0]
    absolute, absolute_t = np.abs(P), np.abs(Pt)
    Pk, Pkt = P[:, None], Pt[:, None]
    first = spectral_norm(Pk @ slopes.mid @ Pkt) + spectral_norm(
        absolute[:, None] @ slopes.rad @ absolute_t[:, None]
    )
    first = first * (1 + LAPACK_MARGIN)
    second = spectral_norm(absolute @ remainder @ absolute_t)
    change = spectral_norm(absolute[:, None] @ slope_spread @ absolute_t[:, None])
    if curvature is not None:
        chosen = np.flatnonzero(second > STRUCTURED_FROM * floor)
        if len(chosen):
            structured, structured_change = structured_terms(P[chosen], curvature.cells(chosen))
            n = mid.shape[-1]
            rounding = STRUCTURE_ROUNDING * 2 * n * (n * (n + 1) // 2)
            second[chosen] = np.minimum(second[chosen], structured + rounding * second[chosen])
            change[chosen] = np.minimum(
                change[chosen], structured_change + rounding * change[chosen]
            )
    spread = (
        spectral_norm(absolute @ center.rad @ absolute_t)
        + np.sum(radii * first, axis=-1)
        + ball * np.sqrt(np.sum(first * first, axis=-1))
        + second
    )
    eps = spread / floor * (1 + LAPACK_MARGIN) + LAPACK_MARGIN
    eps_tube = ball * np.sqrt(np.sum(first * first, axis=-1)) / floor
    model = InertiaModel(mid, P, eps, lam_min, lam_max, positive & (eps < 1), eps_tube)
    rates = first + change
    return model, rates * (1 + LAPACK_MARGIN) / floor[:, None]


@dataclasses.dataclass(frozen=True)
class Curvature:
    """The second derivatives ``H_kj = d^2 M / dq_k dq_j`` of one model over boxes of ``q``
    (``mid``, ``rad``: (boxes, k, j, n, n), symmetric in ``k, j``), the box that holds each
    cell's region (``group``: (cells,)) and the half-widths of that region about the cell's
    centre (``widths``: (cells, k), ``|dq_k| <= w_k``)."""

    mid: np.ndarray
    rad: np.ndarray
    group: np.ndarray
    widths: np.ndarray

    def cells(self, chosen: np.ndarray) -> Curvature:
        """The same for the ``chosen`` cells only."""
        return Curvature(self.mid, self.rad, self.group[chosen], self.widths[chosen])


def structured_terms(P: np.ndarray, curvature: Curvature) -> tuple[np.ndarray, np.ndarray]:
    """The two second-order terms of :func:`inertia_model` with the structure of the second
    derivatives' centres kept, per cell (``P``: (cells, n, n)). Each entry of the Lagrange
    remainder takes its own point of the region, so ``Z = 1/2 sum_kj dq_k dq_j (mid_kj + E_kj)``
    with ``|E_kj| <= rad_kj`` entrywise, and by symmetry in ``k, j``

        ||P Z P^T|| <= sum_{k <= j} f_kj w_k w_j ||P mid_kj P^T||
                       + || |P| (sum_{k <= j} f_kj w_k w_j rad_kj) |P|^T ||,

    ``f_kk = 1/2``, ``f_kj = 1`` otherwise; the change of ``dM/dq_k`` over the region, ``sum_j
    dq_j (mid_kj + E_kj)``, likewise: ``sum_j w_j ||P mid_kj P^T|| + || |P| sum_j w_j rad_kj
    |P|^T ||``. Returns the first (cells,) and the second (cells, k). Where the lightest mode
    couples the joints, ``|P|`` loses the cancellation that ``P mid_kj P^T`` keeps: on an 8-link
    chain the centres' part of the remainder's term is 0.04 of ``lambda_min`` instead of 0.17
    (over a group's box; the radii's part, 0.35 there, is the same either way). The products'
    rounding is not included (:data:`STRUCTURE_ROUNDING`)."""
    cells, n = P.shape[0], P.shape[-1]
    first, second = np.triu_indices(n)
    factor = np.where(first == second, 0.5, 1.0)
    remainder = np.empty(cells)
    change = np.empty((cells, n))
    chunk = max(1, STRUCTURE_CHUNK_BYTES // (len(first) * n * n * 8 * 3))
    for start in range(0, cells, chunk):
        part = slice(start, start + chunk)
        p, box, w = P[part], curvature.group[part], curvature.widths[part]
        pt, absolute = np.swapaxes(p, -1, -2), np.abs(p)
        absolute_t = np.swapaxes(absolute, -1, -2)
        pairs = curvature.mid[box[:, None], first, second]  # (cells, pairs, n, n)
        norms = spectral_norm(p[:, None] @ pairs @ pt[:, None])
        full = np.zeros((len(p), n, n))
        full[:, first, second] = norms
        full[:, second, first] = norms  # ||P mid_kj P^T||, (cells, k, j)
        weights = factor * w[:, first] * w[:, second]
        radial = np.einsum("cp,cpab->cab", weights, curvature.rad[box[:, None], first, second])
        remainder[part] = np.sum(weights * norms, axis=-1) + spectral_norm(
            absolute @ radial @ absolute_t
        )
        radial_k = np.einsum("cj,ckjab->ckab", w, curvature.rad[box])
        change[part] = np.einsum("cj,ckj->ck", w, full) + spectral_norm(
            absolute[:, None] @ radial_k @ absolute_t[:, None]
        )
    return remainder * (1 + 1e-12), change * (1 + 1e-12)


def taylor_terms(
    curvatures: Ball, group: np.ndarray, widths: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Entrywise bounds of the second-order terms of :func:`inertia_model` per cell: with
    ``|H_kj| <= |mid| + rad`` the second derivatives over a box that holds the cell's region
    (``curvatures``: (groups, k, j, models, n, n), cell ``c`` in box ``group[c]``) and ``|dq_k| <=
    w_k`` (``widths``: (cells, k)), the Lagrange remainder ``1/2 sum_kj |dq_k| |dq_j| |H_kj|``
    (cells, models, n, n) and the change of each first derivative over the region, ``sum_j w_j
    |H_kj|`` (cells, k, models, n, n)."""
    magnitude = (np.abs(curvatures.mid) + curvatures.rad) * (1 + 1e-12)
    w = widths * (1 + 1e-12)
    cells, (n, _, models, rows, columns) = len(group), magnitude.shape[1:]
    spread = np.empty((cells, n, models, rows, columns))
    for box in np.unique(group):
        members = np.flatnonzero(group == box)
        spread[members] = np.einsum("cj,kjmab->ckmab", w[members], magnitude[box])
    remainder = 0.5 * np.einsum("ck,ckmab->cmab", w, spread)
    return remainder * (1 + 1e-12), spread * (1 + 1e-12)


def congruence(P: np.ndarray, A: np.ndarray) -> np.ndarray:
    """``P A P^T`` per cell."""
    return P @ A @ np.swapaxes(P, -1, -2)


def safe_cholesky(center: np.ndarray, valid: np.ndarray) -> np.ndarray:
    safe = np.where(valid[..., None, None], center, np.eye(center.shape[-1]))
    return np.linalg.cholesky(safe)


def curvatures_over(regressor: BallRegressor, boxes: Ball, parameters: np.ndarray) -> Ball:
    """The second derivatives ``d^2 M / dq_k dq_j`` of each model (rows of ``parameters``,
    armature excluded) over boxes of ``q`` ((boxes, n)): (boxes, k, j, models, n, n), computed
    over at most :data:`CURVATURE_CHUNK_BYTES` of recursion at a time."""
    n = boxes.mid.shape[-1]
    per_box = n * (n + 1) // 2 * n * len(parameters) * 3 * 8 * 8
    chunk = max(1, int(CURVATURE_CHUNK_BYTES // max(per_box, 1)))
    parts = [
        regressor.mass_matrix_curvatures(boxes[start : start + chunk], parameters)
        for start in range(0, len(boxes.mid), chunk)
    ]
    return concatenate(parts, 0)


def group_curvatures(
    regressor: BallRegressor, parameters: np.ndarray, boxes: Ball, group: np.ndarray
) -> tuple[Ball, Ball]:
    """The boxes of the groups of first cells (the hull of each group's cells' ``boxes``, with a
    relative slack of ``1e-12`` so that they lie well inside; ``group`` consecutive) and the
    second derivatives of every model's ``M`` over them (:func:`curvatures_over`)."""
    starts = np.flatnonzero(np.r_[True, np.diff(group) != 0])
    lower = np.minimum.reduceat(outward(boxes, -1), starts, axis=0)
    upper = np.maximum.reduceat(outward(boxes, 1), starts, axis=0)
    slack = 1e-12 * (np.abs(lower) + np.abs(upper))
    hull = Ball.hull(lower - slack, upper + slack)
    return hull, curvatures_over(regressor, hull, parameters)


def curvatures_for(
    regressor: BallRegressor,
    parameters: np.ndarray,
    boxes: Ball,
    curvatures: Ball,
    q: Ball,
    group: np.ndarray,
    own: np.ndarray,
) -> tuple[Ball, np.ndarray]:
    """The second derivatives that hold over each cell's box ``q`` (the cells of ``group``)
    and the index of each cell's: its group's (``boxes``, ``curvatures`` of
    :func:`group_curvatures`) when the box lies inside it (checked with outward and inward
    rounding), or one over its own box, appended: for the cells marked ``own`` (over a group's
    box, several times wider, ball arithmetic through a long chain encloses the second
    derivatives far wider than they are: on an 8-link chain a radius of three times their
    centre, which no split of a cell that reuses it removes), and for a cell that sticks out (a
    half's Taylor box need not lie in its parent's)."""
    inside = np.all(
        (outward(q, -1) >= inward(boxes, -1)[group]) & (outward(q, 1) <= inward(boxes, 1)[group]),
        axis=-1,
    )
    inside &= ~own
    if np.all(inside):
        return curvatures, group
    outside = np.flatnonzero(~inside)
    lower, upper = outward(q, -1)[outside], outward(q, 1)[outside]
    slack = 1e-12 * (np.abs(lower) + np.abs(upper))
    regions = Ball.hull(lower - slack, upper + slack)
    extra = curvatures_over(regressor, regions, parameters)
    group = group.copy()
    group[outside] = len(boxes.mid) + np.arange(len(outside))
    return concatenate([curvatures, extra], 0), group


def inertia_models(
    regressor: BallRegressor,
    parameters: np.ndarray,
    armature: np.ndarray,
    q: Ball,
    reference_radii: np.ndarray,
    tube: float,
    curvatures: Ball,
    group: np.ndarray,
) -> tuple[list[InertiaModel], list[np.ndarray]]:
    """The inertia model of each model copy (rows of ``parameters``, standard parameters of
    its bodies, and of ``armature``) over the cells of the reference (half-widths
    ``reference_radii``) and the tube ``||e|| <= tube`` around them, ``q`` a box that holds
    both (:func:`inertia_model`), with the slopes ``s_k`` for its rates; ``curvatures`` the
    second derivatives over boxes (:func:`curvatures_over`), cell ``c``'s box holding its region
    being ``group[c]``."""
    cells, n = q.mid.shape
    centers = regressor.mass_matrices(Ball.point(q.mid), parameters)
    diagonal = np.einsum("pi,ij->pij", armature, np.eye(n))
    centers = Ball(centers.mid + diagonal, centers.rad)  # (cells, P, n, n)
    along = Jet(
        Ball.point(np.broadcast_to(q.mid[:, None, :], (cells, n, n))),
        Ball.point(np.broadcast_to(np.eye(n), (cells, n, n))),
    )
    slopes = regressor.mass_matrices(along, parameters).dot  # (cells, k, P, n, n)
    remainder, spread = taylor_terms(curvatures, group, reference_radii + tube)
    pairs = [
        inertia_model(
            centers[:, index], slopes[:, :, index], reference_radii, tube,
            remainder[:, index], spread[:, :, index],
            Curvature(
                curvatures.mid[:, :, :, index], curvatures.rad[:, :, :, index] * (1 + 1e-12),
                group, (reference_radii + tube) * (1 + 1e-12),
            ),
        )
        for index in range(len(parameters))
    ]  # fmt: skip
    return [model for model, _ in pairs], [slope for _, slope in pairs]
