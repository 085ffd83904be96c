"""The plant interface: the state ``(q, qd)`` of a fixed-base arm advanced under a torque held
constant over each step (zero-order hold), by classical RK4 in steps of at most ``max_step`` [s]."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Literal, NamedTuple

import numpy as np

from ...errors import SimulationError
from ...model.robot import Robot
from ...validation import finite_vector, positive_number

#: Default largest integration step [s]: ten RK4 steps per 1 kHz control period.
DEFAULT_MAX_STEP = 1e-4

PlantKind = Literal["pinocchio", "mujoco"]


class PlantState(NamedTuple):
    """Joint positions ``q`` [rad or m] and velocities ``qd`` [rad/s or m/s], length ``dof``."""

    q: np.ndarray
    qd: np.ndarray


class Plant(ABC):
    """A simulated arm driven by a torque held constant over each step (zero-order hold).

    Coordinates follow :class:`~urpc.model.robot.Robot`: ``dof`` joint angles [rad] or positions [m]
    in Pinocchio's joint order (a continuous joint is one unbounded angle).

    Args:
        robot: The true plant: a robot carrying the true inertial parameters.
        max_step: Largest integration step [s]; a step of ``duration`` is split into
            ``ceil(duration / max_step)`` equal RK4 steps.

    Attributes:
        robot: The robot being simulated.
        max_step: Largest integration step [s].
        time: Simulated time since the last :meth:`reset` [s].

    Raises:
        InputError: ``max_step`` is not a finite number > 0.
    """

    #: Backend name, as accepted by :func:`make_plant`.
    kind: str = ""

    def __init__(self, robot: Robot, max_step: float = DEFAULT_MAX_STEP):
        self.robot = robot
        self.max_step = positive_number("max_step", max_step, "a finite number > 0 [s]")
        self._q = np.zeros(robot.dof)
        self._qd = np.zeros(robot.dof)
        self.time = 0.0
        self._last_duration = math.nan
        self._last_substeps = 1

    @property
    def dof(self) -> int:
        """Number of joint coordinates."""
        return self.robot.dof

    @property
    def state(self) -> PlantState:
        """A copy of the current ``(q, qd)``."""
        return PlantState(self._q.copy(), self._qd.copy())

    def reset(self, q: np.ndarray, qd: np.ndarray | None = None) -> PlantState:
        """Set the state (``qd`` defaults to zero) and the time [s] to 0.

        Raises:
            InputError: a vector of the wrong length or with non-finite entries.
        """
        self._q = finite_vector("q", q, self.dof)
        self._qd = np.zeros(self.dof) if qd is None else finite_vector("qd", qd, self.dof)
        self.time = 0.0
        self._load_state()
        return self.state

    def step(self, torque: np.ndarray, duration: float) -> PlantState:
        """Hold ``torque`` [N m or N] constant over ``duration`` [s] and return the new state.

        Raises:
            InputError: a torque of the wrong length or non-finite, a duration that is not > 0.
            SimulationError: the state became non-finite (the plant diverged).
        """
        # The simulator calls this once per control period: validate cheaply (shape and one
        # finiteness test on dot products) and cache the substep count of the last duration.
        if (
            type(torque) is np.ndarray
            and torque.shape == (self.dof,)
            and math.isfinite(torque @ torque)
        ):
            tau = torque
        else:
            tau = finite_vector("torque", torque, self.dof)
        if duration != self._last_duration:
            duration = positive_number("duration", duration, "a finite number > 0 [s]")
            self._last_substeps = max(1, math.ceil(duration / self.max_step - 1e-9))
            self._last_duration = duration
        substeps = self._last_substeps
        q, qd = self._advance(tau, duration / substeps, substeps)
        if not math.isfinite(q @ q + qd @ qd):
            raise SimulationError(
                f"the {self.kind} plant diverged at t = {self.time + duration:.6g} s "
                f"(q = {np.round(q, 6).tolist()}, qd = {np.round(qd, 6).tolist()})"
            )
        self._q, self._qd = q, qd
        self.time += duration
        # Fresh arrays every step (not copies of internal buffers the next step reuses); the
        # caller must not modify them in place.
        return PlantState(q, qd)

    @abstractmethod
    def _load_state(self) -> None:
        """Copy ``self._q, self._qd`` into the backend (after :meth:`reset`)."""

    @abstractmethod
    def _advance(self, tau: np.ndarray, h: float, substeps: int) -> tuple[np.ndarray, np.ndarray]:
        """``substeps`` RK4 steps of ``h`` [s] from the current state under constant ``tau``."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.robot.name!r}, max_step={self.max_step:g})"
