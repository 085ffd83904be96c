"""The spectral norm of many small matrices, bounded from above with a proof per matrix.

The certificate takes hundreds of thousands of spectral norms of small matrices (the inertia
models' and the Coriolis forms' congruences, cell by cell: 471 000 of size 6x6 for the UR5 at
1 kHz). Through numpy's batched call LAPACK's ``syevd`` costs about 2.5 us per 6x6 matrix, most of
it general machinery, and its result carries a rounding error that only a margin covers. Here,
per matrix ``X`` with Gram matrix ``G = X^T X`` (or ``X X^T``, the smaller), formed in the kernel:

1. **An estimate** ``mu`` of ``lambda_max(G)``: the largest Ritz value on a two-dimensional
   subspace after at most 20 subspace iterations (fewer once it settles), which converges as
   ``(lambda_3 / lambda_1)^(2k)``, so that the close pair of eigenvalues a symmetric ``X`` with
   eigenvalues of opposite signs gives ``G`` does not slow it; when its proof fails (3.5 % of the
   UR5's matrices), cyclic Jacobi rotations (Golub & Van Loan, Algorithm 8.5.3) to convergence.
2. **A proof** that ``s = mu (1 + delta)`` bounds ``lambda_max(G)``: a Cholesky factorization of
   ``F = s 1 - G - c 1`` that runs to completion in floating point. A completed floating-point
   Cholesky gives ``R^T R = F + E`` with ``|E| <= gamma_{n+1} |R^T| |R|`` (Higham, *Accuracy and
   Stability of Numerical Algorithms*, Theorem 10.3), so ``||E||_2 <= gamma_{n+1} ||R||_F^2 <=
   gamma_{n+1} tr(F) / (1 - gamma_{n+1})`` and ``F >= -||E||_2 1`` (the argument of S. M. Rump,
   *Verification of positive definiteness*, BIT 46, 2006). The shift ``c = 1e-12 n (s + tr G)``
   exceeds that (about ``(n + 1) n u s``), the rounding of forming ``F`` (``3 u (s + G_ii)`` per
   diagonal entry) and of the Gram matrix itself (at most ``n^2 u lambda_max`` on its eigenvalues)
   together, for ``n`` up to 1000 (larger matrices, and traces near underflow, go to LAPACK). So
   ``s 1 - G`` is positive definite for the exact Gram matrix: ``lambda_max(G) < s`` and
   ``||X||_2 < sqrt(s)`` (the square root rounded up).
3. ``delta = 1e-7`` first; after Jacobi, ``1e-4`` and ``1e-2`` if needed. A matrix no rung
   proves (or not finite) is returned as NaN and its norm taken by LAPACK (:func:`spectral_norm`).

The bound is at most ``(1 + delta)^(1/2)`` times the norm: within 5e-8 on every one of the
UR5's matrices. It costs 0.45 times ``syevd`` with the Gram product on them (1.1 us per matrix).
Checked against LAPACK's eigenvalues on random, rank-deficient, clustered, scaled, rectangular and
entrywise non-negative matrices, and a proof asked below the estimate never succeeds
(``tests/test_verified_norms.py``).
"""

from __future__ import annotations

import numba
import numpy as np

_JIT = {"cache": True, "nogil": True, "boundscheck": False}

#: Most subspace iterations before the first proof attempt (fewer once the estimate gains less
#: than 1e-9 relative in a step).
SUBSPACE_STEPS = 20
#: The relative slack tried, in order, above the power iteration's estimate.
SLACK_LADDER = (1e-7, 1e-4, 1e-2)
#: Relative shift (per dimension) that covers the floating-point Cholesky's and the matrices'
#: rounding; valid up to :data:`LARGEST_DIMENSION`.
ROUNDING_SHIFT = 1e-12
LARGEST_DIMENSION = 1000


@numba.njit(**_JIT)
def _positive_definite(A, scratch):  # pragma: no cover - compiled
    """Whether a floating-point Cholesky of ``A`` (n, n) runs to completion (no pivot <= 0)."""
    n = A.shape[0]
    for i in range(n):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= scratch[i, k] * scratch[j, k]
            if i == j:
                if not s > 0.0:
                    return False
                scratch[i, i] = np.sqrt(s)
            else:
                scratch[i, j] = s / scratch[j, j]
    return True


