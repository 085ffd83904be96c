"""Wall-time figures of whole jobs: simulation speed, synthesis time, campaign throughput."""

from __future__ import annotations

import gc
import statistics
import time

from ...model.robot import load_robot
from ...model.uncertainty import load_uncertainty
from .control_step import control_scenario


def simulation_speed(scenario_name: str, duration: float | None = None) -> float:
    """Simulated seconds per wall second of one run of a scenario (``duration``: overrides the
    scenario's [s]); the wall time of :func:`urpc.studies.scenario.simulate_setup` alone."""
    from ..scenario import build, build_controller, load_scenario, simulate_setup

    scenario = load_scenario(scenario_name).with_overrides(duration=duration)
    setup = build(scenario)
    controller = build_controller(setup)
    gc.collect()
    start = time.perf_counter()
    simulate_setup(setup, controller)
    return scenario.duration / (time.perf_counter() - start)


def synthesis_time(robot_name: str, repeats: int = 7) -> float:
    """Median wall time [s] of ``load_robot + load_uncertainty + synthesize`` with the settings
    of the robot's :data:`CONTROL_SCENARIOS` entry (after one untimed warm-up run)."""
    from ...control.synthesis import synthesize
    from ..scenario import interval_synthesis_options, load_scenario

    scenario = load_scenario(control_scenario(robot_name))
    options = interval_synthesis_options(scenario)

    def chain() -> None:
        robot = load_robot(scenario.robot, scenario.locked_joints)
        box = load_uncertainty(scenario.uncertainty, robot)
        synthesize(robot, box, scenario.epsilon, **options)

    chain()  # warm-up: imports and the example-robot-data lookup happen once per process
    samples = []
    for _ in range(repeats):
        gc.collect()
        start = time.perf_counter()
        chain()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def assembly_synthesis_time(name: str, repeats: int) -> float:
    from ..demo import synthesize_configuration

    return synthesize_configuration(name, repeats=repeats).timing.total


def campaign_throughput(
    scenario_name: str, runs: int, workers: int = 2, duration: float | None = None
) -> float:
    """Runs per minute of :func:`urpc.studies.campaign.run_campaign` (wall time, process start-up
    included); ``duration`` overrides the scenario's [s]."""
    from ..campaign import run_campaign
    from ..scenario import load_scenario

    scenario = load_scenario(scenario_name).with_overrides(duration=duration)
    start = time.perf_counter()
    result = run_campaign(scenario, runs, workers=workers, seed=0)
    return 60.0 * result.runs / (time.perf_counter() - start)
