"""The maximum of a link's CoM quadratic over its CoM box (``docs/bounds.md``, ``vertex`` steps 3-4).

For one (joint, link) pair, ``m_hi G(c)`` (``G(c) = y . phi(c)``, ``phi(c)`` the standard
parameters of a unit point mass at ``c``) is a quadratic in the CoM. In the scaled coordinates
``u in [-1, 1]^3`` of the link's CoM box (``c = center + h u``, ``h`` the half-widths [m]; an
exact axis has ``h = 0`` and drops out) it reads::

    q(u) = alpha + beta . u + (1/2) sum_k K_kk u_k^2 + sum_{j < k} K_jk u_j u_k

with ``alpha, beta, K`` linear in ``y`` (:func:`quadratic_columns`). :func:`box_maximum` bounds
``max s q`` over the box for ``s = +1`` or ``-1`` from the vertex values
(:func:`vertex_values`):

* ``exact=False``: the vertex maximum plus ``sum_k M_k``, ``M_k = max(0, -s K_kk) / 2`` (the
  interpolation margin, Lemma 3 of ``docs/bounds.md``);
* ``exact=True``: the exact maximum. It is attained at a vertex or at the stationary point of
  ``s q`` restricted to a face (edge, square, cube) on which ``s q`` is strictly concave, inside
  that face; edges are solved in closed form from their end values, squares and the cube by
  Cramer's rule. A face is skipped when its interpolation bound (vertex maximum plus its
  margins) is not above the best value so far, and a face whose concavity is too close to call
  (relative determinant within ``SINGULAR`` of zero) contributes that interpolation bound.

Compiled with numba (no fast-math) and inlined into the kernel of :mod:`urpc.bounds.vertex`.
"""

from __future__ import annotations

import numba
import numpy as np

from ..model.uncertainty import barycentric_from_physical

#: A face's Hessian is called strictly concave (or indefinite) only when its determinant relative
#: to the product of its diagonal is above ``SINGULAR`` (below ``-SINGULAR``); in between, the face
#: takes its interpolation bound (sound, and rare).
SINGULAR = 1e-4
#: A computed stationary point counts as inside its face up to this distance in ``u`` (accepting
#: one slightly outside only loosens the bound; the computed point is far more accurate than this
#: whenever the relative determinant exceeds ``SINGULAR``).
INSIDE = 1e-6
#: Rows of :func:`quadratic_columns`: ``alpha``, ``beta_k``, ``K_kk``, then ``K_01, K_02, K_12``.
N_QUADRATIC = 10


def unit_mass_parameters(com: np.ndarray) -> np.ndarray:
    """``phi(c)``: standard parameters of a unit point mass at ``com`` [m] (link frame), so that
    ``y . pi = m y . phi(c) + y[4:10] . I_C``."""
    return barycentric_from_physical(np.concatenate([[1.0], com, np.zeros(6)]))


