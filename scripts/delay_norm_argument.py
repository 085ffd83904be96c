"""Why norms cannot certify the delayed law (docs/robot.md §7): the spectral radius of the norm
recursion of the two-step delayed loop at the dead-beat ceiling, over plants of the box.

    python scripts/delay_norm_argument.py rr_planar
    python scripts/delay_norm_argument.py ur5 --vertices 32 --configurations 20

In the plant's metric, with ``A = T M^-1/2 K M^-1/2`` (``T K = M_L``, the law's lower inertia bound)
and the prediction's ``A0 = T M^1/2 M0^-1 K M^-1/2``, the state and the prediction's error obey
``z+ = (1 - A) z - A p``, ``p+ = (A - A0)(z + p)``; bounded by norms, the recursion
``[[1 - a, ||A||], [||A - A0||, ||A - A0||]]`` (``a = 1 - ||1 - A||``) must have a spectral
radius below 1 for a norm argument to contract. Every vertex when the box has at most 64, else the
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
    worst = (0.0, None)
    for vertex in vertices:
        plant = box.plant(robot, box.vertex(vertex))
        for _ in range(args.configurations):
            q = rng.uniform(lower, upper)
            M, M0, ML = plant.M(q), nominal.M(q), bounds.lower(q)
            root, inverse_root = _roots(M)
            A = inverse_root @ ML @ inverse_root
            A0 = root @ np.linalg.solve(M0, ML) @ inverse_root
            a = 1.0 - np.linalg.norm(np.eye(len(q)) - A, 2)
            norm_A, norm_D = np.linalg.norm(A, 2), np.linalg.norm(A - A0, 2)
            radius = max(abs(np.linalg.eigvals([[1 - a, norm_A], [norm_D, norm_D]])))
            if radius > worst[0]:
                worst = (radius, (vertex, a, norm_A, norm_D))
    radius, (vertex, a, norm_A, norm_D) = worst
    print(
        f"{args.robot}: {len(vertices)} vertices x {args.configurations} configurations; largest "
        f"spectral radius of the norm recursion {radius:.3f} (vertex {vertex}: a = {a:.3f}, "
        f"||A|| = {norm_A:.3f}, ||A - A0|| = {norm_D:.3f})"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
