"""The delayed law's common Lyapunov form (scripts/delay_lyapunov.py, docs/robot.md §7): a form
the S-procedure finds contracts the two-step loop for symmetric ``A``, ``H`` with unrelated
eigenvectors, checked by direct sampling here; none is found where a loop of the ranges is
unstable."""

import runpy
from pathlib import Path

import numpy as np

SCRIPT = runpy.run_path(str(Path(__file__).parents[1] / "scripts" / "delay_lyapunov.py"))
# The UR5's sampled ranges at the dead-beat ceiling (python scripts/delay_lyapunov.py ur5).
A1, A2, H1, H2 = 0.611, 1.0, 0.485, 1.637


def test_a_feasible_form_contracts_every_sampled_non_commuting_loop():
    rho = 0.9
    x = SCRIPT["feasible"](rho, A1, A2, H1, H2)
    assert x is not None
    assert np.linalg.eigvalsh(SCRIPT["form"](x, rho, A1, A2, H1, H2))[-1] < 0
    X = np.array([[1.0, x[0]], [x[0], x[1]]])
    assert np.linalg.eigvalsh(X)[0] > 0 and x[2] >= 0 and x[3] >= 0
    rng = np.random.default_rng(7)

    def symmetric(low, high, n):
        basis, _ = np.linalg.qr(rng.normal(size=(n, n)))
        return (basis * rng.choice([low, high], n)) @ basis.T

    def V(z, y):
        return X[0, 0] * z @ z + 2 * X[0, 1] * z @ y + X[1, 1] * y @ y

    for n in (2, 3, 7):
        for _ in range(300):
            A, H = symmetric(A1, A2, n), symmetric(H1, H2, n)
            z, y = rng.normal(size=n), rng.normal(size=n)
            assert V(z - H @ A @ y, z - A @ y) <= rho**2 * V(z, y) * (1 + 1e-12)
        # a long product of such steps shrinks as rho^k
        z, y = rng.normal(size=n), rng.normal(size=n)
        start = V(z, y)
        for _ in range(60):
            A, H = symmetric(A1, A2, n), symmetric(H1, H2, n)
            z, y = z - H @ A @ y, z - A @ y
        assert V(z, y) <= rho**120 * start * (1 + 1e-9)


def test_the_common_rate_is_no_better_than_the_per_mode_radius():
    """Commuting ``A``, ``H`` are loops of the ranges too: per mode the 2x2 loop's radius is a
    bound from below for any common form (checked on the grid's corners independently)."""
    corners = max(
        float(np.max(np.abs(np.linalg.eigvals([[1, -h * a], [1, -a]]))))
        for a in (A1, A2)
        for h in (H1, H2)
    )
    per_mode = SCRIPT["per_mode_radius"](A1, A2, H1, H2)
    assert per_mode >= corners
    assert SCRIPT["feasible"](per_mode - 0.01, A1, A2, H1, H2) is None


def test_no_form_where_a_commuting_loop_of_the_ranges_diverges():
    """At the dead-beat gain a plant 2.2 times lighter than the prediction's model along a mode
    (``h = 2.2``) makes ``[[1, -2.2], [1, -1]]`` unstable: no form can contract it."""
    assert SCRIPT["per_mode_radius"](1.0, 1.0, 2.2, 2.2) > 1
    assert SCRIPT["feasible"](0.999, 1.0, 1.0, 2.2, 2.2) is None
