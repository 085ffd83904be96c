"""An independent plant: the same arm simulated by MuJoCo (optional dependency)."""

from __future__ import annotations

import numpy as np

from ...model.robot import Robot
from ...validation import finite_vector
from .mujoco_model import build_mujoco_model, import_mujoco, mujoco_joint_indices
from .plant import DEFAULT_MAX_STEP, Plant


class MujocoPlant(Plant):
    """The same arm simulated by MuJoCo (model from :func:`build_mujoco_model`).

    MuJoCo's own RK4 (``mjINT_RK4``) advances the state with the torque applied as
    ``qfrc_applied``; with hinge and slide joints it is the same classical RK4 as
    :class:`PinocchioPlant`, so the two plants differ only by the dynamics algorithms
    (and their rounding), not by the integration scheme.

    Attributes:
        model: The compiled ``mujoco.MjModel``.
        data: The ``mujoco.MjData`` holding the simulated state.
    """

    kind = "mujoco"

    def __init__(self, robot: Robot, max_step: float = DEFAULT_MAX_STEP):
        super().__init__(robot, max_step)
        self._mujoco = import_mujoco()
        self.model = build_mujoco_model(robot)
        self.data = self._mujoco.MjData(self.model)
        self._query = self._mujoco.MjData(self.model)
        self._qpos_index, self._dof_index = mujoco_joint_indices(self.model, robot)
        self._load_state()

    def _load_state(self) -> None:
        self._mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self._qpos_index] = self._q
        self.data.qvel[self._dof_index] = self._qd

    def _advance(self, tau: np.ndarray, h: float, substeps: int) -> tuple[np.ndarray, np.ndarray]:
        self.model.opt.timestep = h
        self.data.qfrc_applied[self._dof_index] = tau
        self._mujoco.mj_step(self.model, self.data, substeps)
        return self.data.qpos[self._qpos_index].copy(), self.data.qvel[self._dof_index].copy()

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """MuJoCo's joint-space inertia matrix [kg m^2] at ``q``, in Pinocchio's joint order."""
        mj, data = self._mujoco, self._query
        data.qpos[self._qpos_index] = finite_vector("q", q, self.dof)
        mj.mj_forward(self.model, data)
        full = np.zeros((self.model.nv, self.model.nv))
        mj.mj_fullM(self.model, data, full)
        return full[np.ix_(self._dof_index, self._dof_index)]

    def bias_forces(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """MuJoCo's ``C(q, qd) qd + g(q)`` [N m or N] (``qfrc_bias``), in Pinocchio's order."""
        mj, data = self._mujoco, self._query
        data.qpos[self._qpos_index] = finite_vector("q", q, self.dof)
        data.qvel[self._dof_index] = finite_vector("qd", qd, self.dof)
        mj.mj_forward(self.model, data)
        return data.qfrc_bias[self._dof_index].copy()
