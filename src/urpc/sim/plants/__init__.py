"""Plants: the true robot, integrated under a torque held constant over each control period.

A :class:`Plant` holds the state ``(q, qd)`` of a fixed-base arm and advances it under a
zero-order-hold torque: :meth:`Plant.step` keeps ``tau`` constant over ``duration`` [s] and
integrates

    M(q) qdd + C(q, qd) qd + g(q) = tau

with classical Runge-Kutta 4 in steps of at most ``max_step`` [s]. Two backends:

* :class:`PinocchioPlant`: accelerations from Pinocchio's articulated-body algorithm on the
  :class:`~urpc.model.robot.Robot` (the reference plant of urpc).
* :class:`MujocoPlant`: an independent plant. MuJoCo compiles the robot's URDF itself (its own
  parser for joint origins, axes and fixed links), then every body receives the inertia the
  :class:`~urpc.model.robot.Robot` gives its URDF link, so true parameters and payloads are honored.
  ``mujoco`` is an optional dependency (``pip install 'urpc[mujoco]'``).

Build a plant with :func:`make_plant`; ``docs/plants.md`` gives the measured agreement.

Modules: ``plant`` (the interface), ``pinocchio_plant``, ``mujoco_plant``, ``mujoco_model`` (the
MuJoCo model of a robot) and ``factory`` (:func:`make_plant`).
"""

from .factory import PLANTS, make_plant
from .mujoco_model import build_mujoco_model, import_mujoco, mujoco_joint_indices
from .mujoco_plant import MujocoPlant
from .pinocchio_plant import PinocchioPlant
from .plant import DEFAULT_MAX_STEP, Plant, PlantKind, PlantState

__all__ = [
    "DEFAULT_MAX_STEP",
    "PLANTS",
    "MujocoPlant",
    "PinocchioPlant",
    "Plant",
    "PlantKind",
    "PlantState",
    "build_mujoco_model",
    "import_mujoco",
    "make_plant",
    "mujoco_joint_indices",
]
