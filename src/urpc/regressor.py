"""The Slotine-Li regressor: ``M(q) qdd_a + C(q, qd) qd_a + g(q) = Y_SL(q, qd, qd_a, qdd_a) pi``.

``pi`` stacks the standard parameters of the moving bodies (Pinocchio order, 10 per joint body,
about the joint frame). ``C`` is the Christoffel-consistent Coriolis matrix, whose product
``C(q, v) w`` is the symmetric bilinear form polarizing ``c(q, x) = C(q, x) x``::

    C(q, v) w = (c(q, v + w) - c(q, v - w)) / 4

With Pinocchio's ``computeJointTorqueRegressor`` ``Y(q, v, a)`` (``Y pi = M a + c(q, v) + g``)
evaluated on two model copies carrying gravity ``+2 g`` and ``-2 g``::

    Y_SL = (Y_{+2g}(q, qd + qd_a, 2 qdd_a) - Y_{-2g}(q, qd - qd_a, -2 qdd_a)) / 4

(the accelerations and gravity add up to ``4 (M qdd_a + g)``, the velocity products to
``4 C(q, qd) qd_a``). Two regressor calls per control step.

A link fixed to body ``j`` by the placement ``X`` contributes ``A(X) pi_link`` to ``pi_j``, a linear
map of its own standard parameters (link frame); :func:`placement_matrix` builds ``A(X)``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .robot import Robot


class SlotineLiRegressor:
    """Evaluates ``Y_SL`` for one robot (keeps its own model copies and data buffers).

    Args:
        robot: The robot (only its kinematics matter; inertias are ignored by regressors).
    """

    def __init__(self, robot: Robot):
        self.robot = robot
        self._model_up = robot.model.copy()
        self._model_up.gravity.linear = 2.0 * np.asarray(robot.model.gravity.linear)
        self._model_down = robot.model.copy()
        self._model_down.gravity.linear = -2.0 * np.asarray(robot.model.gravity.linear)
        self._data_up = self._model_up.createData()
        self._data_down = self._model_down.createData()

    def __call__(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> np.ndarray:
        """``Y_SL`` [N m per unit parameter], shape ``(dof, 10 * dof)``."""
        config = self.robot.configuration(q)
        up = pin.computeJointTorqueRegressor(
            self._model_up, self._data_up, config, qd + qd_a, 2.0 * qdd_a
        )
        down = pin.computeJointTorqueRegressor(
            self._model_down, self._data_down, config, qd - qd_a, -2.0 * qdd_a
        )
        return 0.25 * (up - down)


def placement_matrix(placement: pin.SE3) -> np.ndarray:
    """The 10x10 matrix ``A`` with ``pi_body = A pi_link`` for a link at ``placement`` in the body
    frame (standard parameters, Pinocchio order). Exact up to rounding: ``Inertia.se3Action`` is
    linear in the standard parameters, so the columns are differences of two actions."""
    base = np.zeros(10)
    base[0] = 1.0
    acted_base = np.asarray(placement.act(pin.Inertia.FromDynamicParameters(base)).toDynamicParameters())
    A = np.empty((10, 10))
    for k in range(10):
        pi = base.copy()
        pi[k] += 1.0
        acted = placement.act(pin.Inertia.FromDynamicParameters(pi)).toDynamicParameters()
        A[:, k] = np.asarray(acted) - acted_base
    return A


def link_regressor_map(robot: Robot, links: list[str]) -> np.ndarray:
    """``(10 * dof, 10 * len(links))`` matrix ``B`` such that ``Y_SL @ B`` is the regressor of the
    named links' own standard parameters (each in its link frame), side by side."""
    B = np.zeros((10 * robot.dof, 10 * len(links)))
    for column, name in enumerate(links):
        link = robot.link(name)
        if link.joint_index == 0:
            raise ValueError(f"link '{name}' is fixed to the base and has no regressor")
        # Pinocchio's regressor columns follow joint order; body j sits at rows 10 (j-1).
        row = 10 * (link.joint_index - 1)
        B[row : row + 10, 10 * column : 10 * column + 10] = placement_matrix(link.placement)
    return B
