"""The Newton-Euler recursion of :mod:`urpc.model.regressor_balls` as one compiled pass over a
batch: midpoint-radius ball arithmetic over a truncated Taylor algebra.

**The algebra.** Every scalar of the recursion is a vector of ``K`` components, each a ball: the
value and its derivatives. A product of two such scalars is ``c_o = sum a_i b_j`` over the
entries ``(i, j, o)`` of the algebra's product table (:class:`Algebra`): a ball (``K = 1``), a
jet (value and time derivative, ``K = 2``), a jet of jets (the hyper-dual numbers ``q + s e_k +
t e_j``, ``K = 4``), a value with ``D`` first derivatives sharing it (``K = 1 + D``), or a value
with its gradient and Hessian in ``n`` coordinates (``K = 1 + n + n (n + 1) / 2``). The
component ``(k, j)`` of the last is computed with the very terms, in the same order, as the
``d^2 / ds dt`` component of the hyper-dual number with ``s = e_k``, ``t = e_j``; the first
derivatives ``D`` of a shared value, as the jets along each direction: evaluating them together
shares the value (and the first derivatives) instead of recomputing them for every direction or
pair. ``cos`` and ``sin`` of a scalar are their Taylor polynomials of order 2 at the value,
``f(x0) + f'(x0) d + f''(x0) d^2 / 2`` with ``d`` the scalar's derivative part (``d^3 = 0``).

**Structural zeros.** Each vector of a component carries a flag: unset, the vector is exactly
zero (a point at 0) and every product with it is skipped, which is exact. The flags start from
the inputs (zero velocities of the mass matrices, unit accelerations, unit or sparse parameter
rows, derivative components along one joint) and propagate: a product is flagged when one of its
table entries has both operands flagged, a sum when one of its terms is. Nothing is padded:
parameter rows that vanish on a body give it no force, and a force row vanishes until it meets a
body that has one.

**Rounding.** Every ball of the recursion is computed as a sum of ``N`` terms, each a ball or a
product of two balls (a matrix-vector product contributes three terms per table entry, a cross
product two): the midpoint is the floating-point sum of the terms' midpoint products ``t_i`` (in
any order) and the radius is ``(sum rho_i + (N + 2) u sum |t_i|) (1 + 2 (N + 4) u)``, where
``rho_i = |a| rad_b + rad_a (|b| + rad_b)`` is a product's radius (a ball term's radius itself)
and ``u = 2^-53``. The exact sum differs from the floating-point one by at most ``gamma_N sum
|t_i| <= (N + 2) u sum |t_i|`` (a product rounding and at most ``N - 1`` additions on each term's
path, in any summation order; ``N u`` is tiny), and the radius, a sum of non-negative terms each
at most ``N + 4`` roundings deep (three in a product's radius, ``N - 1`` additions, the rounding
term, the inflation), is computed at least ``(1 - u)^(N + 4)`` times its exact value, which the
factor ``1 + 2 (N + 4) u`` more than makes up. A lone ball term, or a term scaled by ``0``,
``1`` or ``-1``, is copied exactly. Adding a child's force to its parent's, and the polarization
``(tau+ - tau-) / 4`` of the Christoffel, Coriolis and Slotine-Li columns, are ball sums as in
:mod:`urpc.model.ball_arithmetic` (``2u |mid|``, inflated by ``1 + 8u``), or copies where one
operand is exactly zero; the scaling by ``1/4`` is exact. ``cos``/``sin`` of a
ball ``[x - r, x + r]`` are ``cos x +- (|sin x| r + r^2 / 2)`` plus 2 ulps for the library's
rounding (as :func:`urpc.model.ball_arithmetic.cos_sin`). Compiled with numba: IEEE arithmetic,
no fast-math, so the compiler neither reassociates nor contracts the operations the analysis
counts. As in :mod:`urpc.model.ball_arithmetic`, underflow is not accounted for (the
recursion's quantities are far from ``1e-300``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numba
import numpy as np

#: Unit roundoff of IEEE double precision.
U = 2.0**-53
#: Factor that keeps a radius computed in rounded arithmetic above its exact value.
UP = 1.0 + 8 * U

_JIT = {"cache": True, "nogil": True, "boundscheck": False}


# ============================================================================ algebras
@dataclass(frozen=True)
class Algebra:
    """A truncated Taylor algebra: ``K`` components (0 the value) and its product table, sorted
    by first operand: the entries ``(i, tj[e], to[e])`` for ``e`` in ``ptr[i]:ptr[i + 1]``."""

    components: int
    ptr: np.ndarray
    tj: np.ndarray
    to: np.ndarray

    @staticmethod
    def of(entries: list[tuple[int, int, int]], components: int) -> Algebra:
        entries = sorted(entries, key=lambda e: (e[0], e[1]))  # stable: duplicates kept
        first = np.array([e[0] for e in entries], dtype=np.int64)
        ptr = np.searchsorted(first, np.arange(components + 1)).astype(np.int64)
        tj = np.array([e[1] for e in entries], dtype=np.int64)
        to = np.array([e[2] for e in entries], dtype=np.int64)
        return Algebra(components, ptr, tj, to)


@cache
def first_order(directions: int) -> Algebra:
    """A value and ``directions`` first derivatives (a jet for one direction)."""
    entries = [(0, 0, 0)]
    for d in range(1, directions + 1):
        entries += [(0, d, d), (d, 0, d)]
    return Algebra.of(entries, directions + 1)


@cache
def hyper_dual() -> Algebra:
    """A jet of jets: components ``(val.val, val.dot, dot.val, dot.dot)``."""
    entries = [(0, 0, 0), (0, 1, 1), (1, 0, 1), (0, 2, 2), (2, 0, 2)]
    entries += [(0, 3, 3), (1, 2, 3), (2, 1, 3), (3, 0, 3)]
    return Algebra.of(entries, 4)


def pair_index(n: int) -> np.ndarray:
    """The component of ``d^2 / dq_k dq_j`` in :func:`hessian` ``(n)``: ``(n, n)``, symmetric."""
    index = np.zeros((n, n), dtype=np.int64)
    first, second = np.triu_indices(n)
    index[first, second] = 1 + n + np.arange(len(first))
    index[second, first] = index[first, second]
    return index


@cache
def hessian(n: int) -> Algebra:
    """A value, its ``n`` first derivatives (components ``1 + k``) and its second derivatives
    (components :func:`pair_index`); the diagonal ``(k, k)`` gets the product of the first
    derivatives twice, as the hyper-dual ``s t`` component does with ``s = t = e_k``."""
    pairs = pair_index(n)
    K = 1 + n + n * (n + 1) // 2
    entries = [(0, x, x) for x in range(K)]
    for k in range(n):
        entries.append((1 + k, 0, 1 + k))
        for j in range(n):
            entries += [(1 + k, 1 + j, int(pairs[k, j]))] * (2 if j == k else 1)
    entries += [(int(c), 0, int(c)) for c in range(1 + n, K)]
    return Algebra.of(entries, K)


# ============================================================================ the model
@dataclass(frozen=True)
class Chain:
    """A robot's joints as arrays for the kernel (see :class:`urpc.model.regressor_balls.
    BallRegressor`): parents, kinds, axes, ``R(q) = A0 + cos q A1 + sin q A2`` (revolute) or the
    fixed rotation and ``p(q) = translation + direction q`` (prismatic), and children in
    reverse order of processing."""

    parent: np.ndarray  # (n,) int64, -1: the base
    revolute: np.ndarray  # (n,) bool
    axis: np.ndarray  # (n, 3)
    parts: np.ndarray  # (n, 3, 9): A0, A1, A2 (revolute) or the rotation in A0 (prismatic)
    translation: np.ndarray  # (n, 3)
    direction: np.ndarray  # (n, 3): rotation @ axis (prismatic), 0 (revolute)
    gravity: np.ndarray  # (3,)


# ============================================================================ accumulators
# A sum of terms per component ``o`` and entry ``l``: midpoints ``acm``, radii ``acr``, term
# magnitudes ``acs``, the number of terms ``acn[o]`` (0: the component is not flagged) and
# whether a rounded product entered it ``acx[o]``.
@numba.njit(**_JIT)
def _begin(acn, acx):  # pragma: no cover - compiled
    for o in range(acn.shape[0]):
        acn[o] = 0
        acx[o] = False


@numba.njit(**_JIT)
def _open(acm, acr, acs, acn, o, L):  # pragma: no cover - compiled
    if acn[o] == 0:
        for x in range(L):
            acm[o, x] = 0.0
            acr[o, x] = 0.0
            acs[o, x] = 0.0


@numba.njit(**_JIT)
def _finish(acm, acr, acs, acn, acx, L, outm, outr, outf):  # pragma: no cover - compiled
    """The balls of the sums: see the module's rounding analysis."""
    for o in range(acn.shape[0]):
        N = acn[o]
        if N == 0:
            outf[o] = False
        elif N == 1 and not acx[o]:
            outf[o] = True
            for x in range(L):
                outm[o, x] = acm[o, x]
                outr[o, x] = acr[o, x]
        else:
            outf[o] = True
            c = (N + 2) * U
            F = 1.0 + 2 * (N + 4) * U
            for x in range(L):
                outm[o, x] = acm[o, x]
                outr[o, x] = (acr[o, x] + c * acs[o, x]) * F


@numba.njit(**_JIT)
def _acc_ball(acm, acr, acs, acn, xm, xr, xf, sign, L):  # pragma: no cover - compiled
    """``+= sign x`` (``sign`` is +-1: exact)."""
    for o in range(xf.shape[0]):
        if xf[o]:
            _open(acm, acr, acs, acn, o, L)
            acn[o] += 1
            for x in range(L):
                acm[o, x] += sign * xm[o, x]
                acr[o, x] += xr[o, x]
                acs[o, x] += abs(xm[o, x])


@numba.njit(**_JIT)
def _acc_matvec(
    acm, acr, acs, acn, acx, Mm, Mr, Mf, xm, xr, xf, ptr, tj, to, transpose
):  # pragma: no cover - compiled
    """``+= M x`` (``M^T x`` if ``transpose``), ``M`` (K, 9) row-major 3x3, ``x`` (K, 3)."""
    for i in range(Mf.shape[0]):
        if not Mf[i]:
            continue
        for e in range(ptr[i], ptr[i + 1]):
            j = tj[e]
            if not xf[j]:
                continue
            o = to[e]
            _open(acm, acr, acs, acn, o, 3)
            acn[o] += 3
            acx[o] = True
            for r in range(3):
                m = 0.0
                rr = 0.0
                s = 0.0
                for k in range(3):
                    if transpose:
                        a = Mm[i, 3 * k + r]
                        ar = Mr[i, 3 * k + r]
                    else:
                        a = Mm[i, 3 * r + k]
                        ar = Mr[i, 3 * r + k]
                    b = xm[j, k]
                    br = xr[j, k]
                    t = a * b
                    m += t
                    s += abs(t)
                    rr += abs(a) * br + ar * (abs(b) + br)
                acm[o, r] += m
                acr[o, r] += rr
                acs[o, r] += s


@numba.njit(**_JIT)
def _acc_cross(
    acm, acr, acs, acn, acx, am, ar, af, bm, br, bf, sign, ptr, tj, to
):  # pragma: no cover - compiled
    """``+= sign (a x b)`` of 3-vectors (K, 3)."""
    for i in range(af.shape[0]):
        if not af[i]:
            continue
        for e in range(ptr[i], ptr[i + 1]):
            j = tj[e]
            if not bf[j]:
                continue
            o = to[e]
            _open(acm, acr, acs, acn, o, 3)
            acn[o] += 2
            acx[o] = True
            for x in range(3):
                y = (x + 1) % 3
                z = (x + 2) % 3
                t1 = am[i, y] * bm[j, z]
                t2 = am[i, z] * bm[j, y]
                acm[o, x] += sign * (t1 - t2)
                acs[o, x] += abs(t1) + abs(t2)
                acr[o, x] += (
                    abs(am[i, y]) * br[j, z] + ar[i, y] * (abs(bm[j, z]) + br[j, z])
                    + abs(am[i, z]) * br[j, y] + ar[i, z] * (abs(bm[j, y]) + br[j, y])
                )  # fmt: skip


@numba.njit(**_JIT)
def _acc_constant_scalar(acm, acr, acs, acn, acx, c, sm, sr, sf, L):  # pragma: no cover
    """``+= c s``: an exact constant ``c`` (L,) times a scalar ``s`` (K,) of the algebra."""
    exact = True
    for x in range(L):
        if c[x] != 0.0 and c[x] != 1.0 and c[x] != -1.0:
            exact = False
    for o in range(sf.shape[0]):
        if not sf[o]:
            continue
        _open(acm, acr, acs, acn, o, L)
        acn[o] += 1
        if not exact:
            acx[o] = True
        for x in range(L):
            t = c[x] * sm[o]
            acm[o, x] += t
            acr[o, x] += abs(c[x]) * sr[o]
            acs[o, x] += abs(t)


@numba.njit(**_JIT)
def _acc_matmat(
    acm, acr, acs, acn, acx, Am, Ar, Af, Bm, Br, Bf, columns, ptr, tj, to
):  # pragma: no cover - compiled
    """``+= A B``: ``A`` (K, 9) row-major 3x3, ``B`` (K, 3 columns) row-major 3 x columns."""
    for i in range(Af.shape[0]):
        if not Af[i]:
            continue
        for e in range(ptr[i], ptr[i + 1]):
            j = tj[e]
            if not Bf[j]:
                continue
            o = to[e]
            _open(acm, acr, acs, acn, o, 3 * columns)
            acn[o] += 3
            acx[o] = True
            for r in range(3):
                for col in range(columns):
                    m = 0.0
                    rr = 0.0
                    s = 0.0
                    for k in range(3):
                        a = Am[i, 3 * r + k]
                        ra = Ar[i, 3 * r + k]
                        b = Bm[j, columns * k + col]
                        rb = Br[j, columns * k + col]
                        t = a * b
                        m += t
                        s += abs(t)
                        rr += abs(a) * rb + ra * (abs(b) + rb)
                    acm[o, columns * r + col] += m
                    acr[o, columns * r + col] += rr
                    acs[o, columns * r + col] += s


@numba.njit(**_JIT)
def _skew(xm, xr, xf, Sm, Sr, Sf):  # pragma: no cover - compiled
    """``S(x)`` (K, 9) of 3-vectors (K, 3) (exact)."""
    for o in range(xf.shape[0]):
        Sf[o] = xf[o]
        if not xf[o]:
            continue
        a, b, c = xm[o, 0], xm[o, 1], xm[o, 2]
        Sm[o, 0], Sm[o, 1], Sm[o, 2] = 0.0, -c, b
        Sm[o, 3], Sm[o, 4], Sm[o, 5] = c, 0.0, -a
        Sm[o, 6], Sm[o, 7], Sm[o, 8] = -b, a, 0.0
        a, b, c = xr[o, 0], xr[o, 1], xr[o, 2]
        Sr[o, 0], Sr[o, 1], Sr[o, 2] = 0.0, c, b
        Sr[o, 3], Sr[o, 4], Sr[o, 5] = c, 0.0, a
        Sr[o, 6], Sr[o, 7], Sr[o, 8] = b, a, 0.0


# Columns of iota = (xx, xy, yy, xz, yz, zz) in each row of L(x): (I x)_0 = xx x0 + xy x1 + xz x2...
_L_ROW0 = np.array([0, 1, 3])
_L_ROW1 = np.array([1, 2, 4])
_L_ROW2 = np.array([3, 4, 5])


@numba.njit(**_JIT)
def _inertia_map(xm, xr, xf, Lm, Lr, Lf):  # pragma: no cover - compiled
    """``L(x)`` (K, 18), row-major 3x6, with ``I x = L(x) iota``, ``iota = (xx, xy, yy, xz, yz,
    zz)`` (exact)."""
    for o in range(xf.shape[0]):
        Lf[o] = xf[o]
        if not xf[o]:
            continue
        for x in range(18):
            Lm[o, x] = 0.0
            Lr[o, x] = 0.0
        for x in range(3):
            Lm[o, _L_ROW0[x]] = xm[o, x]
            Lm[o, 6 + _L_ROW1[x]] = xm[o, x]
            Lm[o, 12 + _L_ROW2[x]] = xm[o, x]
            Lr[o, _L_ROW0[x]] = xr[o, x]
            Lr[o, 6 + _L_ROW1[x]] = xr[o, x]
            Lr[o, 12 + _L_ROW2[x]] = xr[o, x]


# ============================================================================ the recursion
@numba.njit(**_JIT)
def _recursion(
    parent, revolute, axis, parts, translation, direction, gravity,
    ptr, tj, to,
    qm, qr, vm, vr, am, ar, gscale,
    kind, unit, sign, pim, pir, shared, own_lo, own_hi, sub_lo, sub_hi, polarize,
    outm, outr,
):  # fmt: skip  # pragma: no cover - compiled
    """Joint torques ``outm, outr[b, c, i, o, p]`` of each batch element ``b`` (positions ``q``
    (B, n, K)), column ``c`` (velocities, accelerations (B, C, n, K), gravity scale (C,)) and
    parameter row ``p`` (``pim, pir`` (P, 10 n); per body ``kind`` 0: zero, 1: ``sign`` times
    the unit vector ``unit``, 2: general), component ``o`` of the algebra. Rows ``:shared``
    may be non-zero on any body; the others on one body each, body ``j``'s rows being
    ``own_lo[j]:own_hi[j]`` and those of its subtree within ``sub_lo[j]:sub_hi[j]``. With
    ``polarize``, column ``c`` of the output is ``(c - (c + C / 2)) / 4`` (ball difference, then
    an exact scaling). ``out*`` must be zero on entry: structurally zero entries are not
    written."""
    B, n, K = qm.shape
    C = vm.shape[1]
    P = kind.shape[0]
    half_columns = C // 2
    # Scratch, reused over the batch.
    acm = np.empty((K, 60))
    acr = np.empty((K, 60))
    acs = np.empty((K, 60))
    acn = np.zeros(K, np.int64)
    acx = np.zeros(K, np.bool_)
    Rm = np.zeros((n, K, 9))
    Rr = np.zeros((n, K, 9))
    Rf = np.zeros((n, K), np.bool_)
    pm = np.zeros((n, K, 3))
    pr = np.zeros((n, K, 3))
    pf = np.zeros((n, K), np.bool_)
    cm = np.zeros(K)  # cos, sin, q and d^2 of one joint
    cr = np.zeros(K)
    cf = np.zeros(K, np.bool_)
    sm = np.zeros(K)
    sr = np.zeros(K)
    sf = np.zeros(K, np.bool_)
    xm = np.zeros(K)
    xr = np.zeros(K)
    xf = np.zeros(K, np.bool_)
    dm = np.zeros((K, 1))
    dr = np.zeros((K, 1))
    df = np.zeros(K, np.bool_)
    # Per joint: vw, vl, aw, al (K, 3) and their flags.
    Vm = np.zeros((n, 4, K, 3))
    Vr = np.zeros((n, 4, K, 3))
    Vf = np.zeros((n, 4, K), np.bool_)
    zero3m = np.zeros((K, 3))
    zero3r = np.zeros((K, 3))
    zero3f = np.zeros(K, np.bool_)
    gm = np.zeros((K, 3))
    gr = np.zeros((K, 3))
    gf = np.zeros(K, np.bool_)
    tm = np.zeros((K, 3))  # temporaries
    tr = np.zeros((K, 3))
    tf = np.zeros(K, np.bool_)
    om = np.zeros((K, 3))  # own velocity S qd
    orr = np.zeros((K, 3))
    of = np.zeros(K, np.bool_)
    Swm = np.zeros((K, 9))
    Swr = np.zeros((K, 9))
    Swf = np.zeros(K, np.bool_)
    Sam = np.zeros((K, 9))
    Sar = np.zeros((K, 9))
    Saf = np.zeros(K, np.bool_)
    Lwm = np.zeros((K, 18))
    Lwr = np.zeros((K, 18))
    Lwf = np.zeros(K, np.bool_)
    hm = np.zeros((K, 9))  # a 3x3 result
    hr = np.zeros((K, 9))
    hf = np.zeros(K, np.bool_)
    im = np.zeros((K, 18))  # a 3x6 result
    ir = np.zeros((K, 18))
    if_ = np.zeros(K, np.bool_)
    # The body regressor (K, 10 parameters x 6: linear then angular) and its flags.
    Phm = np.zeros((K, 60))
    Phr = np.zeros((K, 60))
    Phf = np.zeros(K, np.bool_)
    # Forces (linear, angular) per joint, component and parameter row (rows innermost), flagged
    # per joint and component (a flagged block's rows outside the joint's rows stay zero).
    Fm = np.zeros((n, K, 6, P))
    Fr = np.zeros((n, K, 6, P))
    Ff = np.zeros((n, K), np.bool_)
    vacm = np.zeros((K, 3, P))
    vacr = np.zeros((K, 3, P))
    vacs = np.zeros((K, 3, P))
    fum = np.zeros((K, 3, P))
    fur = np.zeros((K, 3, P))
    fuf = np.zeros(K, np.bool_)
    num = np.zeros((K, 3, P))
    nur = np.zeros((K, 3, P))
    nuf = np.zeros(K, np.bool_)
    # A joint axis that is +-1 along one coordinate makes S^T f a copy of that coordinate.
    axis_unit = np.full(n, -1, np.int64)
    axis_sign = np.ones(n)
    for j in range(n):
        count = 0
        for x in range(3):
            if axis[j, x] != 0.0:
                count += 1
        for x in range(3):
            if count == 1 and abs(axis[j, x]) == 1.0:
                axis_unit[j] = x
                axis_sign[j] = axis[j, x]
    half = 0.5
    for b in range(B):
        # ---------------------------------------------------------------- poses
        for j in range(n):
            for o in range(K):
                xm[o] = qm[b, j, o]
                xr[o] = qr[b, j, o]
                xf[o] = xm[o] != 0.0 or xr[o] != 0.0
            if revolute[j]:
                x0 = xm[0]
                r0 = xr[0]
                c0 = math.cos(x0)
                s0 = math.sin(x0)
                reach = min(2.0, 0.5 * r0 * r0 * UP)
                cm[0] = c0
                cr[0] = min(2.0, (abs(s0) * r0 + reach) * UP) + 4 * U
                sm[0] = s0
                sr[0] = min(2.0, (abs(c0) * r0 + reach) * UP) + 4 * U
                cf[0] = True
                sf[0] = True
                # d^2: the products of the derivative components (i, j >= 1).
                _begin(acn, acx)
                for i in range(1, K):
                    if not xf[i]:
                        continue
                    for e in range(ptr[i], ptr[i + 1]):
                        k = tj[e]
                        if k == 0 or not xf[k]:
                            continue
                        o = to[e]
                        _open(acm, acr, acs, acn, o, 1)
                        acn[o] += 1
                        acx[o] = True
                        t = xm[i] * xm[k]
                        acm[o, 0] += t
                        acs[o, 0] += abs(t)
                        acr[o, 0] += abs(xm[i]) * xr[k] + xr[i] * (abs(xm[k]) + xr[k])
                _finish(acm, acr, acs, acn, acx, 1, dm, dr, df)
                # cos_o = -(sin0 x_o) - (cos0 / 2) d2_o, sin_o = cos0 x_o - (sin0 / 2) d2_o.
                for which in range(2):
                    _begin(acn, acx)
                    for o in range(1, K):
                        if not (xf[o] or df[o]):
                            continue
                        _open(acm, acr, acs, acn, o, 1)
                        if xf[o]:
                            fm = -sm[0] if which == 0 else cm[0]
                            fr = sr[0] if which == 0 else cr[0]
                            t = fm * xm[o]
                            acm[o, 0] += t
                            acs[o, 0] += abs(t)
                            acr[o, 0] += abs(fm) * xr[o] + fr * (abs(xm[o]) + xr[o])
                            acn[o] += 1
                            acx[o] = True
                        if df[o]:
                            fm = -half * cm[0] if which == 0 else -half * sm[0]
                            fr = half * (cr[0] if which == 0 else sr[0])
                            t = fm * dm[o, 0]
                            acm[o, 0] += t
                            acs[o, 0] += abs(t)
                            acr[o, 0] += abs(fm) * dr[o, 0] + fr * (abs(dm[o, 0]) + dr[o, 0])
                            acn[o] += 1
                            acx[o] = True
                    for o in range(1, K):
                        N = acn[o]
                        if which == 0:
                            cf[o] = N > 0
                        else:
                            sf[o] = N > 0
                        if N > 0:
                            value = acm[o, 0]
                            radius = (acr[o, 0] + (N + 2) * U * acs[o, 0]) * (1.0 + 2 * (N + 4) * U)
                            if which == 0:
                                cm[o], cr[o] = value, radius
                            else:
                                sm[o], sr[o] = value, radius
                # R = A0 + cos A1 + sin A2.
                for o in range(K):
                    Rf[j, o] = cf[o] or sf[o] or o == 0
                    if not Rf[j, o]:
                        continue
                    N = (1 if o == 0 else 0) + (1 if cf[o] else 0) + (1 if sf[o] else 0)
                    for x in range(9):
                        m = parts[j, 0, x] if o == 0 else 0.0
                        s = abs(m)
                        rr = 0.0
                        if cf[o]:
                            t = cm[o] * parts[j, 1, x]
                            m += t
                            s += abs(t)
                            rr += cr[o] * abs(parts[j, 1, x])
                        if sf[o]:
                            t = sm[o] * parts[j, 2, x]
                            m += t
                            s += abs(t)
                            rr += sr[o] * abs(parts[j, 2, x])
                        Rm[j, o, x] = m
                        Rr[j, o, x] = (rr + (N + 2) * U * s) * (1.0 + 2 * (N + 4) * U)
                for o in range(K):
                    pf[j, o] = o == 0
                for x in range(3):
                    pm[j, 0, x] = translation[j, x]
                    pr[j, 0, x] = 0.0
            else:
                for o in range(K):
                    Rf[j, o] = o == 0
                for x in range(9):
                    Rm[j, 0, x] = parts[j, 0, x]
                    Rr[j, 0, x] = 0.0
                # p = translation + direction q.
                _begin(acn, acx)
                acm[0, :3] = translation[j]
                acr[0, :3] = 0.0
                acs[0, :3] = np.abs(translation[j])
                acn[0] = 1
                _acc_constant_scalar(acm, acr, acs, acn, acx, direction[j], xm, xr, xf, 3)
                _finish(acm, acr, acs, acn, acx, 3, pm[j], pr[j], pf[j])
        # ---------------------------------------------------------------- columns
        for c in range(C):
            for o in range(K):
                gf[o] = False
            if gscale[c] != 0.0:
                gf[0] = True
                for x in range(3):
                    gm[0, x] = -gscale[c] * gravity[x]
                    gr[0, x] = 0.0
            for j in range(n):
                for o in range(K):
                    Ff[j, o] = False
            for j in range(n):
                par = parent[j]
                if par < 0:
                    vwm, vwr, vwf = zero3m, zero3r, zero3f
                    vlm, vlr, vlf = zero3m, zero3r, zero3f
                    awm, awr, awf = zero3m, zero3r, zero3f
                    alm, alr, alf = gm, gr, gf
                else:
                    vwm, vwr, vwf = Vm[par, 0], Vr[par, 0], Vf[par, 0]
                    vlm, vlr, vlf = Vm[par, 1], Vr[par, 1], Vf[par, 1]
                    awm, awr, awf = Vm[par, 2], Vr[par, 2], Vf[par, 2]
                    alm, alr, alf = Vm[par, 3], Vr[par, 3], Vf[par, 3]
                # own = axis qd_j, and the joint's acceleration as a scalar of the algebra.
                for o in range(K):
                    xm[o] = vm[b, c, j, o]
                    xr[o] = vr[b, c, j, o]
                    xf[o] = xm[o] != 0.0 or xr[o] != 0.0
                _begin(acn, acx)
                _acc_constant_scalar(acm, acr, acs, acn, acx, axis[j], xm, xr, xf, 3)
                _finish(acm, acr, acs, acn, acx, 3, om, orr, of)
                for o in range(K):
                    xm[o] = am[b, c, j, o]
                    xr[o] = ar[b, c, j, o]
                    xf[o] = xm[o] != 0.0 or xr[o] != 0.0
                # vw' = R^T vw (+ own); vl' = R^T (vl - p x vw) (+ own).
                _begin(acn, acx)
                _acc_matvec(acm, acr, acs, acn, acx, Rm[j], Rr[j], Rf[j], vwm, vwr, vwf,
                            ptr, tj, to, True)  # fmt: skip
                if revolute[j]:
                    _acc_ball(acm, acr, acs, acn, om, orr, of, 1.0, 3)
                _finish(acm, acr, acs, acn, acx, 3, Vm[j, 0], Vr[j, 0], Vf[j, 0])
                _begin(acn, acx)
                _acc_ball(acm, acr, acs, acn, vlm, vlr, vlf, 1.0, 3)
                _acc_cross(acm, acr, acs, acn, acx, pm[j], pr[j], pf[j], vwm, vwr, vwf, -1.0,
                           ptr, tj, to)  # fmt: skip
                _finish(acm, acr, acs, acn, acx, 3, tm, tr, tf)
                _begin(acn, acx)
                _acc_matvec(acm, acr, acs, acn, acx, Rm[j], Rr[j], Rf[j], tm, tr, tf,
                            ptr, tj, to, True)  # fmt: skip
                if not revolute[j]:
                    _acc_ball(acm, acr, acs, acn, om, orr, of, 1.0, 3)
                _finish(acm, acr, acs, acn, acx, 3, Vm[j, 1], Vr[j, 1], Vf[j, 1])
                # aw' = R^T aw (+ axis qdd + vw' x own); al' = R^T (al - p x aw) + vl' x own
                # (revolute) or + axis qdd + vw' x own (prismatic).
                _begin(acn, acx)
                _acc_matvec(acm, acr, acs, acn, acx, Rm[j], Rr[j], Rf[j], awm, awr, awf,
                            ptr, tj, to, True)  # fmt: skip
                if revolute[j]:
                    _acc_constant_scalar(acm, acr, acs, acn, acx, axis[j], xm, xr, xf, 3)
                    _acc_cross(acm, acr, acs, acn, acx, Vm[j, 0], Vr[j, 0], Vf[j, 0],
                               om, orr, of, 1.0, ptr, tj, to)  # fmt: skip
                _finish(acm, acr, acs, acn, acx, 3, Vm[j, 2], Vr[j, 2], Vf[j, 2])
                _begin(acn, acx)
                _acc_ball(acm, acr, acs, acn, alm, alr, alf, 1.0, 3)
                _acc_cross(acm, acr, acs, acn, acx, pm[j], pr[j], pf[j], awm, awr, awf, -1.0,
                           ptr, tj, to)  # fmt: skip
                _finish(acm, acr, acs, acn, acx, 3, tm, tr, tf)
                _begin(acn, acx)
                _acc_matvec(acm, acr, acs, acn, acx, Rm[j], Rr[j], Rf[j], tm, tr, tf,
                            ptr, tj, to, True)  # fmt: skip
                if revolute[j]:
                    _acc_cross(acm, acr, acs, acn, acx, Vm[j, 1], Vr[j, 1], Vf[j, 1],
                               om, orr, of, 1.0, ptr, tj, to)  # fmt: skip
                else:
                    _acc_constant_scalar(acm, acr, acs, acn, acx, axis[j], xm, xr, xf, 3)
                    _acc_cross(acm, acr, acs, acn, acx, Vm[j, 0], Vr[j, 0], Vf[j, 0],
                               om, orr, of, 1.0, ptr, tj, to)  # fmt: skip
                _finish(acm, acr, acs, acn, acx, 3, Vm[j, 3], Vr[j, 3], Vf[j, 3])
                # ------------------------------------------------ the body regressor
                wm, wr, wf = Vm[j, 0], Vr[j, 0], Vf[j, 0]
                lm, lr, lf = Vm[j, 1], Vr[j, 1], Vf[j, 1]
                awm, awr, awf = Vm[j, 2], Vr[j, 2], Vf[j, 2]
                alm, alr, alf = Vm[j, 3], Vr[j, 3], Vf[j, 3]
                for o in range(K):
                    Phf[o] = False
                # Row m, linear: al + w x vl.
                _begin(acn, acx)
                _acc_ball(acm, acr, acs, acn, alm, alr, alf, 1.0, 3)
                _acc_cross(acm, acr, acs, acn, acx, wm, wr, wf, lm, lr, lf, 1.0, ptr, tj, to)
                _finish(acm, acr, acs, acn, acx, 3, tm, tr, tf)
                for o in range(K):
                    if tf[o]:
                        _phi_open(Phm, Phr, Phf, o)
                        for x in range(3):
                            Phm[o, x] = tm[o, x]
                            Phr[o, x] = tr[o, x]
                # Rows h, linear: S(aw) + S(w) S(w), entry (x, c) -> row 1 + c, column x.
                _skew(wm, wr, wf, Swm, Swr, Swf)
                _skew(awm, awr, awf, Sam, Sar, Saf)
                _begin(acn, acx)
                _acc_ball(acm, acr, acs, acn, Sam, Sar, Saf, 1.0, 9)
                _acc_matmat(acm, acr, acs, acn, acx, Swm, Swr, Swf, Swm, Swr, Swf, 3,
                            ptr, tj, to)  # fmt: skip
                _finish(acm, acr, acs, acn, acx, 9, hm, hr, hf)
                for o in range(K):
                    if hf[o]:
                        _phi_open(Phm, Phr, Phf, o)
                        for x in range(3):
                            for col in range(3):
                                Phm[o, 6 * (1 + col) + x] = hm[o, 3 * x + col]
                                Phr[o, 6 * (1 + col) + x] = hr[o, 3 * x + col]
                # Rows h, angular: -S(al - vl x w).
                _begin(acn, acx)
                _acc_ball(acm, acr, acs, acn, alm, alr, alf, 1.0, 3)
                _acc_cross(acm, acr, acs, acn, acx, lm, lr, lf, wm, wr, wf, -1.0, ptr, tj, to)
                _finish(acm, acr, acs, acn, acx, 3, tm, tr, tf)
                _skew(tm, tr, tf, hm, hr, hf)
                for o in range(K):
                    if hf[o]:
                        _phi_open(Phm, Phr, Phf, o)
                        for x in range(3):
                            for col in range(3):
                                Phm[o, 6 * (1 + col) + 3 + x] = -hm[o, 3 * x + col]
                                Phr[o, 6 * (1 + col) + 3 + x] = hr[o, 3 * x + col]
                # Rows iota, angular: L(aw) + S(w) L(w).
                _inertia_map(awm, awr, awf, Lwm, Lwr, Lwf)
                _begin(acn, acx)
                _acc_ball(acm, acr, acs, acn, Lwm, Lwr, Lwf, 1.0, 18)
                _inertia_map(wm, wr, wf, Lwm, Lwr, Lwf)
                _acc_matmat(acm, acr, acs, acn, acx, Swm, Swr, Swf, Lwm, Lwr, Lwf, 6,
                            ptr, tj, to)  # fmt: skip
                _finish(acm, acr, acs, acn, acx, 18, im, ir, if_)
                for o in range(K):
                    if if_[o]:
                        _phi_open(Phm, Phr, Phf, o)
                        for x in range(3):
                            for col in range(6):
                                Phm[o, 6 * (4 + col) + 3 + x] = im[o, 6 * x + col]
                                Phr[o, 6 * (4 + col) + 3 + x] = ir[o, 6 * x + col]
                # ------------------------------------------------ body forces per row
                for o in range(K):
                    if not Phf[o] or (shared == 0 and own_lo[j] == own_hi[j]):
                        continue
                    _open_block(Fm, Fr, Ff, j, o, P)
                    _body_rows(Phm, Phr, o, j, 0, shared, kind, unit, sign, pim, pir, Fm, Fr)
                    _body_rows(
                        Phm, Phr, o, j, own_lo[j], own_hi[j], kind, unit, sign, pim, pir, Fm, Fr
                    )
            # ---------------------------------------------------------------- backward
            minus = polarize and c >= half_columns
            column = c - half_columns if minus else c
            for j in range(n - 1, -1, -1):
                flagged = False
                for o in range(K):
                    if Ff[j, o]:
                        flagged = True
                if not flagged:
                    continue
                par = parent[j]
                offset = 3 if revolute[j] else 0
                lo, hi = sub_lo[j], sub_hi[j]
                # tau_j = S^T f.
                for o in range(K):
                    if Ff[j, o]:
                        _torques(Fm[j, o], Fr[j, o], offset, axis_unit[j], axis_sign[j], axis[j],
                                 shared, lo, hi, outm[b, column, j, o], outr[b, column, j, o],
                                 minus)  # fmt: skip
                if par < 0:
                    continue
                # f' = R f, n' = R n + p x f', added to the parent's.
                if K == 1:  # balls: one fused loop over the rows, same arithmetic
                    _open_block(Fm, Fr, Ff, par, 0, P)
                    _carry_rows(Rm[j, 0], Rr[j, 0], pm[j, 0], pr[j, 0], Fm[j, 0], Fr[j, 0],
                                Fm[par, 0], Fr[par, 0], shared, lo, hi)  # fmt: skip
                    continue
                _begin(acn, acx)
                _rows_matvec(vacm, vacr, vacs, acn, acx, Rm[j], Rr[j], Rf[j], Fm[j], Fr[j],
                             Ff[j], 0, shared, lo, hi, ptr, tj, to)  # fmt: skip
                _rows_finish(vacm, vacr, vacs, acn, acx, shared, lo, hi, fum, fur, fuf)
                _begin(acn, acx)
                _rows_matvec(vacm, vacr, vacs, acn, acx, Rm[j], Rr[j], Rf[j], Fm[j], Fr[j],
                             Ff[j], 3, shared, lo, hi, ptr, tj, to)  # fmt: skip
                _rows_cross(vacm, vacr, vacs, acn, acx, pm[j], pr[j], pf[j], fum, fur, fuf,
                            shared, lo, hi, ptr, tj, to)  # fmt: skip
                _rows_finish(vacm, vacr, vacs, acn, acx, shared, lo, hi, num, nur, nuf)
                for o in range(K):
                    for which in range(2):
                        if which == 0 and not fuf[o] or which == 1 and not nuf[o]:
                            continue
                        _open_block(Fm, Fr, Ff, par, o, P)
                        if which == 0:
                            _add_rows(Fm, Fr, par, o, 0, fum, fur, shared, lo, hi)
                        else:
                            _add_rows(Fm, Fr, par, o, 3, num, nur, shared, lo, hi)
        if polarize:
            for column in range(half_columns):
                for j in range(n):
                    for o in range(K):
                        for p in range(P):
                            outm[b, column, j, o, p] *= 0.25
                            outr[b, column, j, o, p] *= 0.25


@numba.njit(**_JIT)
def _open_block(Fm, Fr, Ff, j, o, P):  # pragma: no cover - compiled
    """Flag the force block of joint ``j``, component ``o``, zero until written."""
    if not Ff[j, o]:
        Ff[j, o] = True
        for x in range(6):
            for p in range(P):
                Fm[j, o, x, p] = 0.0
                Fr[j, o, x, p] = 0.0


@numba.njit(**_JIT)
def _body_rows(Phm, Phr, o, j, lo, hi, kind, unit, sign, pim, pir, Fm, Fr):  # pragma: no cover
    """The forces ``pi_p Phi`` of rows ``lo:hi`` on body ``j``, component ``o``."""
    for p in range(lo, hi):
        k = kind[p, j]
        if k == 0:
            continue
        if k == 1:
            t = unit[p, j]
            sgn = sign[p, j]
            for x in range(6):
                Fm[j, o, x, p] = sgn * Phm[o, 6 * t + x]
                Fr[j, o, x, p] = Phr[o, 6 * t + x]
            continue
        for x in range(6):
            # Linear: rows m, h (0-3); angular: rows h, iota (1-9).
            first, last = (0, 4) if x < 3 else (1, 10)
            m = 0.0
            rr = 0.0
            s = 0.0
            N = 0
            for t in range(first, last):
                a = pim[p, 10 * j + t]
                ra = pir[p, 10 * j + t]
                if a == 0.0 and ra == 0.0:
                    continue
                bm = Phm[o, 6 * t + x]
                rb = Phr[o, 6 * t + x]
                v = a * bm
                m += v
                s += abs(v)
                rr += abs(a) * rb + ra * (abs(bm) + rb)
                N += 1
            Fm[j, o, x, p] = m
            Fr[j, o, x, p] = (rr + (N + 2) * U * s) * (1.0 + 2 * (N + 4) * U)


@numba.njit(**_JIT)
def _add_rows(Fm, Fr, j, o, offset, um, ur, shared, lo, hi):  # pragma: no cover - compiled
    """``F[j, o, offset:offset + 3] += u[o]`` over the rows, as ball sums (``2u |mid|``,
    ``1 + 8u``); exact (a copy) where either is zero (selects, not branches)."""
    for x in range(3):
        for part in range(2):
            first = 0 if part == 0 else lo
            last = shared if part == 0 else hi
            for p in range(first, last):
                m = um[o, x, p]
                r = ur[o, x, p]
                dm = Fm[j, o, offset + x, p]
                dr = Fr[j, o, offset + x, p]
                total = dm + m
                summed = (dr + r + 2 * U * abs(total)) * UP
                radius = r if dm == 0.0 and dr == 0.0 else summed
                Fr[j, o, offset + x, p] = dr if m == 0.0 and r == 0.0 else radius
                Fm[j, o, offset + x, p] = total


@numba.njit(**_JIT)
def _carry_rows(Rm, Rr, pm, pr, fm, fr, dm, dr, shared, lo, hi):  # pragma: no cover - compiled
    """For balls (one component), row by row: ``f' = R f``, ``n' = R n + p x f'`` (the sums
    of :func:`_rows_matvec`, :func:`_rows_cross` and :func:`_rows_finish`, in the same order)
    added to the parent's force ``d`` (6, P) as :func:`_add_rows` does."""
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = (
        Rm[0],
        Rm[1],
        Rm[2],
        Rm[3],
        Rm[4],
        Rm[5],
        Rm[6],
        Rm[7],
        Rm[8],
    )
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = (
        Rr[0],
        Rr[1],
        Rr[2],
        Rr[3],
        Rr[4],
        Rr[5],
        Rr[6],
        Rr[7],
        Rr[8],
    )
    p0, p1, p2 = pm[0], pm[1], pm[2]
    q0, q1, q2 = pr[0], pr[1], pr[2]
    c3, F3 = 5 * U, 1.0 + 14 * U
    c5, F5 = 7 * U, 1.0 + 18 * U
    for part in range(2):
        first = 0 if part == 0 else lo
        last = shared if part == 0 else hi
        for p in range(first, last):
            x0, x1, x2 = fm[0, p], fm[1, p], fm[2, p]
            y0, y1, y2 = fr[0, p], fr[1, p], fr[2, p]
            # f' = R f.
            u0, v0, w0 = _dot3(a00, a01, a02, r00, r01, r02, x0, x1, x2, y0, y1, y2)
            u1, v1, w1 = _dot3(a10, a11, a12, r10, r11, r12, x0, x1, x2, y0, y1, y2)
            u2, v2, w2 = _dot3(a20, a21, a22, r20, r21, r22, x0, x1, x2, y0, y1, y2)
            g0 = (w0 + c3 * v0) * F3
            g1 = (w1 + c3 * v1) * F3
            g2 = (w2 + c3 * v2) * F3
            # n' = R n + p x f'.
            x0, x1, x2 = fm[3, p], fm[4, p], fm[5, p]
            y0, y1, y2 = fr[3, p], fr[4, p], fr[5, p]
            m0, s0, e0 = _dot3(a00, a01, a02, r00, r01, r02, x0, x1, x2, y0, y1, y2)
            m1, s1, e1 = _dot3(a10, a11, a12, r10, r11, r12, x0, x1, x2, y0, y1, y2)
            m2, s2, e2 = _dot3(a20, a21, a22, r20, r21, r22, x0, x1, x2, y0, y1, y2)
            m0, s0, e0 = _cross_term(m0, s0, e0, p1, p2, q1, q2, u2, u1, g2, g1)
            m1, s1, e1 = _cross_term(m1, s1, e1, p2, p0, q2, q0, u0, u2, g0, g2)
            m2, s2, e2 = _cross_term(m2, s2, e2, p0, p1, q0, q1, u1, u0, g1, g0)
            _add_one(dm, dr, 0, p, u0, g0)
            _add_one(dm, dr, 1, p, u1, g1)
            _add_one(dm, dr, 2, p, u2, g2)
            _add_one(dm, dr, 3, p, m0, (e0 + c5 * s0) * F5)
            _add_one(dm, dr, 4, p, m1, (e1 + c5 * s1) * F5)
            _add_one(dm, dr, 5, p, m2, (e2 + c5 * s2) * F5)


@numba.njit(**_JIT, inline="always")
def _dot3(a0, a1, a2, r0, r1, r2, x0, x1, x2, y0, y1, y2):  # pragma: no cover - compiled
    """A row of a ball matrix times a ball 3-vector: the sums of the midpoint products, of
    their magnitudes and of their radii (as in :func:`_rows_matvec`)."""
    t0 = a0 * x0
    t1 = a1 * x1
    t2 = a2 * x2
    m = t0 + t1 + t2
    s = abs(t0) + abs(t1) + abs(t2)
    e = (
        abs(a0) * y0 + r0 * (abs(x0) + y0)
        + abs(a1) * y1 + r1 * (abs(x1) + y1)
        + abs(a2) * y2 + r2 * (abs(x2) + y2)
    )  # fmt: skip
    return m, s, e


@numba.njit(**_JIT, inline="always")
def _cross_term(m, s, e, py, pz, ry, rz, fz, fy, gz, gy):  # pragma: no cover - compiled
    """``+ (p_y f_z - p_z f_y)`` added to the sums (as in :func:`_rows_cross`)."""
    t1 = py * fz
    t2 = pz * fy
    return (
        m + (t1 - t2),
        s + (abs(t1) + abs(t2)),
        e + (abs(py) * gz + ry * (abs(fz) + gz) + abs(pz) * gy + rz * (abs(fy) + gy)),
    )


@numba.njit(**_JIT, inline="always")
def _add_one(dm, dr, x, p, m, r):  # pragma: no cover - compiled
    """``d[x, p] += (m, r)`` as :func:`_add_rows` does."""
    em = dm[x, p]
    er = dr[x, p]
    total = em + m
    summed = (er + r + 2 * U * abs(total)) * UP
    radius = r if em == 0.0 and er == 0.0 else summed
    dr[x, p] = er if m == 0.0 and r == 0.0 else radius
    dm[x, p] = total


@numba.njit(**_JIT)
def _torques(
    fm, fr, offset, unit, sign, axis, shared, lo, hi, outm, outr, minus
):  # pragma: no cover
    """``S^T f`` of the rows of a joint's force (6, P) into ``out`` (P,): written, or
    (``minus``) subtracted from the written ones as ball sums (exact where either is zero)."""
    for part in range(2):
        first = 0 if part == 0 else lo
        last = shared if part == 0 else hi
        for p in range(first, last):
            if unit >= 0:
                m = sign * fm[offset + unit, p]
                r = fr[offset + unit, p]
            else:
                m = 0.0
                r = 0.0
                s = 0.0
                for x in range(3):
                    v = axis[x] * fm[offset + x, p]
                    m += v
                    s += abs(v)
                    r += abs(axis[x]) * fr[offset + x, p]
                r = (r + 5 * U * s) * (1.0 + 14 * U)
            if not minus:
                outm[p] = m
                outr[p] = r
            else:
                e = outm[p]
                er = outr[p]
                d = e - m
                summed = (er + r + 2 * U * abs(d)) * UP
                radius = r if e == 0.0 and er == 0.0 else summed
                outr[p] = er if m == 0.0 and r == 0.0 else radius
                outm[p] = d


@numba.njit(**_JIT)
def _rows_open(acm, acr, acs, acn, o, shared, lo, hi):  # pragma: no cover - compiled
    if acn[o] == 0:
        for x in range(3):
            for part in range(2):
                first = 0 if part == 0 else lo
                last = shared if part == 0 else hi
                for p in range(first, last):
                    acm[o, x, p] = 0.0
                    acr[o, x, p] = 0.0
                    acs[o, x, p] = 0.0


@numba.njit(**_JIT)
def _rows_matvec(
    acm, acr, acs, acn, acx, Rm, Rr, Rf, Fm, Fr, Ff, offset, shared, lo, hi, ptr, tj, to
):  # pragma: no cover - compiled
    """``+= R f`` for the rows ``:shared`` and ``lo:hi`` of a joint's forces ``F`` (K, 6, P),
    ``f = F[:, offset:offset + 3]``."""
    for i in range(Rf.shape[0]):
        if not Rf[i]:
            continue
        for e in range(ptr[i], ptr[i + 1]):
            j = tj[e]
            if not Ff[j]:
                continue
            o = to[e]
            _rows_open(acm, acr, acs, acn, o, shared, lo, hi)
            acn[o] += 3
            acx[o] = True
            for r in range(3):
                a0, a1, a2 = Rm[i, 3 * r], Rm[i, 3 * r + 1], Rm[i, 3 * r + 2]
                r0, r1, r2 = Rr[i, 3 * r], Rr[i, 3 * r + 1], Rr[i, 3 * r + 2]
                b0, b1, b2 = abs(a0), abs(a1), abs(a2)
                for part in range(2):
                    first = 0 if part == 0 else lo
                    last = shared if part == 0 else hi
                    for p in range(first, last):
                        x0 = Fm[j, offset, p]
                        x1 = Fm[j, offset + 1, p]
                        x2 = Fm[j, offset + 2, p]
                        y0 = Fr[j, offset, p]
                        y1 = Fr[j, offset + 1, p]
                        y2 = Fr[j, offset + 2, p]
                        t0 = a0 * x0
                        t1 = a1 * x1
                        t2 = a2 * x2
                        acm[o, r, p] += t0 + t1 + t2
                        acs[o, r, p] += abs(t0) + abs(t1) + abs(t2)
                        acr[o, r, p] += (
                            b0 * y0 + r0 * (abs(x0) + y0)
                            + b1 * y1 + r1 * (abs(x1) + y1)
                            + b2 * y2 + r2 * (abs(x2) + y2)
                        )  # fmt: skip


@numba.njit(**_JIT)
def _rows_cross(
    acm, acr, acs, acn, acx, pm, pr, pf, Xm, Xr, Xf, shared, lo, hi, ptr, tj, to
):  # pragma: no cover - compiled
    """``+= p x X`` for a 3-vector ``p`` (K, 3) and the rows of ``X`` (K, 3, P)."""
    for i in range(pf.shape[0]):
        if not pf[i]:
            continue
        for e in range(ptr[i], ptr[i + 1]):
            j = tj[e]
            if not Xf[j]:
                continue
            o = to[e]
            _rows_open(acm, acr, acs, acn, o, shared, lo, hi)
            acn[o] += 2
            acx[o] = True
            for x in range(3):
                y = (x + 1) % 3
                z = (x + 2) % 3
                py, pz, ry, rz = pm[i, y], pm[i, z], pr[i, y], pr[i, z]
                ay, az = abs(py), abs(pz)
                for part in range(2):
                    first = 0 if part == 0 else lo
                    last = shared if part == 0 else hi
                    for p in range(first, last):
                        fz = Xm[j, z, p]
                        fy = Xm[j, y, p]
                        gz = Xr[j, z, p]
                        gy = Xr[j, y, p]
                        t1 = py * fz
                        t2 = pz * fy
                        acm[o, x, p] += t1 - t2
                        acs[o, x, p] += abs(t1) + abs(t2)
                        acr[o, x, p] += (
                            ay * gz + ry * (abs(fz) + gz) + az * gy + rz * (abs(fy) + gy)
                        )


@numba.njit(**_JIT)
def _rows_finish(acm, acr, acs, acn, acx, shared, lo, hi, outm, outr, outf):  # pragma: no cover
    """:func:`_finish` over the rows."""
    for o in range(acn.shape[0]):
        N = acn[o]
        outf[o] = N > 0
        if N == 0:
            continue
        exact = N == 1 and not acx[o]
        c = (N + 2) * U
        F = 1.0 + 2 * (N + 4) * U
        for x in range(3):
            for part in range(2):
                first = 0 if part == 0 else lo
                last = shared if part == 0 else hi
                for p in range(first, last):
                    outm[o, x, p] = acm[o, x, p]
                    if exact:
                        outr[o, x, p] = acr[o, x, p]
                    else:
                        outr[o, x, p] = (acr[o, x, p] + c * acs[o, x, p]) * F


@numba.njit(**_JIT)
def _phi_open(Phm, Phr, Phf, o):  # pragma: no cover - compiled
    """Flag component ``o`` of the body regressor, its entries zero until written."""
    if not Phf[o]:
        Phf[o] = True
        for x in range(60):
            Phm[o, x] = 0.0
            Phr[o, x] = 0.0


# ============================================================================ the entry point
def parameter_rows(mid: np.ndarray, rad: np.ndarray, dof: int):
    """Per parameter row and body: 0 (zero), 1 (``sign`` times the unit vector ``unit``), 2."""
    P = mid.shape[0]
    blocks_m = mid.reshape(P, dof, 10)
    blocks_r = rad.reshape(P, dof, 10)
    nonzero = (blocks_m != 0) | (blocks_r != 0)
    count = nonzero.sum(-1)
    unit = np.argmax(nonzero, axis=-1)
    value = np.take_along_axis(blocks_m, unit[..., None], -1)[..., 0]
    radius = np.take_along_axis(blocks_r, unit[..., None], -1)[..., 0]
    is_unit = (count == 1) & (np.abs(value) == 1.0) & (radius == 0.0)
    kind = np.where(count == 0, 0, np.where(is_unit, 1, 2)).astype(np.int64)
    sign = np.where(is_unit, value, 1.0)
    return kind, unit.astype(np.int64), sign


def recursion(
    chain: Chain,
    algebra: Algebra,
    q: tuple[np.ndarray, np.ndarray],
    v: tuple[np.ndarray, np.ndarray],
    a: tuple[np.ndarray, np.ndarray],
    gravity_scale: np.ndarray,
    parameters: tuple[np.ndarray, np.ndarray],
    polarize: bool = False,
    raw: bool = False,
):
    """Joint torques ``Y(q, v_c, a_c) pi_p`` (gravity ``gravity_scale[c] g``) of each batch
    element ``b``, column ``c`` and parameter row ``p``, in the algebra: ``q`` (mid, rad) of shape
    (B, n, K), ``v`` and ``a`` (B, C, n, K), ``parameters`` (P, 10 n); returns (mid, rad) of
    shape (B, C, P, n, K) (views of the kernel's output when the rows keep their order). With
    ``polarize`` (``C`` even), the ``C / 2`` columns ``(tau_c - tau_{c + C / 2}) / 4``
    instead. ``raw``: the kernel's output (B, C, n, K, P') and the rows it holds, instead."""
    qm, qr = (np.ascontiguousarray(x, dtype=float) for x in q)
    vm, vr = (np.ascontiguousarray(x, dtype=float) for x in v)
    am, ar = (np.ascontiguousarray(x, dtype=float) for x in a)
    B, n, K = qm.shape
    C = vm.shape[1]
    rows, shared, own_lo, own_hi, sub_lo, sub_hi = _row_order(chain, *parameters)
    pim = np.ascontiguousarray(parameters[0][rows], dtype=float)
    pir = np.ascontiguousarray(parameters[1][rows], dtype=float)
    kind, unit, sign = parameter_rows(pim, pir, n)
    columns = C // 2 if polarize else C
    outm = np.zeros((B, columns, n, K, len(rows)))
    outr = np.zeros((B, columns, n, K, len(rows)))
    _recursion(
        chain.parent, chain.revolute, chain.axis, chain.parts, chain.translation,
        chain.direction, chain.gravity, algebra.ptr, algebra.tj, algebra.to,
        qm, qr, vm, vr, am, ar, np.ascontiguousarray(gravity_scale, dtype=float),
        kind, unit, sign, pim, pir, shared, own_lo, own_hi, sub_lo, sub_hi, polarize, outm, outr,
    )  # fmt: skip
    P = parameters[0].shape[0]
    if raw:
        return outm, outr, rows
    if len(rows) == P and np.array_equal(rows, np.arange(P)):
        return np.moveaxis(outm, -1, 2), np.moveaxis(outr, -1, 2)  # views
    mid = np.zeros((B, columns, P, n, K))
    rad = np.zeros((B, columns, P, n, K))
    mid[:, :, rows] = np.moveaxis(outm, -1, 2)
    rad[:, :, rows] = np.moveaxis(outr, -1, 2)
    return mid, rad


def _row_order(chain: Chain, mid: np.ndarray, rad: np.ndarray):
    """The parameter rows in the kernel's order: first those non-zero on several bodies
    (``shared`` of them), then those non-zero on one body, by body (rows zero everywhere
    dropped); per joint the range of its own rows and of its subtree's (Pinocchio's joints are
    in depth-first order: a subtree is a range of joints; otherwise every one-body row)."""
    n = len(chain.parent)
    P = mid.shape[0]
    nonzero = ((mid != 0) | (rad != 0)).reshape(P, n, 10).any(-1)  # (P, n)
    bodies = nonzero.sum(-1)
    several = np.flatnonzero(bodies > 1)
    single = np.flatnonzero(bodies == 1)
    body = np.argmax(nonzero[single], axis=-1) if len(single) else np.zeros(0, dtype=int)
    order = np.argsort(body, kind="stable")
    rows = np.concatenate([several, single[order]]).astype(np.int64)
    counts = np.bincount(body, minlength=n)
    own_lo = (len(several) + np.concatenate([[0], np.cumsum(counts)[:-1]])).astype(np.int64)
    own_hi = (own_lo + counts).astype(np.int64)
    sub_lo, sub_hi = own_lo.copy(), own_hi.copy()
    for j in range(n - 1, -1, -1):
        descendants = [k for k in range(j + 1, n) if _ancestor(chain.parent, j, k)]
        last = max(descendants, default=j)
        if descendants and descendants != list(range(j + 1, last + 1)):
            sub_lo[j], sub_hi[j] = len(several), len(rows)  # not a range: every one-body row
        else:
            sub_hi[j] = own_hi[last]
    return rows, len(several), own_lo, own_hi, sub_lo, sub_hi


def _ancestor(parent: np.ndarray, j: int, k: int) -> bool:
    while k >= 0:
        k = parent[k]
        if k == j:
            return True
    return False


@numba.njit(**_JIT)
def pair_scatter(values, first, second, rows, P):  # pragma: no cover - compiled
    """The symmetric ``(B, n, P, n, n)`` array ``out[b, k, rows[q], r, i] = out[b, i, rows[q],
    r, k] = values[b, c, r, 0, q]`` of the pairs ``c = (first[c], second[c])`` of a kernel's
    output (B, pairs, n, 1, P') (the Christoffel matrices: column ``i`` of ``C(q; e_k)`` is column
    ``k`` of ``C(q; e_i)``), zero on the rows not in ``rows``; written in its own order."""
    B, pairs, n = values.shape[0], values.shape[1], values.shape[2]
    pair = np.zeros((n, n), np.int64)
    for c in range(pairs):
        pair[first[c], second[c]] = c
        pair[second[c], first[c]] = c
    source = np.full(P, -1, np.int64)
    for q in range(rows.shape[0]):
        source[rows[q]] = q
    out = np.empty((B, n, P, n, n))
    for b in range(B):
        for k in range(n):
            for p in range(P):
                q = source[p]
                for r in range(n):
                    for i in range(n):
                        out[b, k, p, r, i] = 0.0 if q < 0 else values[b, pair[k, i], r, 0, q]
    return out
