"""Midpoint-radius ball arithmetic on numpy arrays, and jets (a ball and a ball of its time
derivative), vectorized over batches: the arithmetic of :mod:`urpc.model.regressor_balls`.

Each elementary operation returns the floating-point result of the midpoints and adds to the
radius a bound of its rounding error (``2u |result|`` for a sum or product, ``(k + 2) u`` times the
sum of the magnitudes for a ``k``-term dot product, ``u = 2^-53``); the radius itself is computed
with its terms inflated by ``1 + 8u`` (``1 + 2 (k + 4) u`` for a ``k``-term product, whose
radius is a ``k``-term sum). ``sin``/``cos`` of ``[x - r, x + r]`` are
``cos x +- (|sin x| r + r^2 / 2)`` plus 2 ulps for the library's rounding.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

#: Unit roundoff of IEEE double precision.
U = 2.0**-53
#: Factor that keeps a radius computed in rounded arithmetic above its exact value.
UP = 1.0 + 8 * U


@numba.vectorize(["f8(f8, f8, f8)"], cache=True)
def _sum_radius(a, b, mid):  # pragma: no cover - compiled
    """The radius of a sum or difference of balls of radii ``a``, ``b`` with rounded midpoint
    ``mid``: ``(a + b + 2 u |mid|) (1 + 8 u)``, in one pass (compiled, IEEE arithmetic)."""
    return (a + b + 2 * U * abs(mid)) * UP


# ============================================================================ balls
@dataclass(frozen=True)
class Ball:
    """An array of balls ``[mid - rad, mid + rad]`` (same shapes, ``rad >= 0``)."""

    mid: np.ndarray
    rad: np.ndarray

    @staticmethod
    def point(x) -> Ball:
        x = np.asarray(x, dtype=float)
        return Ball(x, np.zeros_like(x))

    @staticmethod
    def hull(lower, upper) -> Ball:
        """A ball containing ``[lower, upper]`` (widened for the rounding of its midpoint)."""
        lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
        mid = 0.5 * (lower + upper)
        rad = np.maximum(upper - mid, mid - lower) * UP + 2 * U * np.abs(mid)
        return Ball(mid, rad)

    @property
    def lower(self) -> np.ndarray:
        return self.mid - self.rad

    @property
    def upper(self) -> np.ndarray:
        return self.mid + self.rad

    @property
    def magnitude(self) -> np.ndarray:
        """``max |x|`` over the ball (rounded up)."""
        return (np.abs(self.mid) + self.rad) * UP

    def __add__(self, other):
        if isinstance(other, Jet):
            return Jet.of(self) + other
        mid = self.mid + other.mid
        return Ball(mid, _sum_radius(self.rad, other.rad, mid))

    def __sub__(self, other):
        if isinstance(other, Jet):
            return Jet.of(self) - other
        mid = self.mid - other.mid
        return Ball(mid, _sum_radius(self.rad, other.rad, mid))

    def __neg__(self) -> Ball:
        return Ball(-self.mid, self.rad)

    def scaled(self, factor: float) -> Ball:
        """Times an exact scalar."""
        mid = self.mid * factor
        return Ball(mid, (self.rad * abs(factor) + 2 * U * np.abs(mid)) * UP)

    def __mul__(self, other):
        """Elementwise product (broadcasting)."""
        if isinstance(other, Jet):
            return Jet.of(self) * other
        mid = self.mid * other.mid
        rad = (
            np.abs(self.mid) * other.rad
            + self.rad * np.abs(other.mid)
            + self.rad * other.rad
            + 2 * U * np.abs(mid)
        )
        return Ball(mid, rad * UP)

    def __getitem__(self, index) -> Ball:
        return Ball(self.mid[index], self.rad[index])

    def map(self, function) -> Ball:
        """A structural operation (reshape, transpose, broadcast) on both arrays."""
        return Ball(function(self.mid), function(self.rad))

    @property
    def shape(self) -> tuple[int, ...]:
        return self.mid.shape


@dataclass(frozen=True)
class Jet:
    """A ball of values and a ball of their time derivatives (forward-mode differentiation)."""

    val: Ball
    dot: Ball

    @staticmethod
    def of(x) -> Jet:
        if isinstance(x, Jet):
            return x
        return Jet(x, Ball.point(np.zeros_like(x.mid)))

    def __add__(self, other) -> Jet:
        other = Jet.of(other)
        return Jet(self.val + other.val, self.dot + other.dot)

    __radd__ = __add__

    def __sub__(self, other) -> Jet:
        other = Jet.of(other)
        return Jet(self.val - other.val, self.dot - other.dot)

    def __neg__(self) -> Jet:
        return Jet(-self.val, -self.dot)

    def scaled(self, factor: float) -> Jet:
        return Jet(self.val.scaled(factor), self.dot.scaled(factor))

    def __mul__(self, other) -> Jet:
        other = Jet.of(other)
        return Jet(self.val * other.val, self.dot * other.val + self.val * other.dot)

    __rmul__ = __mul__

    def __getitem__(self, index) -> Jet:
        return Jet(self.val[index], self.dot[index])

    def map(self, function) -> Jet:
        return Jet(self.val.map(function), self.dot.map(function))

    @property
    def shape(self) -> tuple[int, ...]:
        return self.val.shape


def matmul(A, B):
    """``A @ B`` on balls or jets (numpy's batched matrix product)."""
    if isinstance(A, Jet) or isinstance(B, Jet):
        A, B = Jet.of(A), Jet.of(B)
        return Jet(matmul(A.val, B.val), matmul(A.dot, B.val) + matmul(A.val, B.dot))
    # |A B - mid| <= |A| rad_B + rad_A (|B| + rad_B) + (k + 2) u |A| |B| (one product fewer
    # when grouped); the radius is itself a sum of 2 k non-negative products (two k-term sums
    # added), rounded with a relative error below (k + 3) u: it is inflated by twice that.
    batch_A, batch_B = A.mid.shape[:-2], B.mid.shape[:-2]
    if batch_B and batch_A == batch_B:
        return _compiled_matmul(A, B)
    terms = A.mid.shape[-1]
    absB = np.abs(B.mid)
    mid = _product(A.mid, B.mid)
    rad = _product(np.abs(A.mid), B.rad + (terms + 2) * U * absB)
    if A.rad.any():
        rad = rad + _product(A.rad, absB + B.rad)
    return Ball(mid, rad * (1.0 + 2 * (terms + 4) * U))


def _product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` (numpy's broadcasting), as one matrix product when ``a`` is a single matrix
    for a batch of ``b`` (numpy's batched product makes a library call per small matrix)."""
    if a.ndim != 2 or b.ndim < 3:
        return a @ b
    rows, (terms, columns) = a.shape[0], b.shape[-2:]
    stacked = np.moveaxis(b, -2, 0).reshape(terms, -1)
    out = (a @ stacked).reshape((rows,) + b.shape[:-2] + (columns,))
    return np.moveaxis(out, 0, -2)


def _compiled_matmul(A: Ball, B: Ball) -> Ball:
    """:func:`matmul` for batches of ``A`` and ``B`` of the same shape: one compiled pass
    (numpy's batched product makes a library call per small matrix, and the radius costs it
    three products and five temporaries)."""
    batch = B.mid.shape[:-2]
    (rows, terms), columns = A.mid.shape[-2:], B.mid.shape[-1]

    def flat(x, shape):
        return np.ascontiguousarray(x, dtype=float).reshape((-1,) + shape)

    mid = np.empty((int(np.prod(batch)), rows, columns))
    rad = np.empty_like(mid)
    _ball_matmul_kernel(
        flat(A.mid, (rows, terms)), flat(A.rad, (rows, terms)),
        flat(B.mid, (terms, columns)), flat(B.rad, (terms, columns)),
        (terms + 2) * U, 1.0 + 2 * (terms + 4) * U, mid, rad,
    )  # fmt: skip
    shape = batch + (rows, columns)
    return Ball(mid.reshape(shape), rad.reshape(shape))


@numba.njit(
    "void(f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1], f8, f8, f8[:, :, ::1], "
    "f8[:, :, ::1])",
    cache=True,
    nogil=True,
    boundscheck=False,
)
def _ball_matmul_kernel(Am, Ar, Bm, Br, rounding, inflation, mid, rad):  # pragma: no cover
    """``mid = Am @ Bm`` and its radius over the batch. Compiled: IEEE arithmetic, no
    fast-math; each sum runs in order, so a k-term sum has the relative error ``(k - 1) u`` of
    the analysis in :func:`matmul`, or less."""
    batch, terms, columns = Bm.shape
    rows = Am.shape[1]
    first_factor = np.empty((terms, columns))  # rad_B + (k + 2) u |B|
    second_factor = np.empty((terms, columns))  # |B| + rad_B
    for b in range(batch):
        for k in range(terms):
            for j in range(columns):
                absx = abs(Bm[b, k, j])
                first_factor[k, j] = Br[b, k, j] + rounding * absx
                second_factor[k, j] = absx + Br[b, k, j]
        for i in range(rows):
            for j in range(columns):
                m = 0.0
                first = 0.0
                second = 0.0
                for k in range(terms):
                    a = Am[b, i, k]
                    m += a * Bm[b, k, j]
                    first += abs(a) * first_factor[k, j]
                    second += Ar[b, i, k] * second_factor[k, j]
                mid[b, i, j] = m
                rad[b, i, j] = (first + second) * inflation


def matvec(A, x):
    """``A x`` for matrices ``(..., i, k)`` and vectors ``(..., k)``."""
    return matmul(A, x.map(lambda a: a[..., None])).map(lambda a: a[..., 0])


def transposed(A):
    return A.map(lambda a: np.swapaxes(a, -1, -2))


def skew(x):
    """``S(x)`` with ``S(x) y = x cross y``: shape ``(..., 3) -> (..., 3, 3)``."""
    if isinstance(x, Jet):
        return Jet(skew(x.val), skew(x.dot))

    def build(v, sign):
        a, b, c = v[..., 0], v[..., 1], v[..., 2]
        out = np.zeros(v.shape + (3,))
        out[..., 0, 1], out[..., 0, 2] = -sign * c, b
        out[..., 1, 0], out[..., 1, 2] = c, -sign * a
        out[..., 2, 0], out[..., 2, 1] = -sign * b, a
        return out

    return Ball(build(x.mid, 1.0), build(x.rad, -1.0))


def cross(a, b):
    """``a x b`` of 3-vectors."""
    return matvec(skew(a), b)


def concatenate(parts, axis: int):
    if any(isinstance(p, Jet) for p in parts):
        parts = [Jet.of(p) for p in parts]
        return Jet(
            concatenate([p.val for p in parts], axis), concatenate([p.dot for p in parts], axis)
        )
    return Ball(
        np.concatenate([p.mid for p in parts], axis), np.concatenate([p.rad for p in parts], axis)
    )


def stack(parts, axis: int):
    if any(isinstance(p, Jet) for p in parts):
        parts = [Jet.of(p) for p in parts]
        return Jet(stack([p.val for p in parts], axis), stack([p.dot for p in parts], axis))
    return Ball(np.stack([p.mid for p in parts], axis), np.stack([p.rad for p in parts], axis))


def zeros(shape) -> Ball:
    return Ball.point(np.zeros(shape))


def cos_sin(q):
    """``cos q``, ``sin q`` over a ball (or jet) of angles [rad]."""
    if isinstance(q, Jet):
        c, s = cos_sin(q.val)
        return Jet(c, -(s * q.dot)), Jet(s, c * q.dot)
    c, s = np.cos(q.mid), np.sin(q.mid)
    reach = np.minimum(2.0, 0.5 * q.rad * q.rad * UP)
    library = 4 * U  # two ulps of the library's rounding at magnitudes <= 1
    cos = Ball(c, np.minimum(2.0, (np.abs(s) * q.rad + reach) * UP) + library)
    sin = Ball(s, np.minimum(2.0, (np.abs(c) * q.rad + reach) * UP) + library)
    return cos, sin


def intersect_symmetric(M):
    """A symmetric matrix's two enclosures of each off-diagonal entry, intersected."""
    if isinstance(M, Jet):
        return Jet(intersect_symmetric(M.val), intersect_symmetric(M.dot))
    lower = np.maximum(M.lower, np.swapaxes(M.lower, -1, -2))
    upper = np.minimum(M.upper, np.swapaxes(M.upper, -1, -2))
    return Ball.hull(lower, upper)
