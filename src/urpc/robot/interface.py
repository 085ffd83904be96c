"""The robot protocol: what a control loop needs from a torque-controlled arm.

Three calls per cycle (``docs/robot.md``, "Running on a robot")::

    state = robot.read_state(timeout)     # block until the next sample, or None on timeout
    robot.send_torque(seq, tau)           # the torque answering that sample [N m]
    robot.stop()                          # end of run: brake the arm (also on every fault)

An adapter for an arm's own SDK implements these three methods and the two attributes; the UDP
client of the virtual robot (:class:`urpc.robot.udp.UdpRobot`) and the in-process lock-step robot
(:class:`urpc.robot.virtual.LockstepRobot`) are two implementations.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


@dataclass(frozen=True, eq=False)
class RobotState:
    """One sample of the arm.

    Attributes:
        seq: Sample number, +1 per robot period (a gap means samples were lost); it may wrap
            (the UDP packet's is 32 bits), so it is compared in serial-number arithmetic
            (:func:`urpc.robot.packet.seq_diff`), never with ``<``.
        t: The robot's time of the sample [s].
        q: Joint positions [rad or m].
        qd: Joint velocities [rad/s or m/s].
        received: Local (loop-side) clock reading when the sample arrived [s]; the watchdog
            measures the loop's response time from it.
        stopped: The robot reports that it braked the arm (its own watchdog or a fault).
    """

    seq: int
    t: float
    q: np.ndarray
    qd: np.ndarray
    received: float
    stopped: bool = False


@runtime_checkable
class RobotInterface(Protocol):
    """A torque-controlled arm driven at a fixed period."""

    #: Number of joints.
    dof: int
    #: The robot's control period [s].
    period: float

    def read_state(self, timeout: float) -> RobotState | None:
        """The next sample, waiting at most ``timeout`` [s]; ``None`` if none arrived. When
        several samples are queued, the newest is returned (older ones are stale)."""
        ...

    def send_torque(self, seq: int, tau: np.ndarray) -> None:
        """Command ``tau`` [N m or N] in answer to sample ``seq``."""
        ...

    def stop(self) -> None:
        """Brake the arm and end the session (idempotent)."""
        ...
