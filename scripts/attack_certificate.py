"""Attack the certificate end to end: random configurations of an arm, each certified one run at
vertices of its box (and interior plants) under two disturbances at their bound (against ``r``
in the ``M^-1`` metric, and along the lightest mode of the law's ``M_L``) with the gains started at
the ceiling; a run ending above its floor is a soundness bug (exit status 1).

    python scripts/attack_certificate.py                 # the RR arm, 8 draws, seed 0
    python scripts/attack_certificate.py --seed 12 --draws 10
    python scripts/attack_certificate.py --arm ur5 --seed 1 --draws 4
    python scripts/attack_certificate.py --arm panda --seed 1 --draws 6 --only 5
    python scripts/attack_certificate.py --arm ur5 --edge --seed 7 --draws 4
    python scripts/attack_certificate.py --arm chain4 --edge --duration 1

``--arm rr_planar`` (the paper's RR arm, Table I's box): a draw picks the period (1 ms, 0.5 ms,
0.2 ms), Kr (10-45), epsilon (5e-3-2e-2), the disturbance bound (2-10 N m) and a sinusoid
reference (home, amplitude, frequency, phase); every draw is run at all 8 vertices.

``--arm ur5`` (the box of ``ur5/sampled``: payload and wrist masses), ``--arm panda`` (the box
of ``panda/joint_friction``, fingers locked: payload, link masses and every joint's drive; its
payload-only box is certified only at periods of a few microseconds) and ``--arm arm_3dof``
(the 3-dof demo assembly and its box, built as ``urpc demo`` builds it): a draw picks the period (UR5, Panda:
0.1, 0.2, 0.3 ms; arm_3dof: 0.1, 0.5 ms), Kr (10-45), epsilon (1e-2, 2e-2), the disturbance
bound (1-5 N m) and a sinusoid reference: ``generic_trajectory`` about a random home inside the
joint limits (random amplitude fraction and base frequency, which it caps at the limits and
below the velocity limits), with random phases. Its box has too many vertices to run them all:
the first and last vertices, 14 others drawn at random and 2 interior plants drawn from the box
(``box.sample``). These rows add the plant that came closest and the draw's CPU time, and each
run that ends above its floor is described in full on stderr.

``--edge`` attacks the certificate where it is tightest: each draw is certified once at its
drawn period (doubled while the largest certified period it reports is the cap, twice the
period), then the period is redrawn between 0.7 and 0.97 times that largest certified period
(the floor then lies just below ``epsilon``), and the configuration is certified and run at
that period. ``--arm chainN`` is the ``N``-link chain of
``urpc bench certificate`` (``urpc.studies.benchmark.certificate_cost.chain_urdf``, every mass
+-10 %), drawn like the other generic arms (start it with ``--edge``: its largest periods are
tens of microseconds).

Each row gives the floor, the worst plant's error over the last half of the run (4 s, or
``--duration``) and their ratio; uncertified draws (reported "no", with the first failed
condition for the arms other than the RR arm) are not run. ``--only K`` reruns draw K of a seed
alone (the draws before it are drawn, not run).
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import urpc
from urpc.studies.benchmark.certificate_cost import benchmark_arm
from urpc.studies.demo.synthesis import synthesize_configuration
from urpc.studies.scenario import load_scenario
from urpc.studies.scenario.setup import describe_point
from urpc.trajectories import SinusoidTrajectory
from urpc.trajectory_generic import home_configuration

ARMS = ("rr_planar", "ur5", "panda", "arm_3dof", "chainN")
#: The shipped scenario whose robot (locked joints included) and box an arm is attacked with.
SCENARIOS = {"ur5": "ur5/sampled", "panda": "panda/joint_friction"}
#: The periods [s] drawn per arm (those its box is certified at, on the generic reference).
PERIODS = {"ur5": (1e-4, 2e-4, 3e-4), "panda": (1e-4, 2e-4, 3e-4), "arm_3dof": (1e-4, 5e-4)}
#: A chain's first period [s] (``--edge`` then moves it near its largest certified period).
CHAIN_PERIOD = 2e-5
#: ``--edge``: the period is redrawn in this fraction of the largest certified period.
EDGE_FRACTION = (0.7, 0.97)
#: ``--edge``: at most this many doublings of the period while the largest certified period
#: reaches the certificate's cap of twice the controller's period.
EDGE_DOUBLINGS = 4
#: The disturbances each plant is run under (urpc.sim.sampled.DISTURBANCES): at the bound
#: against ``r`` in the plant's ``M^-1`` metric, and at the bound along the lightest mode of the
#: law's ``M_L`` (the first vanishes where the arm follows the reference exactly).
ADVERSARIES = ("worst", "lightest")
#: Simulated (and certified) time [s]; the error is measured over its last half.
DURATION = 4.0
#: Vertices run per draw at most (all of them when the box has no more), and interior plants
#: drawn when it has more.
MAX_VERTICES = 16
INTERIOR = 2


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


def draw_generic(rng: np.random.Generator, arm: str, nominal):
    """A configuration of an arm other than the RR arm: its reference is a generic sinusoid
    (:func:`urpc.generic_trajectory`) about a random home with random phases, every drawn number
    rounded so that the label rebuilds it exactly."""
    period = CHAIN_PERIOD if is_chain(arm) else float(rng.choice(PERIODS[arm]))
    Kr = float(rng.choice([10.0, 20.0, 30.0, 45.0]))
    epsilon = float(rng.choice([1e-2, 2e-2]))
    d = float(rng.choice([1.0, 2.0, 5.0]))
    lower, upper = nominal.position_limits
    with np.errstate(invalid="ignore"):  # inf - inf on a continuous joint
        reach = np.where(np.isfinite(upper - lower), 0.3 * (upper - lower), 1.5)
    offset = rng.uniform(-1.0, 1.0, nominal.dof) * np.minimum(reach, 1.5)
    home = np.round(home_configuration(nominal) + offset, 2)
    fraction = round(float(rng.uniform(0.1, 0.5)), 2)
    frequency = round(float(rng.uniform(0.1, 0.6)), 2)
    phase = np.round(rng.uniform(0.0, 6.28, nominal.dof), 2)
    generic = urpc.generic_trajectory(
        nominal, home=home, amplitude_fraction=fraction, frequency=frequency
    )
    reference = SinusoidTrajectory(generic.home, generic.amplitude, generic.frequency, phase)
    label = f"home {home.tolist()}, fraction {fraction:g}, {frequency:g} Hz, phase {phase.tolist()}"
    return period, Kr, epsilon, d, reference, label


def plants(box, rng: np.random.Generator) -> list[tuple[str, object]]:
    """``(name, point)``: every vertex of a box with at most :data:`MAX_VERTICES`; else its first
    and last vertices, others drawn at random (bit ``k`` of a vertex's index picks the bound of
    the ``k``-th uncertain coordinate) and :data:`INTERIOR` plants drawn from the box."""
    n = box.n_uncertain
    if 2**n <= MAX_VERTICES:
        return [(f"vertex {i}", box.vertex(i)) for i in range(2**n)]
    indices = {0, 2**n - 1}
    while len(indices) < MAX_VERTICES:
        indices.add(sum(int(bit) << k for k, bit in enumerate(rng.integers(0, 2, n))))
    chosen = [(f"vertex {i}", box.vertex(i)) for i in sorted(indices)]
    return chosen + [(f"interior {k}", box.sample(rng)) for k in range(INTERIOR)]


def is_chain(arm: str) -> bool:
    return arm.startswith("chain") and arm[5:].isdigit() and int(arm[5:]) > 0


def load_arm(arm: str, folder: Path):
    """The URDF's robot (the plants are built on it) and the arm's box (a chain's URDF written
    in ``folder``)."""
    if is_chain(arm):
        return benchmark_arm(arm, folder)
    if arm == "rr_planar":
        robot = urpc.load_robot("rr_planar")
        return robot, urpc.load_uncertainty("rr_planar", robot)
    if arm in SCENARIOS:
        scenario = load_scenario(SCENARIOS[arm])
        robot = urpc.load_robot(scenario.robot, locked_joints=scenario.locked_joints)
        return robot, urpc.load_uncertainty(scenario.uncertainty, robot)
    assembly = synthesize_configuration(arm, repeats=1, sample_period=None)
    return assembly.robot, assembly.box


def main(argv=None) -> int:
    first, rest = __doc__.split("\n\n", 1)
    parser = argparse.ArgumentParser(
        description=" ".join(first.split()),
        epilog=rest,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--arm", default="rr_planar", help=f"one of {', '.join(ARMS)} (default rr_planar)"
    )
    parser.add_argument(
        "--edge", action="store_true", help="periods near the largest certified one (see below)"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--draws", type=int, default=8, help="configurations (default 8)")
    parser.add_argument(
        "--duration", type=float, default=DURATION, help="certified and run time [s] (default 4)"
    )
    parser.add_argument("--only", type=int, metavar="K", help="run only draw K (0-based)")
    args = parser.parse_args(argv)
    if args.arm not in ARMS[:-1] and not is_chain(args.arm):
        parser.error(f"--arm {args.arm}: valid: {', '.join(ARMS)} (N a positive integer)")
    rng = np.random.default_rng(args.seed)
    with tempfile.TemporaryDirectory() as folder:
        robot, box = load_arm(args.arm, Path(folder))
    nominal = box.nominal_robot(robot)
    duration = args.duration
    extended = args.arm != "rr_planar"  # the plant that came closest, the CPU time, the details
    header = "| T [ms] | Kr | epsilon | d [N m] | reference | certified | floor | worst | ratio |"
    if extended:
        header += " worst plant | CPU [s] |"
    print(header)
    print("|---" * header.count(" |") + "|")
    beaten = 0
    total = time.process_time()
    for k in range(args.draws if args.only is None else args.only + 1):
        drawn = draw_generic(rng, args.arm, nominal) if extended else draw(rng)
        period, Kr, epsilon, d, reference, label = drawn
        points = plants(box, rng)  # the RR arm's 8 vertices draw nothing
        fraction = rng.uniform(*EDGE_FRACTION) if args.edge else None
        if args.only is not None and k != args.only:
            continue
        controller = urpc.synthesize(robot, box, epsilon, sample_period=period, Kr=Kr)
        start = time.process_time()
        certificate = urpc.certify(controller, reference, duration=duration, disturbance_bound=d)
        for _ in range(EDGE_DOUBLINGS if fraction is not None else 0):
            # The largest period reported is at most twice the controller's: double it while
            # it reaches that cap.
            if certificate.max_sample_period < 2 * period * (1 - 1e-9):
                break
            period *= 2
            controller = urpc.synthesize(robot, box, epsilon, sample_period=period, Kr=Kr)
            certificate = urpc.certify(
                controller, reference, duration=duration, disturbance_bound=d
            )
        if fraction is not None and certificate.max_sample_period > 0:
            period = float(f"{fraction * certificate.max_sample_period:.3g}")
            controller = urpc.synthesize(robot, box, epsilon, sample_period=period, Kr=Kr)
            certificate = urpc.certify(
                controller, reference, duration=duration, disturbance_bound=d
            )
        row = f"| {period * 1e3:g} | {Kr:g} | {epsilon:g} | {d:g} | {label} | "
        if not certificate.certified:
            why = f": {certificate.failed[0].name}" if extended and certificate.failed else ""
            row += f"no{why} ({time.process_time() - start:.1f} s) | - | - | - |"
            print(row + (" - | - |" if extended else ""), flush=True)
            continue
        saturated = np.array([(controller.phi_max - controller.phi_P) / controller.phi_I])
        floor = certificate.epsilon_floor
        worst, closest = 0.0, ""
        for (name, point), model in itertools.product(points, ADVERSARIES):
            result = urpc.simulate(
                box.plant(robot, point), controller, reference, duration=duration,
                q0=reference.reference(0.0).q, disturbance_bound=d, disturbance=model,
                controller_state0=saturated,
            )  # fmt: skip
            keep = result.t >= result.t[-1] - duration / 2
            error = float(result.error_norm[keep].max())
            name = f"{name} ({model})"
            if error > worst:
                worst, closest = error, name
            if extended and error > floor:
                print(
                    f"BEATEN: --arm {args.arm}{' --edge' if args.edge else ''} --seed {args.seed} "
                    f"--only {k}: T = {period:g} s, "
                    f"Kr = {Kr:g}, epsilon = {epsilon:g}, d = {d:g} N m, duration {duration:g} s, "
                    f"{label}; reference amplitude {reference.amplitude.tolist()}, frequency "
                    f"{reference.frequency.tolist()}; {name} ({describe_point(box, point)}): "
                    f"||e|| = {error:.6g} over the last {duration / 2:g} s > floor {floor:.6g}",
                    file=sys.stderr,
                    flush=True,
                )
        beaten += worst > floor
        verdict = f"{floor / worst:.2f}" + (" BEATEN" if worst > floor else "")
        row += f"yes | {floor:.3g} | {worst:.3g} | {verdict} |"
        if extended:
            row += f" {closest} | {time.process_time() - start:.0f} |"
        print(row, flush=True)
    if extended:
        print(f"{time.process_time() - total:.0f} s of CPU", file=sys.stderr)
    return 1 if beaten else 0


if __name__ == "__main__":
    raise SystemExit(main())
