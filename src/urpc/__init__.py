"""urpc: ultimate robust performance control of robot arms with interval-uncertain dynamics.

The main entry points::

    robot = urpc.load_robot("rr_planar")                    # Pinocchio model + per-link data
    box = urpc.load_uncertainty("uncertainty.yaml", robot)   # the parameter box
    bound = urpc.make_bound("vertex", robot, box)            # enclosure of the mismatch torque
"""

from .bounds import METHODS as BOUND_METHODS
from .bounds import BoundMethod, default_method, make_bound
from .control.interval import IntervalPassivityController
from .control.synthesis import synthesize
from .errors import InputError, SimulationError, UrpcError
from .model.modular import Assembly, assemble, load_assembly, load_module_library
from .model.robot import Robot, load_robot
from .model.uncertainty import (
    ParameterBox,
    load_parameter_point,
    load_uncertainty,
    parse_uncertainty,
)
from .sim.metrics import METRIC_NAMES
from .sim.results import SimulationResult
from .sim.simulation import simulate

__version__ = "0.1.0"

__all__ = [
    "BOUND_METHODS",
    "Assembly",
    "BoundMethod",
    "InputError",
    "ParameterBox",
    "Robot",
    "SimulationError",
    "UrpcError",
    "default_method",
    "load_parameter_point",
    "load_robot",
    "load_uncertainty",
    "make_bound",
    "parse_uncertainty",
    "__version__",
    "IntervalPassivityController",
    "METRIC_NAMES",
    "SimulationResult",
    "simulate",
    "synthesize",
    "assemble",
    "load_assembly",
    "load_module_library",
]
