"""The table of docs/sampled-data.md §5: the certificate of every shipped scenario, the demo arms
and the ``urpc init`` boxes of ur10, kinova and xarm7 at 1 kHz and 10 kHz (implicit law), each
next to the worst error observed under the worst-case disturbance.

    python scripts/sampled_data_table.py [--store FILE] [--only TEXT] [--plants N]

For each configuration: ``certified``, ``epsilon_floor``, ``max_sample_period``, the dominating
term and the certificate's CPU time; then ``N`` plants of the box (its first and last vertices,
then seeded draws) are simulated from the gains' ceiling with the disturbance at its bound,
against ``r`` in the ``M^-1`` metric (``disturbance="worst"``) and held along the lightest mode of
the law's ``M_L`` (``"lightest"``), and the largest ``||e||`` over the last quarter of each run is
reported (the floor must lie above it when certified). Each row is
written to an sqlite store (WAL) as soon as it is measured; a rerun skips the rows already there,
and Ctrl-C stops cleanly. The markdown table of every stored row is printed at the end.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sqlite3
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import urpc
from urpc.control.certificate import certify
from urpc.model.box_template import BoxTemplateSettings, box_template
from urpc.studies.certification import certify_setup
from urpc.studies.demo.settings import DEFAULT_CONFIGURATIONS, DISTURBANCE_BOUND, DURATION
from urpc.studies.demo.synthesis import synthesize_configuration
from urpc.studies.scenario import build, build_controller, load_scenario, shipped_scenarios

IMPLICIT = {"interval": {"sampled_law": "implicit"}}
PERIODS = (1e-3, 1e-4)
#: The ``urpc init`` boxes (default widths) and the disturbance bound their rows assume [N m].
INIT_ROBOTS = ("ur10", "kinova", "xarm7")
INIT_DISTURBANCE = 2.0
#: Simulated time of the worst-case runs [s] (at most the configuration's own duration).
RUN_SECONDS = 2.0


def _scenarios(names):
    for name in names:
        scenario = load_scenario(name).with_overrides(controller_options=IMPLICIT)
        for period in dict.fromkeys([scenario.sample_period, *PERIODS]):

            def make(scenario=scenario, period=period):
                setup = build(scenario.with_overrides(sample_period=period or "continuous"))
                return setup, build_controller(setup, "interval")

            yield name, period, ("scenario", make)


def _demo_arms():
    for configuration in DEFAULT_CONFIGURATIONS:
        for period in PERIODS:

            def make(configuration=configuration, period=period):
                arm = synthesize_configuration(configuration, repeats=1, sample_period=period)
                trajectory = urpc.generic_trajectory(arm.nominal)
                return arm.robot, arm.box, arm.controller, trajectory, DURATION, DISTURBANCE_BOUND

            yield f"demo {configuration}", period, ("arm", make)


def _init_boxes():
    for robot_name in INIT_ROBOTS:
        for period in PERIODS:

            def make(robot_name=robot_name, period=period):
                import yaml

                robot = urpc.load_robot(robot_name)
                text = box_template(robot, BoxTemplateSettings(), robot_source=robot_name)
                data = yaml.safe_load(text)
                data["disturbance"] = "unknown"  # Theorem 2's adaptive law, as the others
                box = urpc.parse_uncertainty(data, robot)
                controller = urpc.synthesize(robot, box, 1e-2, sample_period=period)
                trajectory = urpc.generic_trajectory(box.nominal_robot(robot))
                return robot, box, controller, trajectory, 2.0, INIT_DISTURBANCE

            yield f"{robot_name} (urpc init box)", period, ("arm", make)


def configurations():
    """``(label, period, (kind, make))``, the cheap rows first (the paper's arm, the UR5, the
    demo arms, the init boxes over 2 s), the Panda's 8 s references last."""
    names = sorted(shipped_scenarios())
    yield from _scenarios([n for n in names if not n.startswith("panda")])
    yield from _demo_arms()
    yield from _init_boxes()
    yield from _scenarios([n for n in names if n.startswith("panda")])


