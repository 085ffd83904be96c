"""The valid names of urpc's fixed sets, written once.

Every place that accepts or lists one of these names reads it from here: the scenario format
(its ``Literal`` types and JSON Schema), the command-line parser (its ``choices``), the
registries that map a name to its class (:data:`urpc.bounds.METHODS`,
:data:`urpc.sim.plants.PLANTS`) and the error messages. This module imports nothing, so the
command line lists the names without importing Pinocchio, MuJoCo or the controllers; the classes
behind a name are imported only when it is used.
"""

from __future__ import annotations

#: Controllers a scenario or ``urpc simulate --controller`` can run.
CONTROLLERS = ("interval", "r-alpha", "computed-torque")
#: Bound methods of the mismatch torque (:func:`urpc.make_bound`).
BOUND_METHODS = ("hull", "vertex", "rigorous")
#: Plants that integrate the true robot (:func:`urpc.sim.plants.make_plant`).
PLANT_BACKENDS = ("pinocchio", "mujoco")
#: Disturbances of a sampled run (:mod:`urpc.sim.sampled`): ``ball`` (drawn in the ball), and
#: three at the bound: ``against`` (against ``r``), ``worst`` (against ``r`` in the plant's
#: ``M^-1`` metric), ``lightest`` (along the lightest mode of the law's ``M_L``).
DISTURBANCE_MODELS = ("ball", "against", "worst", "lightest")
#: How a sampled interval controller runs: ``implicit`` (the certified sampled-data law of
#: :mod:`urpc.control.feedback`) or ``paper`` (the paper's law unchanged under the hold).
SAMPLED_LAWS = ("implicit", "paper")
#: The uniform error gains Kr [1/s] the certified synthesis of Kr tries
#: (:func:`urpc.search_gains`, ``urpc certify --search-kr``).
KR_CANDIDATES = (10.0, 15.0, 20.0, 30.0, 45.0, 60.0)
#: Reference trajectories of a scenario file (:mod:`urpc.trajectories`).
TRAJECTORY_KINDS = ("paper", "sinusoid", "quintic", "file", "waypoints")
#: Safe commands of the robot safety layer on a fault (:class:`urpc.robot.safety.SafetyLayer`,
#: ``urpc run --safe-mode``).
SAFE_MODES = ("zero", "damping")
#: Velocities a virtual robot sends (:class:`urpc.robot.virtual.ArmOptions`, ``urpc
#: virtual-robot --velocity``): the plant's, or the backward difference of the sent positions.
VELOCITY_MODES = ("measured", "difference")
