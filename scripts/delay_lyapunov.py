"""A common Lyapunov function of the delayed law's two-step loop (docs/robot.md §7): where norms
fail (``scripts/delay_norm_argument.py``), a quadratic form does contract at the dead-beat ceiling.

    python scripts/delay_lyapunov.py rr_planar
    python scripts/delay_lyapunov.py ur5 --configurations 40 --fractions 1,0.5
    python scripts/delay_lyapunov.py panda --lock panda_finger_joint1,panda_finger_joint2

Per period, with the law's feedback ``K`` (``T K = s M_L``, ``s = 1`` at the dead-beat ceiling),
the plant ``M`` and the nominal model ``M0`` that predicts, the error ``r`` and its prediction
``r^`` obey ``r+ = r - T M^-1 K r^``, ``r^+ = r - T M0^-1 K r^`` (no forcing). In the nominal
metric, ``z = M0^1/2 r``, ``y = M0^1/2 r^``:

    z+ = z - H A y,    y+ = z - A y,    A = M0^-1/2 T K M0^-1/2,    H = M0^1/2 M^-1 M0^1/2

with ``A`` and ``H`` symmetric, the spectrum of ``A`` in ``[s b0, s]`` (``b0 = lambda_min(M0^-1
M_L)``; ``T K <= s M_L <= M0``) and that of ``H`` in ``[h1, h2]`` for every plant of the box
(``h1 = lambda_min(M_U^-1 M0)``, ``h2 = lambda_max(M_L^-1 M0)``, the box's bounds ``M_L <= M <=
M_U``). With ``u = A y`` and ``w = H u``, the sectors ``(u - s b0 y).(s y - u) >= 0`` and ``(w -
h1 u).(h2 u - w) >= 0`` hold whatever the eigenvectors, and so does the coupling ``y.u - b0 |w|^2
>= 0`` (``T K <= M_L <= M`` gives ``w^T M0^-1/2 M M0^-1/2 w <= y.u``, and ``M >= M_L``), so a form
``V = [z; y]^T (X (x) 1) [z; y]`` with

    V(z+, y+) - rho^2 V(z, y) + tau1 (u - s b0 y).(s y - u) + tau2 (w - h1 u).(h2 u - w)
        + tau3 (y.u - b0 |w|^2) <= 0

as a quadratic form in ``(z, y, u, w)`` contracts by ``rho`` per period for every plant of the
box and every configuration (``urpc.control.delay_form``, which the certificate uses: a convex
solver finds the form, exact rational arithmetic proves it). Next to it: the per-mode radius
(``A``, ``H`` sharing their eigenvectors: 2x2 loops over a grid of the two ranges), a bound from
below for any ``rho``, and the largest ``V+ / V`` over random non-commuting draws.

The ranges are sampled here (random configurations within the joint limits, clipped to +-3),
the law's ``M_L`` against the nominal model at the same point: a quick look at a box. The
certificate (``urpc certify`` with ``delay: 1``, docs/sampled-data.md §7) bounds them over cells
of the reference, adds the forcing and the perturbations, and proves the rate it uses.
"""

from __future__ import annotations

import argparse

import numpy as np
import scipy.linalg

import urpc
from urpc.control.delay_form import SectorRanges, common_form, per_mode_radius


def sector_ranges(
    robot_name: str, configurations: int, seed: int, locked: tuple[str, ...] = ()
) -> tuple[float, float, float]:
    """``(b0, h1, h2)`` of the module docstring, over random configurations of the robot's
    shipped box (the law's ``M_L`` for ``b0``; the box's bounds for ``h1``, ``h2``), the
    ``locked`` joints locked."""
    from urpc.model.inertia_bounds import InertiaBounds

    robot = urpc.load_robot(robot_name, locked_joints=locked)
    box = urpc.load_uncertainty(robot_name, robot)
    nominal = box.nominal_robot(robot)
    law = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3).inertia_bounds
    bounds = InertiaBounds(robot, box)
    rng = np.random.default_rng(seed)
    lower, upper = robot.position_limits
    lower, upper = np.maximum(lower, -3.0), np.minimum(upper, 3.0)
    b0, h1, h2 = np.inf, np.inf, 0.0
    for _ in range(configurations):
        q = rng.uniform(lower, upper)
        M0 = nominal.M(q)
        b0 = min(b0, scipy.linalg.eigh(law.lower(q), M0, eigvals_only=True)[0])
        h1 = min(h1, scipy.linalg.eigh(M0, bounds.upper_robot.M(q), eigvals_only=True)[0])
        h2 = max(h2, scipy.linalg.eigh(M0, bounds.lower_robot.M(q), eigvals_only=True)[-1])
    return float(b0), float(h1), float(h2)


