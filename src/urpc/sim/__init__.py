"""Running a controller against a true plant: plants (Pinocchio, MuJoCo), the simulator
(continuous time or sampled with zero-order hold), reference trajectories, metrics, result files
and plots."""

#: The plant backends (:data:`urpc.sim.plants.PLANTS`), named here so that the CLI can list them
#: without importing Pinocchio or MuJoCo.
PLANT_BACKENDS = ("pinocchio", "mujoco")
