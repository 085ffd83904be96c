"""The delayed law's common quadratic form (urpc.control.delay_form, docs/sampled-data.md §7):
a proved form contracts the two-step loop for symmetric ``A``, ``H`` with unrelated eigenvectors
that satisfy its sectors and coupling, checked by direct sampling; the exact proof rejects what
does not hold; no form is found below the radius of a loop it must contract, or where one
diverges."""

import numpy as np
import pytest

from urpc.control.delay_form import SectorRanges, common_form, per_mode_radius, proves

# The UR5's sampled ranges at the dead-beat ceiling (python scripts/delay_lyapunov.py ur5).
UR5 = SectorRanges(0.611, 1.0, 0.485, 1.637, 0.611)
# The paper's arm's, as the certificate bounds them over cells at 0.2 ms.
RR = SectorRanges(0.85, 0.978, 0.344, 1.05, 0.957)


def _admissible_pair(rng, n, ranges):
    """Symmetric ``A``, ``H`` with eigenvalues at the ends of the ranges (or inside) and unrelated
    eigenvectors, drawn until the coupling ``A^1/2 H^2 A^1/2 <= 1 / c`` holds."""
    while True:
        pair = []
        for low, high in ((ranges.a1, ranges.a2), (ranges.h1, ranges.h2)):
            basis, _ = np.linalg.qr(rng.normal(size=(n, n)))
            values = rng.choice([low, high], n) if rng.random() < 0.5 else rng.uniform(low, high, n)
            pair.append((basis * values) @ basis.T)
        A, H = pair
        root = np.linalg.cholesky(A)
        if ranges.c * np.linalg.eigvalsh(root.T @ H @ H @ root)[-1] <= 1.0:
            return A, H


@pytest.mark.parametrize("ranges", [UR5, RR])
def test_a_proved_form_contracts_every_sampled_non_commuting_loop(ranges):
    form = common_form(ranges)
    assert form is not None and form.rate < 1
    X, rho = form.X, form.rate
    rng = np.random.default_rng(7)

    def V(z, y):
        return X[0, 0] * z @ z + 2 * X[0, 1] * z @ y + X[1, 1] * y @ y

    for n in (2, 3, 7):
        for _ in range(200):
            A, H = _admissible_pair(rng, n, ranges)
            z, y = rng.normal(size=n), rng.normal(size=n)
            assert V(z - H @ A @ y, z - A @ y) <= rho**2 * V(z, y) * (1 + 1e-12)
        # a pair redrawn at every period: the form shrinks as rho^(2k)
        z, y = rng.normal(size=n), rng.normal(size=n)
        start = V(z, y)
        for _ in range(60):
            A, H = _admissible_pair(rng, n, ranges)
            z, y = z - H @ A @ y, z - A @ y
        assert V(z, y) <= rho**120 * start * (1 + 1e-9)


def test_the_form_holds_for_every_range_within_the_one_it_was_proved_for():
    """The ranges are widened outward before the search: the proof covers the given ones, and
    narrower ranges prove the same form."""
    form = common_form(RR)
    wide = form.ranges
    assert wide.a1 <= RR.a1 and wide.a2 >= RR.a2 and wide.h1 <= RR.h1 and wide.h2 >= RR.h2
    assert wide.c <= RR.c
    x = (form.x12, form.x22, *form.t)
    assert proves(wide, form.rate, x) and proves(RR, form.rate, x)


def test_the_exact_proof_rejects_a_rate_or_ranges_the_form_does_not_cover():
    form = common_form(UR5)
    x = (form.x12, form.x22, *form.t)
    assert proves(form.ranges, form.rate, x)
    assert not proves(form.ranges, form.rate * 0.95, x)  # a faster rate than the form gives
    wider = SectorRanges(UR5.a1, UR5.a2, UR5.h1, UR5.h2 * 1.3, UR5.c)
    assert not proves(wider, form.rate, x)
    assert not proves(form.ranges, form.rate, (form.x12, form.x22, -1.0, *form.t[1:]))
    # X not positive definite
    assert not proves(form.ranges, form.rate, (2.0, 1.0, *form.t))


def test_no_form_beats_the_loops_it_must_contract():
    """A pair sharing its eigenvectors is a loop of the ranges too (when the coupling admits
    it): no form's rate is below the largest radius of those loops (the corners checked
    independently of the grid)."""
    corners = [
        float(np.max(np.abs(np.linalg.eigvals([[1, -h * a], [1, -a]]))))
        for a in (UR5.a1, UR5.a2)
        for h in (UR5.h1, UR5.h2)
        if UR5.c * h * h * a <= 1.0
    ]
    per_mode = per_mode_radius(UR5)
    assert corners and per_mode >= max(corners)
    assert common_form(UR5).rate >= per_mode * (1 - 1e-9)


def test_no_form_where_a_loop_of_the_ranges_diverges():
    """At the dead-beat gain a plant 2.2 times lighter than the prediction's model along a mode
    (``h = 2.2``, admitted by a coupling of ``c = 0.2``) makes ``[[1, -2.2], [1, -1]]``
    unstable: no form can contract it. Nor over the Panda's shipped box (its payload: ``M0``
    up to 3.6 times a plant)."""
    diverging = SectorRanges(1.0, 1.0, 2.2, 2.2, 0.2)
    assert per_mode_radius(diverging) > 1
    assert common_form(diverging) is None
    assert common_form(SectorRanges(0.275, 1.0, 0.312, 3.638, 0.275)) is None


@pytest.mark.parametrize(
    "ranges",
    [
        SectorRanges(float("nan"), 1.0, 0.5, 1.0, 0.5),
        SectorRanges(0.5, 0.4, 0.5, 1.0, 0.5),
        SectorRanges(0.5, 1.0, 0.0, 1.0, 0.5),
        SectorRanges(0.5, 1.0, 0.5, float("inf"), 0.5),
    ],
)
def test_unusable_ranges_have_no_form(ranges):
    assert common_form(ranges) is None
