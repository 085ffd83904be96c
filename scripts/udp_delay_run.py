"""A wall-clock run at the robot's rate through the UDP virtual robot with one sample of delay,
next to the sampled simulation of the same configuration with the same delay.

What it does (docs/robot.md §8 quotes its figures):

1. starts ``urpc virtual-robot ROBOT --delay 1 --true-params sample --seed S --disturbance D``
   on a free port: the scenario's true plant (its ``{sample: {seed: S}}`` draw) and its
   disturbance bound, the torque answering sample ``k`` applied over period ``k + 1``;
2. runs ``urpc run SCENARIO --delay 1 --late-budget B --json`` against it (the delayed law, the
   safety layer with the URDF's efforts, the watchdog), in wall-clock time, and keeps its JSON and
   the virtual robot's closing lines;
3. simulates the scenario in process (``urpc.simulate``) three ways: the delayed law behind one
   sample of actuation delay (the configuration of the wall-clock run), the undelayed law behind
   the same delay, and the undelayed law without delay.

    python scripts/udp_delay_run.py                          # ur5/sampled, 3 wall-clock runs
    python scripts/udp_delay_run.py --runs 1 --json
    python scripts/udp_delay_run.py --scenario rr_planar/s3_ic1 --robot rr_planar --seed 0

``--late-budget`` defaults to 100000 (the watchdog never stops the run for late cycles): on a
shared machine without real-time scheduling a 1 kHz Python loop misses deadlines, and the point
is to count them, not to stop at the fifth. The virtual robot's own watchdog stays on (20 ms,
``--watchdog-ms``).
A wall-clock figure is the machine's as much as urpc's: the script prints the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys

URPC = [sys.executable, "-m", "urpc"]


def wall_clock_run(args) -> dict:
    """One virtual robot and one ``urpc run`` against it; the run's JSON and the robot's lines."""
    robot = subprocess.Popen(
        [
            *URPC, "virtual-robot", args.robot, "--port", "0", "--delay", "1",
            "--true-params", "sample", "--seed", str(args.seed),
            "--disturbance", str(args.disturbance), "--wait", "120",
            "--watchdog-ms", str(args.watchdog_ms),
        ],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        ready = robot.stdout.readline()
        match = re.search(r"ready on (udp://127\.0\.0\.1:\d+)", ready)
        if not match:
            raise SystemExit(f"the virtual robot did not start: {ready}{robot.stderr.read()}")
        command = [
            *URPC, "run", args.scenario, "--robot-address", match.group(1), "--delay", "1",
            "--late-budget", str(args.late_budget), "--json",
        ]  # fmt: skip
        if args.duration is not None:
            command += ["--duration", str(args.duration)]
        done = subprocess.run(command, capture_output=True, text=True, timeout=600)
        if not done.stdout.strip():
            raise SystemExit(f"urpc run printed nothing: {done.stderr}")
        summary = json.loads(done.stdout)
        out, _ = robot.communicate(timeout=60)
    finally:
        if robot.poll() is None:
            robot.kill()
            robot.wait()
    summary["virtual_robot"] = [
        line.removeprefix("virtual-robot: ") for line in [ready.strip(), *out.splitlines()]
    ]
    return summary


def simulated(args) -> dict:
    """Final errors [rad] of the scenario simulated with and without the delay, each law."""
    from urpc.studies.scenario import build, build_controller, load_scenario, simulate_setup

    base = load_scenario(args.scenario)
    if args.duration is not None:
        base = base.with_overrides(duration=args.duration)
    runs = {
        "delayed law, actuation delay 1": (1, 1),
        "undelayed law, actuation delay 1": (0, 1),
        "undelayed law, no delay": (0, 0),
    }
    figures = {}
    for label, (law, plant) in runs.items():
        scenario = base.with_overrides(
            controller_options={"interval": {"delay": law}}, actuation_delay=plant
        )
        setup = build(scenario)
        result = simulate_setup(setup, build_controller(setup))
        metrics = result.metrics
        figures[label] = {
            "met": metrics["met"],
            "final_error": metrics["final_error"],
            "epsilon": scenario.epsilon,
            "actuation_delay": result.info["actuation_delay"],
        }
    return figures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="ur5/sampled")
    parser.add_argument("--robot", default="ur5", help="the scenario's robot, for the arm")
    parser.add_argument(
        "--seed", type=int, default=1, help="the seed of the scenario's true-plant draw (1)"
    )
    parser.add_argument(
        "--disturbance", type=float, default=2.0, help="the scenario's ||d|| bound [N m] (2)"
    )
    parser.add_argument("--duration", type=float, help="default: the scenario's")
    parser.add_argument("--runs", type=int, default=3, help="wall-clock runs (3)")
    parser.add_argument("--late-budget", type=int, default=100000)
    parser.add_argument(
        "--watchdog-ms",
        type=float,
        default=20.0,
        help="the virtual robot's own watchdog: it brakes after this long without a torque "
        "[ms] (20, as real arms do; raise it on a loaded machine to count late cycles rather "
        "than stop at the first long stall)",
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    load = os.getloadavg()
    runs = []
    for k in range(args.runs):
        print(f"wall-clock run {k + 1}/{args.runs} ...", file=sys.stderr, flush=True)
        runs.append(wall_clock_run(args))
    print("simulating ...", file=sys.stderr, flush=True)
    simulation = simulated(args)
    document = {
        "scenario": args.scenario,
        "load_average": [load, os.getloadavg()],
        "wall_clock": runs,
        "simulated": simulation,
    }
    if args.json:
        print(json.dumps(document, indent=2))
        return 0
    print(
        f"{args.scenario}: load average {load[0]:.2f} at the start, "
        f"{document['load_average'][1][0]:.2f} at the end"
    )
    print("wall clock (delayed law, virtual robot --delay 1):")
    for run in runs:
        final = run.get("final_error")
        shown = "no result" if final is None else f"{final:.3g} rad (epsilon {run['epsilon']:g})"
        print(
            f"  {run['ending']}: {run['cycles']} cycles, {run['deadline_misses']} late "
            f"({100 * run['deadline_miss_rate']:.2f} %), worst response "
            f"{run['worst_response_ms']:.1f} ms, {run['lost_samples']} samples overtaken, "
            f"{run['safety_interventions']} safety interventions, final error {shown}, "
            f"step p50 {run['step_time'].get('p50', float('nan')) * 1e6:.0f} us"
        )
        print(f"    robot: {run['virtual_robot'][-1]}")
        if run["message"]:
            print(f"    {run['message']}")
    print("simulated (urpc.simulate, same scenario):")
    for label, figures in simulation.items():
        print(
            f"  {label}: final error {figures['final_error']:.3g} rad "
            f"(epsilon {figures['epsilon']:g}), {'met' if figures['met'] else 'NOT met'}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