def measure(kind: str, make, plants: int) -> dict:
    start = time.process_time()
    if kind == "scenario":
        setup, controller = make()
        certificate = certify_setup(setup, controller)
        scenario = setup.scenario
        robot = urpc.load_robot(scenario.robot, locked_joints=scenario.locked_joints)
        box = setup.box  # its plants are built on the URDF's robot (payloads added)
        trajectory, duration = setup.trajectory, setup.scenario.duration
        disturbance = setup.scenario.disturbance
    else:
        robot, box, controller, trajectory, duration, disturbance = make()
        certificate = certify(
            controller, trajectory, duration=duration, disturbance_bound=disturbance
        )
    cpu = time.process_time() - start
    row = {
        "certified": certificate.certified,
        "floor": certificate.epsilon_floor,
        "max_period": certificate.max_sample_period,
        "term": certificate.figures.get("dominant_term"),
        "epsilon": certificate.epsilon,
        "cpu_s": cpu,
        "observed": None,
    }
    if controller.sample_period is None or not disturbance:
        return row  # continuous time, or no disturbance to push against r
    rng = np.random.default_rng(0)
    points = [box.vertex(0), box.vertex(2**box.n_uncertain - 1)]
    points += [box.sample(rng) for _ in range(max(0, plants - 2))]
    seconds = min(RUN_SECONDS, duration)
    saturated = None  # Theorem 1's law has no state; Theorem 2's starts at the ceiling
    if controller.n_states:
        saturated = np.array([(controller.phi_max - controller.phi_P) / controller.phi_I])
    worst = 0.0
    for point, model in itertools.product(points[:plants], ADVERSARIES):
        result = urpc.simulate(
            box.plant(robot, point), controller, trajectory, duration=seconds,
            q0=trajectory.reference(0.0).q, disturbance_bound=disturbance,
            disturbance=model, controller_state0=saturated,
        )  # fmt: skip
        keep = result.t >= 0.75 * seconds
        worst = max(worst, float(np.max(result.error_norm[keep])))
    row["observed"] = worst
    return row


#: The disturbances each plant runs under, at the bound (urpc.sim.sampled.DISTURBANCES):
#: against ``r`` in the plant's ``M^-1`` metric, and held along the lightest mode of the law's
#: ``M_L`` (the first vanishes where ``r = 0``); the row keeps the larger error.
ADVERSARIES = ("worst", "lightest")


def open_store(path: Path) -> sqlite3.Connection:
    path.parent.mkdir(parents=True, exist_ok=True)
    store = sqlite3.connect(path)
    store.execute("PRAGMA journal_mode=WAL")
    store.execute(
        "CREATE TABLE IF NOT EXISTS rows (label TEXT, period TEXT, row TEXT, "
        "PRIMARY KEY (label, period))"
    )
    return store


def _period(period: float | None) -> str:
    return "continuous" if period is None else f"{period * 1e3:g}"


def _number(x, scale: float = 1.0) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "none"
    return f"{x * scale:.3g}"


def table(store: sqlite3.Connection) -> str:
    lines = [
        "| configuration | epsilon [rad] | period [ms] | certified | epsilon_floor [rad] "
        "| max_sample_period [ms] | dominating term | worst observed [rad] | certify CPU [s] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for label, period, text in store.execute("SELECT label, period, row FROM rows ORDER BY rowid"):
        row = json.loads(text)
        lines.append(
            f"| {label} | {row['epsilon']:g} | {period} | {'yes' if row['certified'] else 'no'} "
            f"| {_number(row['floor'])} | {_number(row['max_period'], 1e3)} "
            f"| {row['term'] or '-'} | {_number(row['observed'])} | {row['cpu_s']:.1f} |"
        )
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = Path(tempfile.gettempdir()) / "urpc_sampled_data_table.sqlite"
    parser.add_argument("--store", type=Path, default=default, help=f"default {default}")
    parser.add_argument("--only", help="only the configurations whose label contains TEXT")
    parser.add_argument("--plants", type=int, default=3, help="worst-case runs per row")
    args = parser.parse_args()
    store = open_store(args.store)
    done = {(label, period) for label, period in store.execute("SELECT label, period FROM rows")}
    try:
        for label, period, (kind, make) in configurations():
            if args.only and args.only not in label:
                continue
            key = (label, _period(period))
            if key in done:
                continue
            print(f"{label} at {key[1]} ms ...", file=sys.stderr, flush=True)
            row = measure(kind, make, args.plants)
            with store:
                store.execute("INSERT INTO rows VALUES (?, ?, ?)", (*key, json.dumps(row)))
    except KeyboardInterrupt:
        print("interrupted: the rows measured so far are in the store", file=sys.stderr)
        print(table(store))
        return 130
    print(table(store))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
