"""Running a controller against a true plant: plants (Pinocchio, MuJoCo), the simulator
(continuous time or sampled with zero-order hold), reference trajectories, metrics, result files
and plots."""

from ..names import PLANT_BACKENDS

__all__ = ["PLANT_BACKENDS"]
