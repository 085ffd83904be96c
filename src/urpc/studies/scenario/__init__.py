"""Scenario files: everything one simulation run needs, in one YAML file.

Settings (:mod:`.settings`: :func:`load_scenario` validates a file into a frozen
:class:`Scenario`, the model of :mod:`urpc.formats.scenario`), building (:mod:`.setup`:
:func:`build` makes the robot, the box, the true plant, the trajectory and the initial state) and
running (:mod:`.run`: :func:`build_controller` synthesizes, :func:`run_scenario` simulates), each
separate from the others.
"""

from ...formats.scenario import Scenario
from .run import (
    build_controller,
    interval_synthesis_options,
    run_scenario,
    simulate_setup,
    true_parameter_values,
)
from .settings import (
    CONTROLLERS,
    PLANT_BACKENDS,
    SCENARIO_KEYS,
    load_scenario,
    parse_scenario,
    shipped_scenarios,
)
from .setup import ScenarioSetup, build, describe_point, sample_true_parameters

__all__ = [
    "CONTROLLERS",
    "PLANT_BACKENDS",
    "SCENARIO_KEYS",
    "Scenario",
    "ScenarioSetup",
    "build",
    "build_controller",
    "describe_point",
    "interval_synthesis_options",
    "load_scenario",
    "parse_scenario",
    "run_scenario",
    "sample_true_parameters",
    "shipped_scenarios",
    "simulate_setup",
    "true_parameter_values",
]
