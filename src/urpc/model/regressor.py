"""The Slotine-Li regressor: ``M(q) qdd_a + C(q, qd) qd_a + g(q) = Y_SL(q, qd, qd_a, qdd_a) pi``.

``pi`` stacks the standard parameters of the moving bodies (Pinocchio order, 10 per joint body,
about the joint frame). ``C`` is the Christoffel-consistent Coriolis matrix, whose product
``C(q, v) w`` is the symmetric bilinear form polarizing ``c(q, x) = C(q, x) x``::

    C(q, v) w = (c(q, v + w) - c(q, v - w)) / 4

Pinocchio's ``computeJointTorqueRegressor`` ``Y_g(q, v, a)`` (``Y_g pi = M a + c(q, v) + g``, for
gravity ``g``) is linear in ``(a, g)`` and quadratic in ``v``. Two calls, one on a model copy with
gravity ``4 g`` and one on a copy without gravity, give::

    4 Y_SL = Y_{4g}(q, qd + qd_a, 4 qdd_a) - Y_0(q, qd - qd_a, 0)

(the first call carries ``4 (M qdd_a + g)`` and ``c(qd + qd_a)``, the second only ``c(qd - qd_a)``;
their difference of velocity products is ``4 C(q, qd) qd_a``). The factors 4 are powers of two, so
they add no rounding. :meth:`SlotineLiRegressor.scaled` returns ``4 Y_SL`` without the final
scaling: the bound methods fold ``1/4`` into the matrices they precompute, which saves one array
operation per control step.

A link fixed to body ``j`` by the placement ``X`` contributes ``A(X) pi_link`` to ``pi_j``, a linear
map of its own standard parameters (link frame); :func:`placement_matrix` builds ``A(X)``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .robot import Robot


class SlotineLiRegressor:
    """Evaluates ``Y_SL`` for one robot (keeps its own model copies and data buffers).

    Args:
        robot: The robot (only its kinematics matter; inertias are ignored by regressors).
    """

    #: :meth:`scaled` returns ``SCALE * Y_SL``.
    SCALE = 4.0

    def __init__(self, robot: Robot):
        self.robot = robot
        gravity = np.asarray(robot.model.gravity.linear)
        self._model_gravity = robot.model.copy()
        self._model_gravity.gravity.linear = self.SCALE * gravity
        self._model_free = robot.model.copy()
        self._model_free.gravity.linear = np.zeros(3)
        self._data_gravity = self._model_gravity.createData()
        self._data_free = self._model_free.createData()
        self._zero = np.zeros(robot.dof)
        # Joint angles are the Pinocchio configuration unless a joint is continuous (cos, sin).
        self._configuration = None if robot.model.nq == robot.model.nv else robot.configuration

    def __call__(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> np.ndarray:
        """``Y_SL`` [N m per unit parameter], shape ``(dof, 10 * dof)``.

        Args:
            q: Joint positions [rad or m].
            qd: Joint velocities [rad/s or m/s].
            qd_a: The controller's reference velocity ``qd_d + Kr e`` [rad/s or m/s].
            qdd_a: The controller's reference acceleration ``qdd_d + Kr ed`` [rad/s^2 or m/s^2].
        """
        Y = self.scaled(q, qd, qd_a, qdd_a)
        Y *= 1.0 / self.SCALE
        return Y

    def scaled(
        self,
        q: np.ndarray,
        qd: np.ndarray,
        qd_a: np.ndarray,
        qdd_a: np.ndarray,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """``SCALE * Y_SL`` (exactly, the scale is a power of two), written into ``out`` if given.

        The fast path of the bound methods, which fold ``1 / SCALE`` into their own matrices.
        """
        try:
            config = q if self._configuration is None else self._configuration(q)
            with_gravity = pin.computeJointTorqueRegressor(
                self._model_gravity, self._data_gravity, config, qd + qd_a, self.SCALE * qdd_a
            )
            free = pin.computeJointTorqueRegressor(
                self._model_free, self._data_free, config, qd - qd_a, self._zero
            )
        except (ValueError, TypeError, IndexError) as exc:
            # Only on failure (free on the fast path): say which vector has the wrong shape.
            raise _shape_error(self.robot, q=q, qd=qd, qd_a=qd_a, qdd_a=qdd_a) or exc from None
        # Pinocchio hands back a fresh copy, which can take the difference in place.
        return np.subtract(with_gravity, free, out=with_gravity if out is None else out)


def _shape_error(robot: Robot, **vectors) -> InputError | None:
    """An error naming the first state vector that is not ``dof`` finite numbers, if any."""
    for name, value in vectors.items():
        array = np.asarray(value)
        if array.shape != (robot.dof,):
            return InputError(
                f"{name} has shape {array.shape}, but {robot.name} has {robot.dof} joints "
                f"({', '.join(robot.joint_names)})",
                field=name,
            )
    return None


def placement_matrix(placement: pin.SE3) -> np.ndarray:
    """The 10x10 matrix ``A`` with ``pi_body = A pi_link`` for a link at ``placement`` in the body
    frame (standard parameters, Pinocchio order). Exact up to rounding: ``Inertia.se3Action`` is
    linear in the standard parameters, so the columns are differences of two actions. The identity
    placement gives exactly the identity matrix."""
    base = np.zeros(10)
    base[0] = 1.0
    acted_base = np.asarray(
        placement.act(pin.Inertia.FromDynamicParameters(base)).toDynamicParameters()
    )
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
