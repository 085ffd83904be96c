"""The reference plant: RK4 on accelerations from Pinocchio's articulated-body algorithm."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...model.robot import Robot
from .plant import DEFAULT_MAX_STEP, Plant


class PinocchioPlant(Plant):
    """Classical RK4 on ``x = (q, qd)``, ``xd = (qd, ABA(q, qd, tau))`` (Pinocchio).

    One step of ``h``: ``k1 = f(x)``, ``k2 = f(x + h/2 k1)``, ``k3 = f(x + h/2 k2)``,
    ``k4 = f(x + h k3)``, ``x <- x + h/6 (k1 + 2 k2 + 2 k3 + k4)``; the error is ``O(h^4)``.
    """

    kind = "pinocchio"

    def __init__(self, robot: Robot, max_step: float = DEFAULT_MAX_STEP):
        super().__init__(robot, max_step)
        self._data = robot.model.createData()
        model = robot.model
        self._configuration = (lambda q: q) if model.nq == model.nv else robot.configuration

    def _load_state(self) -> None:
        """Nothing to do: the state lives in ``self._q, self._qd``."""

    def _advance(self, tau: np.ndarray, h: float, substeps: int) -> tuple[np.ndarray, np.ndarray]:
        model, data, configuration, aba = self.robot.model, self._data, self._configuration, pin.aba
        half, sixth = 0.5 * h, h / 6.0
        q, v = self._q, self._qd
        for _ in range(substeps):
            a1 = aba(model, data, configuration(q), v, tau)
            v2 = v + half * a1
            a2 = aba(model, data, configuration(q + half * v), v2, tau)
            v3 = v + half * a2
            a3 = aba(model, data, configuration(q + half * v2), v3, tau)
            v4 = v + h * a3
            a4 = aba(model, data, configuration(q + h * v3), v4, tau)
            q = q + sixth * (v + 2.0 * (v2 + v3) + v4)
            v = v + sixth * (a1 + 2.0 * (a2 + a3) + a4)
        return q, v
