"""What the sampled and the continuous-time simulation share: the closed loop's setup and the
divergence error."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..control.base import Controller, Reference
from ..errors import SimulationError
from ..model.robot import Robot
from .progress import SimulationProgress


class Trajectory(Protocol):
    """Anything with ``reference(t) -> Reference`` (desired q [rad], qd [rad/s], qdd [rad/s^2])."""

    def reference(self, t: float) -> Reference: ...


@dataclass(frozen=True)
class RunSetup:
    """What both integrators need."""

    plant: Robot
    controller: Controller
    trajectory: Trajectory
    duration: float
    q0: np.ndarray
    qd0: np.ndarray
    state0: np.ndarray
    limit: np.ndarray | None
    max_state: float
    bar: SimulationProgress


def diverged(t: float, q: np.ndarray, qd: np.ndarray, reason: str):
    """Raise the :class:`~urpc.errors.SimulationError` naming the time [s], the reason and the
    state."""
    with np.printoptions(precision=6, threshold=20):
        raise SimulationError(
            f"the simulation diverged at t = {t:.6g} s ({reason}): q = {np.asarray(q)} rad, "
            f"qd = {np.asarray(qd)} rad/s"
        )
