"""The proved spectral-norm bounds of ``urpc.model.verified_norms`` against LAPACK's eigenvalues
(an independent algorithm): never below the norm, tight where the power iteration settles, and a
proof that never succeeds below the largest eigenvalue."""

from __future__ import annotations

import numpy as np
import pytest

from urpc.model.verified_norms import (
    ROUNDING_SHIFT,
    SLACK_LADDER,
    SUBSPACE_STEPS,
    _largest_eigenvalue_bounds,
    spectral_norm,
)

# LAPACK's own eigenvalues carry a backward error of order n u ||G||: the reference is compared
# with that much slack, far below the bounds' slack (1e-7 and more above the norm).
REFERENCE_ROUNDING = 1e-13


def _batches(rng: np.random.Generator, n: int, count: int = 400) -> dict[str, np.ndarray]:
    Q = np.linalg.qr(rng.standard_normal((count, n, n)))[0]
    clustered = np.tile(np.linspace(1.0, 0.0, n), (count, 1))
    clustered[:, 1 % n] = 1.0 - 1e-9  # two top eigenvalues 1e-9 apart
    rank_one = np.zeros((count, n))
    rank_one[:, 0] = rng.uniform(0.1, 10.0, count)
    scaled = rng.standard_normal((count, n, n)) * 10.0 ** rng.uniform(-8, 8, (count, 1, 1))
    return {
        "gaussian": rng.standard_normal((count, n, n)),
        "non-negative": np.abs(rng.standard_normal((count, n, n))),
        "clustered": Q * np.sqrt(clustered)[:, None, :],
        "rank one": Q * np.sqrt(rank_one)[:, None, :],
        "scaled": scaled,
        "rectangular": rng.standard_normal((count, n, n + 3)),
    }


@pytest.mark.parametrize("n", [1, 2, 6, 7, 12, 30])
def test_the_bound_is_never_below_the_norm_and_tight(n):
    rng = np.random.default_rng(n)
    for kind, X in _batches(rng, n).items():
        exact = np.linalg.norm(X, 2, axis=(-2, -1))
        bound = spectral_norm(X)
        assert np.all(bound >= exact * (1 - REFERENCE_ROUNDING)), kind
        # (1 + 1e-7)^(1/2) above: the first rung, proved from the subspace or Jacobi estimate.
        assert np.all(bound <= exact * (1 + 5.0001e-8) + 1e-300), kind


def test_no_proof_succeeds_below_the_largest_eigenvalue():
    """Rungs around the estimate, down to 1e-6 below it and up to 1e-9 above: whatever a rung
    proves is at least LAPACK's largest eigenvalue (a success below it would be a false proof),
    and a rung 1e-6 below the estimate (which is below the largest eigenvalue) never succeeds."""
    rng = np.random.default_rng(1)
    for n in (2, 6, 12):
        for kind, X in _batches(rng, n).items():
            G = np.ascontiguousarray(np.swapaxes(X, -1, -2) @ X)
            largest = np.linalg.eigvalsh(G)[..., -1]
            zero = np.trace(G, axis1=-2, axis2=-1) == 0
            for ladder in ([-1e-6], [-1e-9], [0.0], [1e-12], [1e-9]):
                proved = _largest_eigenvalue_bounds(
                    G, SUBSPACE_STEPS, np.array(ladder), ROUNDING_SHIFT
                )
                done = ~np.isnan(proved)
                assert np.all(proved[done] >= largest[done] * (1 - REFERENCE_ROUNDING)), kind
                if ladder == [-1e-6]:
                    assert not done[~zero].any(), kind


def test_zero_matrices_are_zero_and_non_finite_ones_are_left_to_lapack():
    assert np.array_equal(spectral_norm(np.zeros((3, 4, 4))), np.zeros(3))
    G = np.eye(3)[None].repeat(2, axis=0)
    G[1, 0, 0] = np.nan
    bounds = _largest_eigenvalue_bounds(G, SUBSPACE_STEPS, np.array(SLACK_LADDER), ROUNDING_SHIFT)
    assert bounds[0] == pytest.approx(1.0, rel=1e-6) and bounds[0] >= 1.0
    assert np.isnan(bounds[1])
    assert spectral_norm(np.zeros((0, 3, 3))).shape == (0,)


def test_the_batch_shape_is_kept():
    X = np.random.default_rng(3).standard_normal((4, 5, 3, 3))
    bound = spectral_norm(X)
    assert bound.shape == (4, 5)
    assert np.all(bound >= np.linalg.norm(X, 2, axis=(-2, -1)) * (1 - REFERENCE_ROUNDING))
