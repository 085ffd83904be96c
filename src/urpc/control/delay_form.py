"""A common quadratic form that contracts the delayed law's two-step loop (docs/sampled-data.md
§7), found by a convex solver and proved in exact rational arithmetic.

Per period the delayed law's feedback acts on the error ``r`` through its prediction ``r^``. In
the metric of the nominal model ``N = M0(q_k)``, ``z = N^1/2 r``, ``y = N^1/2 r^``, the loop
without its forcing is

    z+ = z - H A y,    y+ = z - A y,    A = N^-1/2 T K N^-1/2,    H = N^1/2 M^-1 N^1/2

with ``A`` and ``H`` symmetric, whatever their eigenvectors. With ``u = A y`` and ``w = H u``
three inequalities hold for every vector (:class:`SectorRanges`): the sectors ``(u - a1 y).(a2 y -
u) >= 0`` (the spectrum of ``A`` in ``[a1, a2]``) and ``(w - h1 u).(h2 u - w) >= 0`` (that of ``H``
in ``[h1, h2]``), and the coupling ``y.u >= c |w|^2``. A form ``V = [z; y]^T (X (x) 1) [z; y]``
(``X`` 2x2, ``X_11 = 1``) with multipliers ``t1, t2, t3 >= 0`` such that

    V(z+, y+) - rho^2 V(z, y) + t1 (u - a1 y).(a2 y - u) + t2 (w - h1 u).(h2 u - w)
        + t3 (y.u - c |w|^2)  <=  0

as a quadratic form in ``(z, y, u, w)`` (a 4x4 matrix ``F``: every term is a scalar times the
identity, the S-procedure) gives ``V(z+, y+) <= rho^2 V(z, y)`` for every ``A``, ``H`` in the
ranges, changing from one period to the next: ``||.||_X = V^1/2`` is a norm the loop contracts by
``rho``.

:func:`common_form` bisects on ``rho``; at each step the least largest eigenvalue of ``F`` over
``(X, t)`` is a small semidefinite program (Clarabel, an interior-point conic solver). The
solver's answer is not trusted: :func:`proves` checks the final ``F`` negative definite in exact
rational arithmetic (Sylvester's criterion on ``-F``, from the floating-point numbers as given),
and the ranges are first widened outward to three significant digits, so that a form serves
every range within them (and the certificate's pieces and tubes share forms).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from fractions import Fraction

import clarabel
import numpy as np
import scipy.sparse

__all__ = ["CommonForm", "SectorRanges", "common_form", "per_mode_radius", "proves"]

#: The ranges are widened outward to this many significant digits before a form is sought.
RANGE_DIGITS = 3
#: The bisection on ``rho`` stops within this of the least rate the solver finds.
RATE_TOLERANCE = 1e-3


@dataclasses.dataclass(frozen=True)
class SectorRanges:
    """The ranges a common form must hold over: ``A`` in ``[a1, a2]``, ``H`` in ``[h1, h2]``,
    the coupling ``y.u >= c |w|^2`` (module docstring)."""

    a1: float
    a2: float
    h1: float
    h2: float
    c: float

    def widened(self) -> SectorRanges:
        """The ranges rounded outward to :data:`RANGE_DIGITS` significant digits (a form for
        the wider ranges holds for these)."""
        return SectorRanges(
            _round(self.a1, -1), _round(self.a2, 1), _round(self.h1, -1), _round(self.h2, 1),
            _round(self.c, -1),
        )  # fmt: skip

    def usable(self) -> bool:
        """Finite, ``0 < a1 <= a2``, ``0 < h1 <= h2`` and ``c >= 0``."""
        values = (self.a1, self.a2, self.h1, self.h2, self.c)
        return (
            all(math.isfinite(v) for v in values)
            and 0 < self.a1 <= self.a2
            and 0 < self.h1 <= self.h2
            and self.c >= 0
        )


@dataclasses.dataclass(frozen=True)
class CommonForm:
    """A proved form: ``V(z+, y+) <= rate^2 V(z, y)`` over ``ranges`` with ``X = [[1, x12],
    [x12, x22]]`` and the multipliers ``t``."""

    ranges: SectorRanges
    rate: float
    x12: float
    x22: float
    t: tuple[float, float, float]

    @property
    def X(self) -> np.ndarray:
        return np.array([[1.0, self.x12], [self.x12, self.x22]])

    def coordinate_scales(self) -> np.ndarray:
        """``(l_z, l_y, l_p)`` with ``|z| <= l_z ||[z; y]||_X``, ``|y| <= l_y ||.||_X`` and ``|z -
        y| <= l_p ||.||_X``: ``(c^T X^-1 c)^1/2`` for ``c`` = ``(1, 0)``, ``(0, 1)``, ``(1, -1)``
        (Cauchy-Schwarz in ``X``'s inner product), rounded up."""
        det = self.x22 - self.x12 * self.x12
        inverse = np.array([[self.x22, -self.x12], [-self.x12, 1.0]]) / det
        directions = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, -1.0]])
        values = np.einsum("ki,ij,kj->k", directions, inverse, directions)
        return np.sqrt(values) * (1 + 1e-9)

    def norm_bound(self, f_z: np.ndarray, f_y: np.ndarray) -> np.ndarray:
        """A bound of ``||(f_z, f_y)||_X`` from bounds ``|f_z| <= f_z`` and ``|f_y| <= f_y``:
        ``X_11 f_z^2 + 2 |X_12| f_z f_y + X_22 f_y^2`` (Cauchy-Schwarz on the cross term)."""
        a = abs(self.x12)
        return np.sqrt(f_z**2 + 2 * a * f_z * f_y + self.x22 * f_y**2) * (1 + 1e-12)


