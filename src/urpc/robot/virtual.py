"""The virtual robot: a plant that behaves like a torque-controlled arm.

:class:`VirtualArm` is the arm itself, with no clock and no socket: per period it measures
(encoder quantization, noise, velocity as measured or by finite differences), takes the torque
that applies (none, one sample of delay), adds a disturbance, integrates the plant over the
period and keeps its own watchdog: once armed by a first torque, the arm is **braked** (held still,
``qd = 0``, torque ignored) when no torque has arrived for ``watchdog_timeout`` (20 ms), as real
arms do. A torque with a non-finite entry is dropped and counted (:attr:`VirtualArm.rejected`;
the last torque holds, and the watchdog brakes the arm if no valid one follows); a torque beyond
the plant's effort limits (the URDF's, where finite) is clipped to them and counted
(:attr:`VirtualArm.clipped`), as a real arm's drives saturate; a plant that diverges anyway brakes
the arm with the reason. Two drivers run it:

* :func:`urpc.robot.virtual_server.serve`, the process of ``urpc virtual-robot``: wall-clock
  time at the robot's rate, UDP on 127.0.0.1 (:mod:`urpc.robot.packet`), lost packets;
* :class:`LockstepRobot`, in-process and on a fake clock (:class:`FakeClock`), for tests and
  for the delayed law's studies: the same arm, with no wall time at all.

Which torque applies over the period that starts at sample ``k``: the one answering sample
``k - delay``. With ``delay = 0`` the robot waits for it (up to ``wait`` of the period, then holds
the last torque and counts a late cycle): the ideal zero-order hold of ``urpc simulate``. With
``delay = 1`` it applies the torque that arrived during the previous period, as most torque
interfaces do.

The arm counts its samples in :attr:`VirtualArm.seq` (from 0, unbounded: robot time is
``seq * period``) and numbers them on the wire :attr:`VirtualArm.wire_seq`, ``first_seq + seq``
modulo ``2**32`` as the packet carries it (``first_seq`` lets a test start just before the wrap).
A torque's ``seq`` is mapped back to the sample it answers in serial-number arithmetic
(:func:`~urpc.robot.packet.seq_diff`), so the wrap changes nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, SimulationError
from ..names import VELOCITY_MODES
from ..sim.plants import make_plant
from ..sim.sampled import ball_samples
from .interface import RobotState
from .packet import LATE, STOPPED, seq_diff, seq_wrap

#: Default robot-side watchdog [s].
WATCHDOG_TIMEOUT = 0.020


@dataclass(frozen=True)
class ArmOptions:
    """How the virtual arm measures and actuates.

    Attributes:
        delay: Samples between a state and the period its torque applies to: 0 or 1.
        encoder_resolution: Position quantum [rad or m] (0: none).
        noise: Standard deviation of the position noise [rad or m] (0: none).
        velocity: ``measured`` (the plant's velocity, plus noise / period) or ``difference``
            (backward difference of the measured positions over one period).
        loss: Probability that a datagram is lost, each direction (UDP driver only).
        disturbance: Radius of the ball of the input disturbance [N m], drawn per period.
        seed: Seed of noise, loss and disturbance.
        watchdog_timeout: Time without torque after which the arm is braked [s].
        wait: Fraction of the period the robot waits for the torque when ``delay = 0``.
    """

    delay: int = 0
    encoder_resolution: float = 0.0
    noise: float = 0.0
    velocity: str = "measured"
    loss: float = 0.0
    disturbance: float = 0.0
    seed: int = 0
    watchdog_timeout: float = WATCHDOG_TIMEOUT
    wait: float = 0.7

    def __post_init__(self):
        if self.delay not in (0, 1):
            raise InputError(f"{self.delay}: valid delays are 0 and 1 [samples]", field="delay")
        if self.velocity not in VELOCITY_MODES:
            raise InputError(
                f"{self.velocity!r}; valid: {', '.join(VELOCITY_MODES)}", field="velocity"
            )
        for name in ("encoder_resolution", "noise", "disturbance"):
            if not getattr(self, name) >= 0:
                raise InputError(f"{getattr(self, name)} must be >= 0", field=name)
        if not 0 <= self.loss < 1:
            raise InputError(f"{self.loss} must be in [0, 1)", field="loss")
        if not self.watchdog_timeout > 0:
            raise InputError(f"{self.watchdog_timeout} must be > 0 [s]", field="watchdog_timeout")


class VirtualArm:
    """A plant run as a torque-controlled arm (see the module docstring).

    Args:
        plant_robot: The true plant (:meth:`urpc.ParameterBox.plant`).
        period: The robot's period [s].
        options: :class:`ArmOptions`.
        q0, qd0: Initial state (default: zeros).
        backend: ``pinocchio`` or ``mujoco``.
        first_seq: The wire's sequence number of the first sample (any integer; taken modulo
            ``2**32``).

    Attributes:
        seq: Number of the current sample, from 0 (unbounded).
        wire_seq: Its sequence number on the wire (``first_seq + seq`` modulo ``2**32``).
        braked: The watchdog (or a STOP) braked the arm.
        armed: A torque has arrived once (brakes released, watchdog running).
        late: Periods that started without their torque (the last one was held).
        rejected: Torques dropped for a non-finite entry.
        clipped: Torques clipped to the effort limits.
        effort_limit: Per joint, the largest torque applied [N m or N] (``inf``: none).
        stop_reason: Why the arm was braked.
    """

    def __init__(
        self,
        plant_robot,
        period: float,
        options: ArmOptions | None = None,
        q0=None,
        qd0=None,
        backend: str = "pinocchio",
        first_seq: int = 0,
    ):
        self.robot = plant_robot
        self.first_seq = seq_wrap(int(first_seq))
        self.period = float(period)
        self.options = options = ArmOptions() if options is None else options
        self.dof = n = plant_robot.dof
        # Two RK4 steps per period: the plant of a 1 kHz arm in well under a period of Python.
        self.plant = make_plant(backend, plant_robot, max_step=self.period / 2)
        self.plant.reset(np.zeros(n) if q0 is None else q0, None if qd0 is None else qd0)
        self._rng = np.random.default_rng(options.seed)
        self.seq = 0
        self.braked = False
        self.armed = False
        self.late = 0
        self.rejected = 0
        self.clipped = 0
        effort = np.asarray(plant_robot.effort_limit, dtype=float)
        self.effort_limit = np.where(np.isfinite(effort) & (effort > 0), effort, np.inf)
        self.stop_reason: str | None = None
        self.stopped_at: float | None = None
        self.last_torque_time: float | None = None
        self.applied = np.zeros(n)
        self._torques: dict[int, np.ndarray] = {}  # by the sample they answer (the last few)
        self._q_measured_previous: np.ndarray | None = None
        self.late_flag = False
        self.torques = 0

    @property
    def state(self):
        return self.plant.state

    @property
    def wire_seq(self) -> int:
        return seq_wrap(self.first_seq + self.seq)

    def sample_of(self, wire_seq: int) -> int:
        """The sample number (:attr:`seq`'s count) of the wire's ``wire_seq``, taken as the
        sample nearest to the current one in serial-number arithmetic."""
        return self.seq + seq_diff(wire_seq, self.wire_seq)

    def measure(self) -> tuple[np.ndarray, np.ndarray]:
        """The measured ``(q, qd)`` of the current sample."""
        q_true, qd_true = self.plant.state
        options, period = self.options, self.period
        q = q_true
        if options.noise > 0:
            q = q + options.noise * self._rng.standard_normal(self.dof)
        if options.encoder_resolution > 0:
            q = np.round(q / options.encoder_resolution) * options.encoder_resolution
        if options.velocity == "difference":
            previous = self._q_measured_previous
            qd = np.zeros(self.dof) if previous is None or self.braked else (q - previous) / period
        else:
            qd = qd_true
            if options.noise > 0:
                qd = qd + (options.noise / period) * self._rng.standard_normal(self.dof)
        self._q_measured_previous = q
        return q, qd

    def receive(self, now: float, seq: int, tau: np.ndarray) -> bool:
        """A torque answering the sample numbered ``seq`` on the wire arrived at ``now`` [s].
        False when it is dropped: the arm is braked, or an entry is not finite (counted in
        :attr:`rejected`; it neither arms the arm nor feeds its watchdog). A torque beyond
        :attr:`effort_limit` is clipped to it (counted in :attr:`clipped`)."""
        if self.braked:
            return False
        tau = np.array(tau, dtype=float)
        if tau.shape != (self.dof,) or not np.isfinite(tau).all():
            self.rejected += 1
            return False
        limited = np.clip(tau, -self.effort_limit, self.effort_limit)
        if not np.array_equal(limited, tau):
            self.clipped += 1
        self.armed = True
        self.last_torque_time = now
        self.torques += 1
        self._torques[self.sample_of(seq)] = limited
        if len(self._torques) > 8:
            del self._torques[min(self._torques)]
        return True

    def has_torque_for_current(self) -> bool:
        """Whether the torque that applies to the current period has arrived."""
        return (self.seq - self.options.delay) in self._torques

    def check_watchdog(self, now: float) -> bool:
        """Brake the arm if no torque arrived for the watchdog's timeout; True when braked."""
        if self.armed and not self.braked:
            quiet = now - self.last_torque_time
            if quiet > self.options.watchdog_timeout:
                self.brake(
                    now,
                    f"stopped by watchdog: no torque for {quiet * 1e3:.1f} ms (limit "
                    f"{self.options.watchdog_timeout * 1e3:g} ms) at t = {self.seq * self.period:.3f} s",
                )
        return self.braked

    def brake(self, now: float, reason: str) -> None:
        if not self.braked:
            self.braked = True
            self.stop_reason = reason
            self.stopped_at = now
            q, _ = self.plant.state
            self.plant.reset(q, np.zeros(self.dof))

    def advance(self) -> None:
        """Integrate the period that starts at the current sample; then the next sample."""
        self.late_flag = False
        if self.armed and not self.braked:
            wanted = self.seq - self.options.delay
            if wanted in self._torques:
                self.applied = self._torques.pop(wanted)
                for old in [s for s in self._torques if s < wanted]:
                    del self._torques[old]
            elif self.seq > self.options.delay:
                self.late += 1
                self.late_flag = True
            tau = self.applied
            if self.options.disturbance > 0:
                tau = tau + ball_samples(1, self.dof, self.options.disturbance, self._rng)[0]
            try:
                self.plant.step(tau, self.period)
            except SimulationError as exc:  # the arm stops where it was, as braked
                self.brake(None, f"stopped: {exc}")
        self.seq += 1

    def flags(self) -> int:
        return (STOPPED if self.braked else 0) | (LATE if self.late_flag else 0)


class FakeClock:
    """A clock that moves only when told: ``clock()`` reads it, ``advance(dt)`` moves it."""

    def __init__(self, start: float = 0.0):
        self.now = float(start)

    def __call__(self) -> float:
        return self.now

    def advance(self, dt: float) -> None:
        self.now += dt

    def sleep(self, dt: float) -> None:
        self.now += max(0.0, dt)


class LockstepRobot:
    """A :class:`VirtualArm` behind the :class:`~urpc.robot.interface.RobotInterface`, in lock
    step with the loop on a :class:`FakeClock`: each :meth:`read_state` starts a period on the
    clock's schedule, each :meth:`send_torque` arrives ``response_time`` [s] after its state (a
    callable ``response_time(seq)`` models a slow or stalling loop)."""

    def __init__(self, arm: VirtualArm, clock: FakeClock, response_time=0.0):
        self.arm = arm
        self.dof, self.period = arm.dof, arm.period
        self.clock = clock
        self.response_time = (
            response_time if callable(response_time) else (lambda seq: response_time)
        )
        self._tick = clock()
        self._pending_read = False
        self.stopped = False

    def read_state(self, timeout: float) -> RobotState | None:
        arm = self.arm
        if self._pending_read:  # the previous sample's period: integrate it before the next
            arm.advance()
            self._tick += self.period
        self.clock.now = max(self.clock.now, self._tick)
        arm.check_watchdog(self.clock())
        q, qd = arm.measure()
        self._pending_read = True
        return RobotState(arm.wire_seq, arm.seq * self.period, q, qd, self.clock(), arm.braked)

    def send_torque(self, seq: int, tau: np.ndarray) -> None:
        self.clock.now = max(self.clock.now, self._tick + self.response_time(seq))
        self.arm.check_watchdog(self.clock())
        self.arm.receive(self.clock(), seq, tau)

    def stop(self) -> None:
        self.stopped = True
        self.arm.brake(self.clock(), "stopped on request of the controller")


__all__ = ["ArmOptions", "FakeClock", "LockstepRobot", "VirtualArm"]
