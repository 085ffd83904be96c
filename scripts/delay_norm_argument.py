"""Why norms cannot certify the delayed law (docs/robot.md §7): the spectral radius of the norm
recursion of the two-step delayed loop at the dead-beat ceiling, over plants of the box.

    python scripts/delay_norm_argument.py rr_planar
    python scripts/delay_norm_argument.py ur5 --vertices 32 --configurations 20
    python scripts/delay_norm_argument.py ur5 --fractions 1,0.75,0.5,0.3

In the plant's metric, with ``A = T M^-1/2 K M^-1/2`` (``T K = M_L``, the law's lower inertia bound)
and the prediction's ``A0 = T M^1/2 M0^-1 K M^-1/2``, the state and the prediction's error obey
``z+ = (1 - A) z - A p``, ``p+ = (A - A0)(z + p)``; bounded by norms, the recursion
``[[1 - a, ||A||], [||A - A0||, ||A - A0||]]`` (``a = 1 - ||1 - A||``) must have a spectral
radius below 1 for a norm argument to contract. ``--fractions`` repeats it for a feedback held
below the dead-beat ceiling, ``T K = s M_L`` (``A``, ``A0`` and the recursion's entries scale with
``s``): the largest ``s`` whose radius is below 1 is what a delayed law capped there could
certify by norms, and ``1 - radius`` the contraction margin left for the period's other
perturbations (``b`` of docs/sampled-data.md §2). Every vertex when the box has at most 64, else the
first, the last and random ones; random configurations within the joint limits (clipped to +-3).
"""

from __future__ import annotations

import argparse

import numpy as np

import urpc


def _roots(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    w, V = np.linalg.eigh(M)
    return (V * np.sqrt(w)) @ V.T, (V / np.sqrt(w)) @ V.T


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", help="a robot with a shipped box (urpc robots)")
    parser.add_argument("--vertices", type=int, default=32, help="vertices when not all (32)")
    parser.add_argument("--configurations", type=int, default=20, help="per vertex (20)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--fractions", default="1", help="comma-separated s of T K = s M_L (default 1: dead-beat)"
    )
    args = parser.parse_args(argv)
    robot = urpc.load_robot(args.robot)
    box = urpc.load_uncertainty(args.robot, robot)
    nominal = box.nominal_robot(robot)
    bounds = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3).inertia_bounds
    rng = np.random.default_rng(args.seed)
    lower, upper = robot.position_limits
    lower, upper = np.maximum(lower, -3.0), np.minimum(upper, 3.0)
    count = 2**box.n_uncertain
    if count <= 64:
        vertices = list(range(count))
    else:
        vertices = [0, count - 1] + [int(v) for v in rng.integers(0, count, args.vertices - 2)]
    fractions = [float(x) for x in args.fractions.split(",") if x.strip()]
    worst = {s: (0.0, None) for s in fractions}
    for vertex in vertices:
        plant = box.plant(robot, box.vertex(vertex))
        for _ in range(args.configurations):
            q = rng.uniform(lower, upper)
            M, M0, ML = plant.M(q), nominal.M(q), bounds.lower(q)
            root, inverse_root = _roots(M)
            for s in fractions:
                A = s * (inverse_root @ ML @ inverse_root)
                A0 = s * (root @ np.linalg.solve(M0, ML) @ inverse_root)
                a = 1.0 - np.linalg.norm(np.eye(len(q)) - A, 2)
                norm_A, norm_D = np.linalg.norm(A, 2), np.linalg.norm(A - A0, 2)
                radius = max(abs(np.linalg.eigvals([[1 - a, norm_A], [norm_D, norm_D]])))
                if radius > worst[s][0]:
                    worst[s] = (radius, (vertex, a, norm_A, norm_D))
    print(f"{args.robot}: {len(vertices)} vertices x {args.configurations} configurations")
    for s in fractions:
        radius, (vertex, a, norm_A, norm_D) = worst[s]
        print(
            f"  T K = {s:g} M_L: largest spectral radius of the norm recursion {radius:.3f} "
            f"(margin {1 - radius:+.3f}; vertex {vertex}: a = {a:.3f}, ||A|| = {norm_A:.3f}, "
            f"||A - A0|| = {norm_D:.3f})"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