def _round(x: float, direction: int) -> float:
    """``x`` rounded to :data:`RANGE_DIGITS` significant digits, up (``direction`` 1) or down."""
    if x == 0 or not math.isfinite(x):
        return x
    scale = 10.0 ** (math.floor(math.log10(abs(x))) - RANGE_DIGITS + 1)
    rounded = (math.ceil if direction > 0 else math.floor)(x / scale) * scale
    # The division and product round: step once more in the direction asked for.
    return float(np.nextafter(rounded, direction * math.inf))


def _matrices(ranges: SectorRanges, rho: float) -> tuple[np.ndarray, list[np.ndarray]]:
    """``F = F0 + sum_i x_i F_i`` over ``x = (X_12, X_22, t1, t2, t3)`` (module docstring), in
    floating point (for the solver)."""
    return _affine(ranges, rho, float)


def _affine(ranges: SectorRanges, rho, number):
    """The affine pieces of ``F`` with entries of type ``number`` (``float`` or ``Fraction``)."""
    a1, a2, h1, h2, c = (number(v) for v in dataclasses.astuple(ranges))
    rho2 = number(rho) * number(rho)
    zero, one, half = number(0), number(1), number(1) / number(2)
    step = [[one, zero, zero, -one], [one, zero, -one, zero]]  # (z+, y+) = (z - w, z - u)
    now = [[one, zero, zero, zero], [zero, one, zero, zero]]

    def quadratic(X):  # step^T X step - rho^2 now^T X now
        out = [[zero] * 4 for _ in range(4)]
        for i in range(4):
            for j in range(4):
                total = zero
                for a in range(2):
                    for b in range(2):
                        total += step[a][i] * X[a][b] * step[b][j]
                        total -= rho2 * now[a][i] * X[a][b] * now[b][j]
                out[i][j] = total
        return out

    def sector(i, j, low, high):  # (v_j - low v_i).(high v_i - v_j)
        out = [[zero] * 4 for _ in range(4)]
        out[i][j] = out[j][i] = (low + high) * half
        out[i][i], out[j][j] = -low * high, -one
        return out

    coupling = [[zero] * 4 for _ in range(4)]  # y.u - c |w|^2
    coupling[1][2] = coupling[2][1] = half
    coupling[3][3] = -c
    F0 = quadratic([[one, zero], [zero, zero]])
    pieces = [
        quadratic([[zero, one], [one, zero]]),
        quadratic([[zero, zero], [zero, one]]),
        sector(1, 2, a1, a2),
        sector(2, 3, h1, h2),
        coupling,
    ]
    if number is float:
        return np.array(F0), [np.array(P) for P in pieces]
    return F0, pieces


def proves(ranges: SectorRanges, rho: float, x: tuple[float, ...]) -> bool:
    """Whether ``x = (X_12, X_22, t1, t2, t3)`` proves the rate ``rho`` over ``ranges``: ``t >=
    0``, ``X`` positive definite and ``-F`` positive definite, every step in exact rational
    arithmetic from the floating-point values given (Sylvester's criterion: the leading
    principal minors of ``-F`` are positive)."""
    if not all(math.isfinite(v) for v in (rho, *x)) or min(x[2:]) < 0:
        return False
    X12, X22 = Fraction(x[0]), Fraction(x[1])
    if not X22 - X12 * X12 > 0:
        return False
    F0, pieces = _affine(ranges, rho, Fraction)
    F = [[-F0[i][j] - sum(Fraction(v) * P[i][j] for v, P in zip(x, pieces, strict=True)) for j in range(4)]
         for i in range(4)]  # fmt: skip
    return all(_determinant([row[:k] for row in F[:k]]) > 0 for k in range(1, 5))


def _determinant(A: list[list[Fraction]]) -> Fraction:
    """The determinant by fraction-exact elimination."""
    A = [row[:] for row in A]
    n, det = len(A), Fraction(1)
    for k in range(n):
        pivot = next((i for i in range(k, n) if A[i][k] != 0), None)
        if pivot is None:
            return Fraction(0)
        if pivot != k:
            A[k], A[pivot] = A[pivot], A[k]
            det = -det
        det *= A[k][k]
        for i in range(k + 1, n):
            factor = A[i][k] / A[k][k]
            for j in range(k, n):
                A[i][j] -= factor * A[k][j]
    return det