@numba.njit(**_JIT)
def _proved(G, trace, s, A, scratch, shift):  # pragma: no cover - compiled
    """Whether ``lambda_max(G) < s`` is proved: the Cholesky factorization of ``(s - c) 1 - G``
    runs to completion (module docstring, step 3)."""
    n = G.shape[0]
    c = shift * n * (s + trace)
    for a in range(n):
        for b in range(n):
            A[a, b] = -G[a, b]
        A[a, a] += s - c
    return _positive_definite(A, scratch)


@numba.njit(**_JIT)
def _orthonormal(u, v, n):  # pragma: no cover - compiled
    """Gram-Schmidt (twice) of ``u``, ``v`` in place; ``v`` replaced by a coordinate vector
    when it lies in ``u``'s span. False when ``u`` is zero."""
    norm = 0.0
    for a in range(n):
        norm += u[a] * u[a]
    if norm == 0.0:
        return False
    norm = np.sqrt(norm)
    for a in range(n):
        u[a] /= norm
    for attempt in range(n + 1):
        for _ in range(2):
            dot = 0.0
            for a in range(n):
                dot += u[a] * v[a]
            for a in range(n):
                v[a] -= dot * u[a]
        norm = 0.0
        for a in range(n):
            norm += v[a] * v[a]
        if norm > 1e-20:
            norm = np.sqrt(norm)
            for a in range(n):
                v[a] /= norm
            return True
        for a in range(n):
            v[a] = 1.0 if a == attempt % n else 0.0
    return True


@numba.njit(**_JIT)
def _subspace_estimate(G, trace, u, v, y, z, steps):  # pragma: no cover - compiled
    """The largest Ritz value of ``G`` on a two-dimensional subspace after subspace iterations
    (step 1): a lower estimate of ``lambda_max`` that converges as ``(lambda_3 /
    lambda_1)^(2k)``, so that a close second eigenvalue (``X``'s eigenvalues of opposite signs
    and near magnitudes) does not slow it down."""
    n = G.shape[0]
    # The diagonal's square roots plus a constant: positive, so never orthogonal to the Perron
    # vector of a non-negative matrix; the second start alternates in sign.
    for a in range(n):
        u[a] = np.sqrt(max(G[a, a], 0.0)) + trace / n * 1e-3
        v[a] = u[a] if a % 2 == 0 else -u[a]
    theta = 0.0
    for step in range(steps):
        if not _orthonormal(u, v, n):
            break
        h11, h12, h22 = 0.0, 0.0, 0.0
        for a in range(n):
            s1, s2 = 0.0, 0.0
            for b in range(n):
                s1 += G[a, b] * u[b]
                s2 += G[a, b] * v[b]
            y[a], z[a] = s1, s2
            h11 += u[a] * s1
            h12 += u[a] * s2
            h22 += v[a] * s2
        previous = theta
        half = 0.5 * (h11 - h22)
        theta = 0.5 * (h11 + h22) + np.sqrt(half * half + h12 * h12)
        for a in range(n):
            u[a], v[a] = y[a], z[a]
        if step >= 2 and theta - previous <= 1e-9 * theta:
            break
    return max(theta, 0.0)


@numba.njit(**_JIT)
def _jacobi_estimate(G, W):  # pragma: no cover - compiled
    """The largest eigenvalue by cyclic Jacobi rotations (Golub & Van Loan, Algorithm 8.5.3)
    until the off-diagonal part is below ``1e-15`` of the matrix (step 2): the largest diagonal
    entry plus the off-diagonal part's Frobenius norm (Weyl)."""
    n = G.shape[0]
    total = 0.0
    for a in range(n):
        for b in range(n):
            W[a, b] = G[a, b]
            total += G[a, b] * G[a, b]
    for _ in range(30):
        off = 0.0
        for a in range(n):
            for b in range(a + 1, n):
                off += 2.0 * W[a, b] * W[a, b]
        if off <= 1e-30 * total:
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                if W[p, q] == 0.0:
                    continue
                tau = (W[q, q] - W[p, p]) / (2.0 * W[p, q])
                if tau >= 0.0:
                    t = 1.0 / (tau + np.sqrt(1.0 + tau * tau))
                else:
                    t = -1.0 / (-tau + np.sqrt(1.0 + tau * tau))
                c = 1.0 / np.sqrt(1.0 + t * t)
                s = t * c
                for k in range(n):
                    wp, wq = W[k, p], W[k, q]
                    W[k, p] = c * wp - s * wq
                    W[k, q] = s * wp + c * wq
                for k in range(n):
                    wp, wq = W[p, k], W[q, k]
                    W[p, k] = c * wp - s * wq
                    W[q, k] = s * wp + c * wq
    off = 0.0
    largest = -np.inf
    for a in range(n):
        largest = max(largest, W[a, a])
        for b in range(n):
            if a != b:
                off += W[a, b] * W[a, b]
    return max(largest + np.sqrt(off), 0.0)


