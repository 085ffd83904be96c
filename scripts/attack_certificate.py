"""Attack the certificate end to end: random configurations of the paper's RR arm, each
certified one run at all 8 vertices of Table I under the worst-case disturbance with the gains
started at the ceiling; a run ending above its floor is a soundness bug (exit status 1).

    python scripts/attack_certificate.py                 # 8 draws, seed 0
    python scripts/attack_certificate.py --seed 12 --draws 10

A draw picks the period (1 ms, 0.5 ms, 0.2 ms), Kr (10-45), epsilon (5e-3-2e-2), the
disturbance bound (2-10 N m) and a sinusoid reference (home, amplitude, frequency, phase). Each
row gives the floor, the worst vertex's error over the last 2 s of a 4 s run and their ratio.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import urpc
from urpc.trajectories import SinusoidTrajectory


def draw(rng: np.random.Generator):
    period = float(rng.choice([1e-3, 5e-4, 2e-4]))
    Kr = float(rng.choice([10.0, 20.0, 30.0, 45.0]))
    epsilon = float(rng.choice([5e-3, 1e-2, 2e-2]))
    d = float(rng.choice([2.0, 5.0, 10.0]))
    home = rng.uniform(-1.5, 1.5, 2) + np.array([math.pi / 2, 0.0])
    amplitude = rng.uniform(0.05, 0.6, 2)
    frequency = float(rng.uniform(0.1, 1.0))
    phase = rng.uniform(0.0, 6.28, 2)
    reference = SinusoidTrajectory(
        home=tuple(home), amplitude=tuple(amplitude), frequency=frequency, phase=tuple(phase)
    )
    label = (
        f"home {np.round(home, 2).tolist()}, A {np.round(amplitude, 2).tolist()}, "
        f"{frequency:.2f} Hz"
    )
    return period, Kr, epsilon, d, reference, label


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--draws", type=int, default=8, help="configurations (default 8)")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    print("| T [ms] | Kr | epsilon | d [N m] | reference | certified | floor | worst | ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    beaten = 0
    for _ in range(args.draws):
        period, Kr, epsilon, d, reference, label = draw(rng)
        controller = urpc.synthesize(robot, box, epsilon, sample_period=period, Kr=Kr)
        start = time.process_time()
        certificate = urpc.certify(controller, reference, duration=4.0, disturbance_bound=d)
        row = f"| {period * 1e3:g} | {Kr:g} | {epsilon:g} | {d:g} | {label} | "
        if not certificate.certified:
            print(row + f"no ({time.process_time() - start:.1f} s) | - | - | - |", flush=True)
            continue
        saturated = np.array([(controller.phi_max - controller.phi_P) / controller.phi_I])
        worst = 0.0
        for vertex in range(8):
            result = urpc.simulate(
                box.plant(robot, box.vertex(vertex)), controller, reference, duration=4.0,
                q0=reference.reference(0.0).q, disturbance_bound=d, disturbance="worst",
                controller_state0=saturated,
            )  # fmt: skip
            keep = result.t >= result.t[-1] - 2.0
            worst = max(worst, float(result.error_norm[keep].max()))
        floor = certificate.epsilon_floor
        beaten += worst > floor
        verdict = f"{floor / worst:.2f}" + (" BEATEN" if worst > floor else "")
        print(row + f"yes | {floor:.3g} | {worst:.3g} | {verdict} |", flush=True)
    return 1 if beaten else 0


if __name__ == "__main__":
    raise SystemExit(main())
