"""urpc: ultimate robust performance control of robot arms with interval-uncertain dynamics.

The main entry points::

    robot = urpc.load_robot("rr_planar")                    # Pinocchio model + per-link data
    box = urpc.load_uncertainty("rr_planar", robot)         # the parameter box (file or name)
    scenario = urpc.load_scenario("rr_planar/s2_ic1")       # a scenario (file or shipped name)
    bound = urpc.make_bound("vertex", robot, box)            # enclosure of the mismatch torque

``import urpc`` is cheap: each public name is imported from its module on first use (module
``__getattr__``, PEP 562), so a command line or a script pays for Pinocchio, SciPy and numba only
when it touches a name that needs them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from .errors import InputError, SimulationError, UrpcError

__version__ = "0.1.0"

#: Public name -> (module relative to this package, attribute in that module).
_LAZY = {
    "BOUND_METHODS": (".bounds", "METHODS"),
    "BoundMethod": (".bounds", "BoundMethod"),
    "default_method": (".bounds", "default_method"),
    "make_bound": (".bounds", "make_bound"),
    "Certificate": (".control.certificate", "Certificate"),
    "certify": (".control.certificate", "certify"),
    "Controller": (".control.base", "Controller"),
    "IntervalPassivityController": (".control.interval", "IntervalPassivityController"),
    "synthesize": (".control.synthesis", "synthesize"),
    "search_gains": (".control.gain_search", "search_gains"),
    "load_controller": (".control.controller_file", "load_controller"),
    "ControlLoop": (".robot.loop", "ControlLoop"),
    "SafetyLayer": (".robot.safety", "SafetyLayer"),
    "Watchdog": (".robot.watchdog", "Watchdog"),
    "RobotInterface": (".robot.interface", "RobotInterface"),
    "RobotState": (".robot.interface", "RobotState"),
    "run_on_robot": (".robot.runner", "run"),
    "FileTrajectory": (".trajectory_samples", "FileTrajectory"),
    "WaypointTrajectory": (".trajectory_moves", "WaypointTrajectory"),
    "StreamedReference": (".trajectory_moves", "StreamedReference"),
    "from_samples": (".trajectory_samples", "from_samples"),
    "load_samples": (".trajectory_files", "load_samples"),
    "identify": (".identify", "identify"),
    "Assembly": (".model.modular", "Assembly"),
    "assemble": (".model.modular", "assemble"),
    "load_assembly": (".model.modular", "load_assembly"),
    "load_module_library": (".model.modular", "load_module_library"),
    "Robot": (".model.robot", "Robot"),
    "load_robot": (".model.robot", "load_robot"),
    "ParameterBox": (".model.uncertainty", "ParameterBox"),
    "load_parameter_point": (".model.uncertainty", "load_parameter_point"),
    "ParameterPoint": (".model.point", "ParameterPoint"),
    "load_uncertainty": (".model.uncertainty", "load_uncertainty"),
    "parse_uncertainty": (".model.uncertainty", "parse_uncertainty"),
    "physically_consistent": (".model.parameter_point", "physically_consistent"),
    "sample_rigid_point": (".model.parameter_point", "sample_rigid_point"),
    "METRIC_NAMES": (".sim.metrics", "METRIC_NAMES"),
    "SimulationResult": (".sim.results", "SimulationResult"),
    "simulate": (".sim.simulation", "simulate"),
    "SolverOptions": (".sim.options", "SolverOptions"),
    "PaperTrajectory": (".trajectories", "PaperTrajectory"),
    "QuinticTrajectory": (".trajectories", "QuinticTrajectory"),
    "Reference": (".trajectories", "Reference"),
    "SinusoidTrajectory": (".trajectories", "SinusoidTrajectory"),
    "Trajectory": (".trajectories", "Trajectory"),
    "generic_trajectory": (".trajectories", "generic_trajectory"),
    "home_configuration": (".trajectories", "home_configuration"),
    "load_scenario": (".studies.scenario", "load_scenario"),
}

__all__ = [
    "BOUND_METHODS",
    "Assembly",
    "BoundMethod",
    "Certificate",
    "Controller",
    "InputError",
    "ParameterBox",
    "ParameterPoint",
    "Robot",
    "SimulationError",
    "UrpcError",
    "certify",
    "default_method",
    "load_parameter_point",
    "load_robot",
    "load_uncertainty",
    "make_bound",
    "parse_uncertainty",
    "physically_consistent",
    "sample_rigid_point",
    "__version__",
    "IntervalPassivityController",
    "METRIC_NAMES",
    "PaperTrajectory",
    "QuinticTrajectory",
    "Reference",
    "SinusoidTrajectory",
    "Trajectory",
    "generic_trajectory",
    "home_configuration",
    "SimulationResult",
    "SolverOptions",
    "simulate",
    "synthesize",
    "search_gains",
    "load_controller",
    "ControlLoop",
    "SafetyLayer",
    "Watchdog",
    "RobotInterface",
    "RobotState",
    "run_on_robot",
    "FileTrajectory",
    "WaypointTrajectory",
    "StreamedReference",
    "from_samples",
    "load_samples",
    "identify",
    "assemble",
    "load_assembly",
    "load_module_library",
    "load_scenario",
]


def __getattr__(name: str):
    """Import a public name from its module on first access, then cache it in the package."""
    try:
        module_name, attribute = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'urpc' has no attribute '{name}'") from None
    value = getattr(importlib.import_module(module_name, __name__), attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


if TYPE_CHECKING:  # static type checkers and IDEs see the eager imports
    from .bounds import METHODS as BOUND_METHODS
    from .bounds import BoundMethod, default_method, make_bound
    from .control.base import Controller
    from .control.certificate import Certificate, certify
    from .control.controller_file import load_controller
    from .control.gain_search import search_gains
    from .control.interval import IntervalPassivityController
    from .control.synthesis import synthesize
    from .identify import identify
    from .model.modular import Assembly, assemble, load_assembly, load_module_library
    from .model.point import ParameterPoint
    from .model.robot import Robot, load_robot
    from .model.uncertainty import (
        ParameterBox,
        load_parameter_point,
        load_uncertainty,
        parse_uncertainty,
    )
    from .robot.interface import RobotInterface, RobotState
    from .robot.loop import ControlLoop
    from .robot.runner import run as run_on_robot
    from .robot.safety import SafetyLayer
    from .robot.watchdog import Watchdog
    from .sim.metrics import METRIC_NAMES
    from .sim.options import SolverOptions
    from .sim.results import SimulationResult
    from .sim.simulation import simulate
    from .studies.scenario import load_scenario
    from .trajectories import (
        PaperTrajectory,
        QuinticTrajectory,
        Reference,
        SinusoidTrajectory,
        Trajectory,
        generic_trajectory,
        home_configuration,
    )
    from .trajectory_files import load_samples
    from .trajectory_moves import StreamedReference, WaypointTrajectory
    from .trajectory_samples import FileTrajectory, from_samples