@numba.njit(**_JIT)
def _bound_one(G, x, y, u, v, A, W, steps, ladder, shift):  # pragma: no cover - compiled
    """A proved upper bound of ``lambda_max`` of one symmetric positive semi-definite ``G``
    (n, n); NaN where none could be proved (the other arrays: work space)."""
    n = G.shape[0]
    trace = 0.0
    for a in range(n):
        trace += G[a, a]
        for b in range(n):
            if not np.isfinite(G[a, b]):
                return np.nan
    if 0.0 < trace < 1e-280:
        return np.nan
    if trace == 0.0:  # a positive semi-definite matrix of zero trace is zero
        return 0.0
    mu = G[0, 0]  # exact for n = 1
    for estimate in range(2):
        if n > 1 and estimate == 0:
            mu = _subspace_estimate(G, trace, x, y, u, v, steps)
        elif n > 1:
            mu = _jacobi_estimate(G, W)
        for rung in range(ladder.shape[0]):
            s = mu * (1.0 + ladder[rung])
            if s == 0.0:
                s = trace * ladder[rung]
            if _proved(G, trace, s, A, W, shift):
                return s
            if estimate == 0:
                break  # the subspace estimate gets one attempt, then Jacobi's the ladder
    return np.nan


@numba.njit(**_JIT)
def _largest_eigenvalue_bounds(G, steps, ladder, shift):  # pragma: no cover - compiled
    """:func:`_bound_one` of each matrix of ``G`` (m, n, n)."""
    m, n = G.shape[0], G.shape[1]
    out = np.empty(m)
    x, y, u, v = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    A, W = np.empty((n, n)), np.empty((n, n))
    for i in range(m):
        out[i] = _bound_one(G[i], x, y, u, v, A, W, steps, ladder, shift)
    return out


@numba.njit(**_JIT)
def _gram_bounds(X, steps, ladder, shift):  # pragma: no cover - compiled
    """:func:`_bound_one` of the Gram matrix of each matrix of ``X`` (m, rows, columns): ``X^T X``
    or ``X X^T``, the smaller, formed here (its rounding is covered by the shift)."""
    m, rows, columns = X.shape
    n = min(rows, columns)
    out = np.empty(m)
    G = np.empty((n, n))
    x, y, u, v = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    A, W = np.empty((n, n)), np.empty((n, n))
    for i in range(m):
        for a in range(n):
            for b in range(a + 1):
                s = 0.0
                if rows >= columns:
                    for k in range(rows):
                        s += X[i, k, a] * X[i, k, b]
                else:
                    for k in range(columns):
                        s += X[i, a, k] * X[i, b, k]
                G[a, b] = s
                G[b, a] = s
        out[i] = _bound_one(G, x, y, u, v, A, W, steps, ladder, shift)
    return out


def spectral_norm(X: np.ndarray) -> np.ndarray:
    """An upper bound of the spectral norm of each matrix of a batch (symmetric or not): the
    square root of a proved bound of the largest eigenvalue of its Gram matrix ``X^T X`` (or
    ``X X^T``, the smaller), rounded up; LAPACK's ``syevd`` for the few whose proof failed (and
    for non-finite ``X``, as before: it raises)."""
    rows, columns = X.shape[-2:]
    shape = X.shape[:-2]
    if X.size == 0:
        return np.zeros(shape)
    flat = np.ascontiguousarray(X, dtype=np.float64).reshape(-1, rows, columns)
    if min(rows, columns) > LARGEST_DIMENSION:
        bound = np.full(len(flat), np.nan)
    else:
        ladder = np.asarray(SLACK_LADDER, dtype=np.float64)
        bound = _gram_bounds(flat, SUBSPACE_STEPS, ladder, ROUNDING_SHIFT)
    norm = np.sqrt(bound) * (1 + 4 * np.finfo(float).eps)
    failed = np.isnan(bound)
    if failed.any():
        Y = flat[failed]
        Yt = np.swapaxes(Y, -1, -2)
        gram = Yt @ Y if rows >= columns else Y @ Yt
        norm[failed] = np.sqrt(np.maximum(np.linalg.eigvalsh(gram)[..., -1], 0.0))
    return norm.reshape(shape)
