"""The delayed law's common Lyapunov form (scripts/delay_lyapunov.py, docs/robot.md §7): a form
the S-procedure finds contracts the two-step loop for symmetric ``A``, ``H`` with unrelated
eigenvectors that satisfy its sectors and coupling, checked by direct sampling here; none is
found below the radius of a loop it must contract, or where such a loop diverges."""

import runpy
from pathlib import Path

import numpy as np

SCRIPT = runpy.run_path(str(Path(__file__).parents[1] / "scripts" / "delay_lyapunov.py"))
# The UR5's sampled ranges at the dead-beat ceiling (python scripts/delay_lyapunov.py ur5).
A1, A2, H1, H2 = 0.611, 1.0, 0.485, 1.637
C = A1  # the coupling's b0


def _admissible_pair(rng, n):
    """Symmetric ``A``, ``H`` with their eigenvalues at the ends of the ranges and unrelated
    eigenvectors, drawn until the coupling ``A^1/2 H^2 A^1/2 <= 1 / C`` holds."""
    while True:
        pair = []
        for low, high in ((A1, A2), (H1, H2)):
            basis, _ = np.linalg.qr(rng.normal(size=(n, n)))
            pair.append((basis * rng.choice([low, high], n)) @ basis.T)
        A, H = pair
        root = np.linalg.cholesky(A)
        if C * np.linalg.eigvalsh(root.T @ H @ H @ root)[-1] <= 1.0:
            return A, H


def test_a_feasible_form_contracts_every_sampled_non_commuting_loop():
    rho = 0.9
    x = SCRIPT["feasible"](rho, A1, A2, H1, H2, C)
    assert x is not None
    assert np.linalg.eigvalsh(SCRIPT["form"](x, rho, A1, A2, H1, H2, C))[-1] < 0
    X = np.array([[1.0, x[0]], [x[0], x[1]]])
    assert np.linalg.eigvalsh(X)[0] > 0 and np.min(x[2:]) >= 0
    rng = np.random.default_rng(7)

    def V(z, y):
        return X[0, 0] * z @ z + 2 * X[0, 1] * z @ y + X[1, 1] * y @ y

    for n in (2, 3, 7):
        for _ in range(200):
            A, H = _admissible_pair(rng, n)
            z, y = rng.normal(size=n), rng.normal(size=n)
            assert V(z - H @ A @ y, z - A @ y) <= rho**2 * V(z, y) * (1 + 1e-12)
        # a pair redrawn at every period: the form shrinks as rho^(2k)
        z, y = rng.normal(size=n), rng.normal(size=n)
        start = V(z, y)
        for _ in range(60):
            A, H = _admissible_pair(rng, n)
            z, y = z - H @ A @ y, z - A @ y
        assert V(z, y) <= rho**120 * start * (1 + 1e-9)


def test_no_form_beats_the_loops_it_must_contract():
    """A pair sharing its eigenvectors is a loop of the ranges too (when the coupling admits
    it): no form finds a rate below the largest radius of those loops (checked on the
    admissible corners independently of the script's grid)."""
    corners = [
        float(np.max(np.abs(np.linalg.eigvals([[1, -h * a], [1, -a]]))))
        for a in (A1, A2)
        for h in (H1, H2)
        if C * h * h * a <= 1.0
    ]
    per_mode = SCRIPT["per_mode_radius"](A1, A2, H1, H2, C)
    assert corners and per_mode >= max(corners)
    assert SCRIPT["feasible"](per_mode - 0.01, A1, A2, H1, H2, C) is None


def test_no_form_where_a_loop_of_the_ranges_diverges():
    """At the dead-beat gain a plant 2.2 times lighter than the prediction's model along a mode
    (``h = 2.2``, admitted by a coupling of ``c = 0.2``) makes ``[[1, -2.2], [1, -1]]``
    unstable: no form can contract it."""
    assert SCRIPT["per_mode_radius"](1.0, 1.0, 2.2, 2.2, 0.2) > 1
    assert SCRIPT["feasible"](0.999, 1.0, 1.0, 2.2, 2.2, 0.2) is None
