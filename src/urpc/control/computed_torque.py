"""Computed torque on the nominal model: the simple, non-robust reference controller.

With ``e = q_d - q`` and the nominal model ``M0, C0, g0``::

    u = M0(q) (qdd_d + Kd ed + Kp e) + C0(q, qd) qd + g0(q)                          [N m]

computed by one Pinocchio RNEA call. When the model is exact and there is no disturbance the
closed loop is the linear error dynamics ``e'' + Kd e' + Kp e = 0`` per joint, with
``Kp = omega_n^2`` and ``Kd = 2 zeta omega_n``. With a wrong model nothing is guaranteed.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..model.robot import Robot
from ..model.uncertainty import ParameterBox
from ..validation import positive_number
from .base import Controller, Reference, sample_period_of


class ComputedTorqueController(Controller):
    """Computed torque with PD error feedback (module docstring).

    Args:
        robot: The model the controller believes in (the nominal robot).
        natural_frequency: ``omega_n`` [rad/s] of the error dynamics, > 0.
        damping: Damping ratio ``zeta`` (1: critically damped), > 0.
        sample_period: Control period [s] the law runs at under a zero-order hold; ``None``
            (default): continuous time.

    Raises:
        InputError: a non-positive or non-finite gain.
    """

    name = "computed-torque"

    def __init__(
        self,
        robot: Robot,
        *,
        natural_frequency: float = 10.0,
        damping: float = 1.0,
        sample_period: float | None = None,
    ):
        for label, value in (("natural_frequency", natural_frequency), ("damping", damping)):
            positive_number(label, value, "a finite number > 0")
        self.robot = robot
        self.dof = robot.dof
        self.sample_period = sample_period_of(sample_period)
        self.natural_frequency = float(natural_frequency)
        self.damping = float(damping)
        self.Kp = self.natural_frequency**2  # [1/s^2]
        self.Kd = 2.0 * self.damping * self.natural_frequency  # [1/s]
        self._data = robot.model.createData()

    def output(
        self, t: float, q: np.ndarray, qd: np.ndarray, reference: Reference, state: np.ndarray
    ) -> np.ndarray:
        """``u = M0 (qdd_d + Kd ed + Kp e) + C0 qd + g0`` [N m]."""
        try:
            shape = (self.dof,)  # a one-entry vector would broadcast: refuse it
            if not (
                np.shape(reference.q) == np.shape(reference.qd) == np.shape(reference.qdd) == shape
            ):
                raise ValueError("the reference has the wrong size")
            acceleration = (
                reference.qdd + self.Kd * (reference.qd - qd) + self.Kp * (reference.q - q)
            )
            config = self.robot.configuration(np.asarray(q, dtype=float))
            return pin.rnea(self.robot.model, self._data, config, qd, acceleration).copy()
        except (ValueError, TypeError, IndexError, AttributeError) as exc:
            # Only on failure (free on the fast path): say which vector has the wrong size.
            raise self.state_error(q, qd, reference) or exc from None

    def __repr__(self) -> str:
        return (
            f"ComputedTorqueController(natural_frequency={self.natural_frequency:g}, "
            f"damping={self.damping:g})"
        )


def synthesize_computed_torque(
    robot: Robot,
    box: ParameterBox | None = None,
    *,
    natural_frequency: float = 10.0,
    damping: float = 1.0,
    sample_period: float | None = None,
) -> ComputedTorqueController:
    """Computed torque on the nominal model of ``robot`` and ``box`` (payloads attached at their
    nominal point); the box's intervals are ignored. ``sample_period`` [s] is the period the law
    runs at (``None``: continuous time)."""
    model = robot if box is None else box.nominal_robot(robot)
    return ComputedTorqueController(
        model, natural_frequency=natural_frequency, damping=damping, sample_period=sample_period
    )