def frozen_radius(
    robot_name: str, configurations: int, seed: int, locked: tuple[str, ...] = ()
) -> float:
    """The largest spectral radius of the delayed loop itself, ``[[1, -T M^-1 K], [1, -T M0^-1
    K]]`` at ``T K = M_L``, frozen at random configurations on every vertex of the box (the
    first, the last and 30 random ones when it has more than 32): each plant and configuration
    alone, which the common form must also contract."""
    robot = urpc.load_robot(robot_name, locked_joints=locked)
    box = urpc.load_uncertainty(robot_name, robot)
    nominal = box.nominal_robot(robot)
    law = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3).inertia_bounds
    rng = np.random.default_rng(seed)
    lower, upper = robot.position_limits
    lower, upper = np.maximum(lower, -3.0), np.minimum(upper, 3.0)
    count = 2**box.n_uncertain
    vertices = range(count) if count <= 32 else [0, count - 1, *rng.integers(0, count, 30)]
    n, worst = robot.dof, 0.0
    for vertex in vertices:
        plant = box.plant(robot, box.vertex(int(vertex)))
        for _ in range(configurations):
            q = rng.uniform(lower, upper)
            TK = law.lower(q)
            loop = np.block(
                [
                    [np.eye(n), -np.linalg.solve(plant.M(q), TK)],
                    [np.eye(n), -np.linalg.solve(nominal.M(q), TK)],
                ]
            )
            worst = max(worst, float(np.max(np.abs(np.linalg.eigvals(loop)))))
    return worst


def largest_ratio(form, dof: int = 6, draws: int = 2000, seed: int = 1) -> float:
    """The largest ``V(z+, y+) / V(z, y)`` over random symmetric ``A``, ``H`` with unrelated
    eigenvectors (half of them with every eigenvalue at an end of its range) that the coupling
    admits (``A^1/2 H^2 A^1/2 <= 1 / c``; the others are drawn again)."""
    rng = np.random.default_rng(seed)
    X = form.X
    a1, a2, h1, h2, c = (getattr(form.ranges, k) for k in ("a1", "a2", "h1", "h2", "c"))

    def symmetric(low, high, ends):
        basis, _ = np.linalg.qr(rng.normal(size=(dof, dof)))
        values = rng.choice([low, high], dof) if ends else rng.uniform(low, high, dof)
        return (basis * values) @ basis.T

    def V(z, y):
        return X[0, 0] * z @ z + 2 * X[0, 1] * z @ y + X[1, 1] * y @ y

    worst, k = 0.0, 0
    while k < draws:
        A, H = symmetric(a1, a2, k % 2 == 0), symmetric(h1, h2, k % 2 == 0)
        root = np.linalg.cholesky(A)
        if c * np.linalg.eigvalsh(root.T @ H @ H @ root)[-1] > 1.0:
            continue
        k += 1
        z, y = rng.normal(size=dof), rng.normal(size=dof)
        worst = max(worst, V(z - H @ A @ y, z - A @ y) / V(z, y))
    return worst


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", help="a robot with a shipped box (urpc robots)")
    parser.add_argument("--configurations", type=int, default=40, help="sampled (40)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--lock", default="", help="comma-separated joints to lock (none)")
    parser.add_argument(
        "--fractions", default="1", help="comma-separated s of T K = s M_L (default 1: dead-beat)"
    )
    args = parser.parse_args(argv)
    locked = tuple(j.strip() for j in args.lock.split(",") if j.strip())
    b0, h1, h2 = sector_ranges(args.robot, args.configurations, args.seed, locked)
    print(
        f"{args.robot} ({args.configurations} configurations): b0 = {b0:.3f}, H in "
        f"[{h1:.3f}, {h2:.3f}]; the frozen loops of the box's vertices at the ceiling, largest "
        f"radius {frozen_radius(args.robot, 10, args.seed, locked):.3f}"
    )
    for s in (float(v) for v in args.fractions.split(",") if v.strip()):
        ranges = SectorRanges(s * b0, s, h1, h2, b0)
        form = common_form(ranges)
        modes = per_mode_radius(ranges)
        if form is None:
            print(f"  T K = {s:g} M_L: no common form proved (per-mode radius {modes:.3f})")
            continue
        print(
            f"  T K = {s:g} M_L: common rate rho = {form.rate:.3f} (per-mode radius "
            f"{modes:.3f}); X = [[1, {form.x12:.3f}], [{form.x12:.3f}, {form.x22:.3f}]], "
            f"t = ({form.t[0]:.3f}, {form.t[1]:.3f}, {form.t[2]:.3f}); largest V+/V over 2000 "
            f"random draws {largest_ratio(form):.3f} <= rho^2 = {form.rate**2:.3f}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