_SVEC_4 = [(i, j) for j in range(4) for i in range(j + 1)]  # Clarabel: upper triangle by column
_SVEC_2 = [(i, j) for j in range(2) for i in range(j + 1)]


def _svec(S: np.ndarray, index) -> np.ndarray:
    return np.array([S[i, j] * (1.0 if i == j else math.sqrt(2.0)) for i, j in index])


def _least_eigenvalue(ranges: SectorRanges, rho: float) -> tuple[float, np.ndarray] | None:
    """``min_x lambda_max(F(x))`` with ``X_22 - X_12^2 >= 1e-6``, ``t >= 0`` and ``|x| <=
    1e4`` (a semidefinite program over ``(x, s)``: ``s 1 - F(x)`` positive semidefinite), and
    its ``x``; ``None`` when the solver fails."""
    F0, pieces = _matrices(ranges, rho)
    n_x = len(pieces)
    # Variables v = (x_1..x_5, s); constraints b - A v in the cones.
    rows_F = np.column_stack([_svec(P, _SVEC_4) for P in pieces] + [-_svec(np.eye(4), _SVEC_4)])
    b_F = -_svec(F0, _SVEC_4)
    X12, X22 = np.array([[0.0, 1], [1, 0]]), np.array([[0.0, 0], [0, 1]])
    rows_X = np.zeros((3, n_x + 1))
    rows_X[:, 0], rows_X[:, 1] = -_svec(X12, _SVEC_2), -_svec(X22, _SVEC_2)
    b_X = _svec(np.array([[1.0, 0], [0, -1e-6]]), _SVEC_2)
    rows_t = np.zeros((3, n_x + 1))
    rows_t[:, 2:5] = -np.eye(3)
    rows_box = np.vstack([np.eye(n_x + 1)[:n_x], -np.eye(n_x + 1)[:n_x]])
    A = np.vstack([rows_t, rows_box, rows_F, rows_X])
    b = np.concatenate([np.zeros(3), np.full(2 * n_x, 1e4), b_F, b_X])
    cones = [
        clarabel.NonnegativeConeT(3 + 2 * n_x),
        clarabel.PSDTriangleConeT(4),
        clarabel.PSDTriangleConeT(2),
    ]
    q = np.zeros(n_x + 1)
    q[-1] = 1.0
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solver = clarabel.DefaultSolver(
        scipy.sparse.csc_matrix((n_x + 1, n_x + 1)), q, scipy.sparse.csc_matrix(A), b, cones,
        settings,
    )  # fmt: skip
    solution = solver.solve()
    if str(solution.status) not in ("Solved", "AlmostSolved"):
        return None
    v = np.asarray(solution.x)
    return float(v[-1]), v[:n_x]


def common_form(ranges: SectorRanges) -> CommonForm | None:
    """The least rate (within :data:`RATE_TOLERANCE`) with a proved form over ``ranges``
    widened (:meth:`SectorRanges.widened`), or ``None`` when no rate below 1 is proved."""
    if not ranges.usable():
        return None
    return _common_form(ranges.widened())


@functools.lru_cache(maxsize=256)
def _common_form(ranges: SectorRanges) -> CommonForm | None:
    def attempt(rho: float):
        found = _least_eigenvalue(ranges, rho)
        if found is None or not found[0] < -1e-9:
            return None
        x = tuple(float(v) for v in found[1])
        return x if proves(ranges, rho, x) else None

    high = 1.0 - 1e-6
    best = attempt(high)
    if best is None:
        return None
    low = 0.0
    while high - low > RATE_TOLERANCE:
        middle = 0.5 * (low + high)
        x = attempt(middle)
        if x is None:
            low = middle
        else:
            high, best = middle, x
    return CommonForm(ranges, high, best[0], best[1], (best[2], best[3], best[4]))


def per_mode_radius(ranges: SectorRanges, points: int = 81) -> float:
    """The largest spectral radius of the 2x2 loop ``[[1, -h a], [1, -a]]`` over a grid of
    ``a`` in ``[a1, a2]`` and ``h`` in ``[h1, h2]`` that the coupling admits (``c h^2 a <= 1``):
    ``A`` and ``H`` sharing their eigenvectors, loops every common form must contract, so no
    form's rate is below it."""
    worst = 0.0
    for a in np.linspace(ranges.a1, ranges.a2, points):
        for h in np.linspace(ranges.h1, ranges.h2, points):
            if ranges.c * h * h * a <= 1.0:
                loop = [[1.0, -h * a], [1.0, -a]]
                worst = max(worst, float(np.max(np.abs(np.linalg.eigvals(loop)))))
    return worst
