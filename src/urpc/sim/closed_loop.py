"""What the sampled and the continuous-time simulation share: the closed loop's setup and the
divergence error."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..control.base import Controller
from ..errors import SimulationError
from ..model.robot import Robot
from ..trajectories import Trajectory
from .progress import SimulationProgress


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