def _polarized(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Standard parameters ``[0, 0, 0, 0, I]`` of the symmetric bilinear form whose diagonal is
    ``phi``'s rotational part: ``I(a, b) = (a . b) 1 - (a b^T + b a^T) / 2`` (Pinocchio order xx,
    xy, yy, xz, yz, zz), so that ``I(c, c) = |c|^2 1 - c c^T``."""
    S = np.dot(a, b) * np.eye(3) - 0.5 * (np.outer(a, b) + np.outer(b, a))
    return np.concatenate([np.zeros(4), [S[0, 0], S[0, 1], S[1, 1], S[0, 2], S[1, 2], S[2, 2]]])


def quadratic_columns(center: np.ndarray, half_width: np.ndarray) -> np.ndarray:
    """``(10, N_QUADRATIC)`` columns ``B`` with ``y . B = [alpha, beta_k, K_kk, K_01, K_02,
    K_12]`` of ``q(u) = y . phi(center + h u)`` for a link regressor row ``y``, CoM box center
    [m] and half-widths ``h`` [m]."""
    columns = np.zeros((10, N_QUADRATIC))
    columns[:, 0] = unit_mass_parameters(center)
    unit = np.eye(3)
    for k in range(3):
        # d phi / d c_k = [0, e_k, 2 I(c, e_k)],  d2 phi / d c_k d c_l = [0, 0, 2 I(e_k, e_l)].
        slope = np.concatenate([[0.0], unit[k], np.zeros(6)]) + 2.0 * _polarized(center, unit[k])
        columns[:, 1 + k] = half_width[k] * slope
        columns[:, 4 + k] = half_width[k] ** 2 * 2.0 * _polarized(unit[k], unit[k])
    for j, k in ((0, 1), (0, 2), (1, 2)):
        columns[:, 6 + j + k] = half_width[j] * half_width[k] * 2.0 * _polarized(unit[j], unit[k])
    return columns


@numba.njit(cache=True, nogil=True, boundscheck=False)
def vertex_values(z, at):
    """``q`` at the 8 vertices into ``z[at + v]`` (bit ``k`` of ``v``: ``u_k = +1``), from
    ``alpha, beta, K`` in ``z[:N_QUADRATIC]``; returns their maximum and minimum."""
    b0, b1, b2 = z[1], z[2], z[3]
    k01, k02, k12 = z[7], z[8], z[9]
    center = z[0] + 0.5 * (z[4] + z[5] + z[6])
    low0, high0 = center - b0, center + b0
    # (u0, u1) = (-, -), (+, -), (-, +), (+, +)
    v00, v10 = low0 - b1 + k01, high0 - b1 - k01
    v01, v11 = low0 + b1 - k01, high0 + b1 + k01
    # the third axis: +- (b2 + u0 k02 + u1 k12)
    d00, d10 = b2 - k02 - k12, b2 + k02 - k12
    d01, d11 = b2 - k02 + k12, b2 + k02 + k12
    z[at + 0], z[at + 4] = v00 - d00, v00 + d00
    z[at + 1], z[at + 5] = v10 - d10, v10 + d10
    z[at + 2], z[at + 6] = v01 - d01, v01 + d01
    z[at + 3], z[at + 7] = v11 - d11, v11 + d11
    high = max(
        max(max(z[at + 0], z[at + 4]), max(z[at + 1], z[at + 5])),
        max(max(z[at + 2], z[at + 6]), max(z[at + 3], z[at + 7])),
    )
    low = min(
        min(min(z[at + 0], z[at + 4]), min(z[at + 1], z[at + 5])),
        min(min(z[at + 2], z[at + 6]), min(z[at + 3], z[at + 7])),
    )
    return high, low


@numba.njit(cache=True, nogil=True, boundscheck=False)
def box_maximum(z, sign, exact, at, best):
    """An upper bound of ``max s q`` over ``[-1, 1]^3`` (``s = sign``), exact if ``exact``;
    ``z[at : at + 8]`` the vertex values (:func:`vertex_values`), ``best`` their maximum times
    ``s``."""
    m0 = max(0.0, -0.5 * sign * z[4])
    m1 = max(0.0, -0.5 * sign * z[5])
    m2 = max(0.0, -0.5 * sign * z[6])
    if not exact or m0 + m1 + m2 == 0.0:
        return best + m0 + m1 + m2
    vertex_best = best
    # Edges: s q restricted to an edge along k is a parabola with curvature -2 M_k in u_k; with end
    # values a, b its maximum is (a + b) / 2 + M_k + (b - a)^2 / (16 M_k) when |b - a| < 4 M_k.
    for k in range(3):
        m = m0 if k == 0 else (m1 if k == 1 else m2)
        if m == 0.0:
            continue
        bit = 1 << k
        for v in range(8):
            if v & bit:
                continue
            a, b = sign * z[at + v], sign * z[at + (v | bit)]
            if max(a, b) + m <= best:
                continue
            d = b - a
            if abs(d) < 4.0 * m:
                best = max(best, 0.5 * (a + b) + m + d * d / (16.0 * m))
    # Squares (the third axis at an end) and the cube.
    for j, k, fixed in ((0, 1, 2), (0, 2, 1), (1, 2, 0)):
        mj = m0 if j == 0 else m1
        mk = m1 if k == 1 else m2
        if mj == 0.0 or mk == 0.0:
            continue
        for end in (0, 1 << fixed):
            corners = max(
                max(sign * z[at + end], sign * z[at + (end | (1 << j))]),
                max(sign * z[at + (end | (1 << k))], sign * z[at + (end | (1 << j) | (1 << k))]),
            )
            if corners + mj + mk <= best:
                continue
            e = 1.0 if end else -1.0
            const = z[0] + e * z[1 + fixed] + 0.5 * z[4 + fixed]
            rj = z[1 + j] + e * z[6 + j + fixed]  # K_jk sits at 6 + j + k
            rk = z[1 + k] + e * z[6 + k + fixed]
            pjk = -sign * z[6 + j + k]
            square = _square(sign, const, rj, rk, 2.0 * mj, 2.0 * mk, pjk, corners + mj + mk)
            best = max(best, square)
    whole = vertex_best + m0 + m1 + m2  # the interpolation bound of the cube
    if m0 > 0.0 and m1 > 0.0 and m2 > 0.0 and whole > best:
        best = max(best, _cube(z, sign, 2.0 * m0, 2.0 * m1, 2.0 * m2, whole))
    return best


@numba.njit(cache=True, nogil=True, boundscheck=False)
def _square(sign, const, rj, rk, pjj, pkk, pjk, fallback):
    """``s q`` at the stationary point of ``s q = s const + s r . x - x^T P x / 2`` on a square
    (``P = [[pjj, pjk], [pjk, pkk]]``, ``pjj, pkk > 0``), ``-inf`` if ``P`` is indefinite or the
    point is outside, ``fallback`` if ``P`` is too close to singular to tell."""
    scale = pjj * pkk
    det = scale - pjk * pjk
    if det < -SINGULAR * scale:
        return -np.inf  # indefinite: no local maximum inside the face
    if det <= SINGULAR * scale:
        return fallback
    rj, rk = sign * rj, sign * rk
    xj = (pkk * rj - pjk * rk) / det
    xk = (pjj * rk - pjk * rj) / det
    if max(abs(xj), abs(xk)) > 1.0 + INSIDE:
        return -np.inf  # the stationary point is outside the face
    # s q at the computed point (its error is second order in the point's).
    return sign * const + rj * xj + rk * xk - 0.5 * (pjj * xj * xj + pkk * xk * xk) - pjk * xj * xk


@numba.njit(cache=True, nogil=True, boundscheck=False)
def _cube(z, sign, p00, p11, p22, fallback):
    """``s q`` at the stationary point inside the cube (as :func:`_square`, by Sylvester's
    criterion and Cramer's rule); ``fallback``: the cube's interpolation bound."""
    p01, p02, p12 = -sign * z[7], -sign * z[8], -sign * z[9]
    minor = p00 * p11 - p01 * p01
    c00 = p11 * p22 - p12 * p12
    c01 = p02 * p12 - p01 * p22
    c02 = p01 * p12 - p02 * p11
    det = p00 * c00 + p01 * c01 + p02 * c02
    scale = p00 * p11 * p22
    if minor < -SINGULAR * p00 * p11 or (minor > SINGULAR * p00 * p11 and det < -SINGULAR * scale):
        return -np.inf  # indefinite (Sylvester's criterion)
    if minor <= SINGULAR * p00 * p11 or det <= SINGULAR * scale:
        return fallback
    r0, r1, r2 = sign * z[1], sign * z[2], sign * z[3]
    c11 = p00 * p22 - p02 * p02
    c12 = p01 * p02 - p00 * p12
    x0 = (c00 * r0 + c01 * r1 + c02 * r2) / det
    x1 = (c01 * r0 + c11 * r1 + c12 * r2) / det
    x2 = (c02 * r0 + c12 * r1 + minor * r2) / det
    if max(abs(x0), abs(x1), abs(x2)) > 1.0 + INSIDE:
        return -np.inf
    return (
        sign * z[0]
        + r0 * x0
        + r1 * x1
        + r2 * x2
        - 0.5 * (p00 * x0 * x0 + p11 * x1 * x1 + p22 * x2 * x2)
        - (p01 * x0 * x1 + p02 * x0 * x2 + p12 * x1 * x2)
    )
