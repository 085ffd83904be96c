"""One run on a robot: read the state, check it, step the loop, limit the torque, send it, and
watch the deadlines, until the duration is over or something stops the run.

Per cycle (``docs/robot.md``)::

    state = robot.read_state(timeout)          # None: nothing arrived -> watchdog.check_silence
    watchdog.arrived(state.seq, state.received)  # stale (not newer): ignored, counted,
                                               # -> watchdog.check_silence (fresh states only)
    safety.check_state(t, q, qd)               # fault -> safe command, stop
    tau = loop.step(t, q, qd)                  # the controller
    tau, fault = safety.limit(t, tau)          # clip (counted); non-finite -> safe command, stop
    robot.send_torque(state.seq, tau)
    watchdog.answered(state.received, clock()) # late past the budget -> safe command, stop

Loop time is ``t = (seq - seq_0) period``: a lost sample leaves a gap in time, not a shift. The
difference is taken in serial-number arithmetic (:func:`urpc.robot.packet.seq_diff`) and summed
sample by sample, so loop time keeps counting across the wrap of the 32-bit ``seq`` (about 49.7
days at 1 kHz) and past it.
The run ends when loop time reaches the duration (a sample overtaken by a newer one does not
make it longer). Every loop is bounded: by the duration in loop time, by the watchdog's silence
limit while no fresh state arrives (stale ones do not count), and by :func:`overrun_grace` on the
clock: a run takes at most its duration plus ``max(1 s, duration / 4)``. The clock is a parameter (``time.monotonic`` by default), which lets
tests drive a whole run on a fake clock.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError
from ..validation import positive_number
from .interface import RobotInterface, RobotState
from .loop import ControlLoop
from .packet import seq_diff
from .safety import SafetyLayer
from .watchdog import Watchdog

#: How a run ended.
ENDINGS = ("completed", "fault", "watchdog", "robot_stopped", "no_robot")


@dataclass
class RunReport:
    """How a run went.

    Attributes:
        ending: One of :data:`ENDINGS`.
        message: What stopped it (``None`` when completed).
        cycles: Samples answered.
        wall_time: Clock time from the first state to the end [s].
        safety: :meth:`SafetyLayer.summary` with the first interventions.
        watchdog: :meth:`Watchdog.summary`.
    """

    ending: str
    message: str | None
    cycles: int
    wall_time: float
    safety: dict[str, Any] = field(default_factory=dict)
    watchdog: dict[str, Any] = field(default_factory=dict)
    events: list[dict[str, Any]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.ending == "completed"

    def to_dict(self) -> dict[str, Any]:
        return {
            "ending": self.ending,
            "message": self.message,
            "cycles": self.cycles,
            "wall_time": self.wall_time,
            "safety": self.safety,
            "watchdog": self.watchdog,
            "events": self.events[:50],
        }


def run(
    robot: RobotInterface,
    loop: ControlLoop,
    safety: SafetyLayer,
    watchdog: Watchdog,
    duration: float,
    *,
    clock=time.monotonic,
    start_timeout: float = 5.0,
    first: RobotState | None = None,
) -> RunReport:
    """Drive ``robot`` with ``loop`` for ``duration`` [s] of loop time, behind ``safety`` and
    ``watchdog``; the robot is stopped (:meth:`RobotInterface.stop`) however the run ends. The
    run ends once loop time reaches ``duration``; it is stopped with the safe command when no
    fresh state arrives for ``watchdog.silence``, or when it has taken more than ``duration +
    overrun_grace(duration)`` on ``clock``. ``first``: a state already read (its sample is the
    run's first)."""
    duration = positive_number("duration", duration, "a finite number > 0 [s]")
    start_timeout = positive_number("start_timeout", start_timeout, "a finite number > 0 [s]")
    if safety.dof != loop.dof:
        raise InputError(
            f"the safety layer guards {safety.dof} joints ({', '.join(safety.joint_names)}) and "
            f"the loop drives {loop.dof}; build both for the same arm "
            "(SafetyLayer.for_robot(controller.robot, period))",
            field="safety",
        )
    period = loop.period
    last_index = max(1, math.ceil(duration / period - 1e-9))  # the run's last sample, from 0
    allowed = duration + overrun_grace(duration)  # clock time the run may take
    read_timeout = min(period, watchdog.silence)
    try:
        state = robot.read_state(start_timeout) if first is None else first
        start = clock()
        if state is None:
            return _report(
                "no_robot",
                f"no state from the robot within {start_timeout:g} s",
                0,
                0.0,
                safety,
                watchdog,
            )
        last_qd = state.qd
        last_seq = state.seq
        index = 0  # samples from the first one to last_seq (unwrapped)
        first_t, period_checked = state.t, False
        ending, message = "completed", None
        while True:
            if state is None or not watchdog.arrived(state.seq, state.received):
                if state is not None:  # stale: not answered, and not the robot talking
                    gap = seq_diff(state.seq, last_seq)
                    safety.stale(
                        (index + gap) * period,
                        f"sample {state.seq} arrived after sample {last_seq}; ignored",
                    )
                now = clock()
                if watchdog.check_silence(now):
                    safety.watchdog(index * period, watchdog.message)
                    _send_safe(robot, safety, last_seq + 1, last_qd)
                    ending, message = "watchdog", watchdog.message
                    break
                if now - start > allowed:
                    message = _overrun(now - start, index * period, duration, allowed)
                    safety.watchdog(index * period, message)
                    _send_safe(robot, safety, last_seq + 1, last_qd)
                    ending = "watchdog"
                    break
                state = robot.read_state(read_timeout)
                continue
            if state.stopped:
                ending, message = "robot_stopped", "the robot reports that it stopped the arm"
                break
            gap = seq_diff(state.seq, last_seq)  # 0 at the first sample
            t = (index + gap) * period
            last_seq, index = state.seq, index + gap
            if index >= PERIOD_CHECK_SAMPLES and not period_checked:
                period_checked = True
                mismatch = _period_mismatch(state.t - first_t, index, period)
                if mismatch is not None:
                    _send_safe(robot, safety, state.seq, state.qd)
                    ending, message = "fault", mismatch
                    break
            fault = safety.check_state(t, state.q, state.qd)
            if fault is not None:
                _send_safe(robot, safety, state.seq, state.qd)
                ending, message = "fault", _fault_message(fault)
                break
            last_qd = state.qd
            tau = loop.step(t, state.q, state.qd)
            sent, fault = safety.limit(t, tau)
            robot.send_torque(state.seq, sent)
            loop.record_sent(sent, safety.clipped or fault is not None)
            if fault is not None:
                ending, message = "fault", _fault_message(fault)
                break
            now = clock()
            watchdog.answered(state.received, now)
            if watchdog.tripped:
                safety.watchdog(t, watchdog.message)
                _send_safe(robot, safety, state.seq, state.qd)
                ending, message = "watchdog", watchdog.message
                break
            if index >= last_index:  # loop time reached the duration
                break
            if now - start > allowed:
                message = _overrun(now - start, t, duration, allowed)
                safety.watchdog(t, message)
                _send_safe(robot, safety, state.seq, state.qd)
                ending = "watchdog"
                break
            state = robot.read_state(read_timeout)
        return _report(ending, message, watchdog.cycles, clock() - start, safety, watchdog)
    finally:
        robot.stop()


#: A run may take its duration plus this much clock time (at least OVERRUN_GRACE [s], or
#: OVERRUN_FRACTION of the duration): a robot whose states come slower than its period (or whose
#: loop time stalls) is stopped by the loop's watchdog instead of stretching the run.
OVERRUN_GRACE = 1.0
OVERRUN_FRACTION = 0.25


def overrun_grace(duration: float) -> float:
    """The clock time [s] a run of ``duration`` [s] may take beyond it."""
    return max(OVERRUN_GRACE, OVERRUN_FRACTION * duration)


def _overrun(elapsed: float, loop_time: float, duration: float, allowed: float) -> str:
    return (
        f"the run has taken {elapsed:.3g} s of clock time for {loop_time:.3g} s of its "
        f"{duration:.3g} s of loop time (allowed: {allowed:.3g} s): the robot's states come "
        "slower than its period, or with sequence numbers that do not advance; safe command "
        "sent, run stopped"
    )


#: After this many samples the robot's period (from its states' times) is compared with the
#: loop's; a ratio outside PERIOD_TOLERANCE stops the run (a 10 kHz law on a 1 kHz arm).
PERIOD_CHECK_SAMPLES = 50
PERIOD_TOLERANCE = (0.9, 1.1)


def _period_mismatch(elapsed: float, samples: int, period: float) -> str | None:
    """What to say when ``samples`` robot periods took ``elapsed`` [s] of the robot's time and
    that is not ``samples`` loop periods (``None`` when it is, or the times say nothing)."""
    if not (math.isfinite(elapsed) and elapsed > 0):
        return None
    robot_period = elapsed / samples
    low, high = PERIOD_TOLERANCE
    if low <= robot_period / period <= high:
        return None
    return (
        f"the robot's period is {robot_period * 1e3:.4g} ms (the times of its states), the "
        f"controller's {period * 1e3:.4g} ms: synthesize the controller for the robot's period "
        "(the scenario's sample_period); safe command sent, run stopped"
    )


def _send_safe(robot: RobotInterface, safety: SafetyLayer, seq: int, qd: np.ndarray) -> None:
    robot.send_torque(seq, safety.safe_command(qd))


def _fault_message(fault) -> str:
    what = {
        "non_finite_state": "non-finite state",
        "position_limit": "position out of range (beyond the joint limits less the margin)",
        "velocity_limit": "velocity out of range (beyond the velocity limit less the margin)",
        "non_finite_torque": "the controller returned a non-finite torque",
    }[fault.kind]
    return f"{what} at t = {fault.t:.4f} s: {fault.detail}; safe command sent, run stopped"


def _report(
    ending, message, cycles, wall_time, safety: SafetyLayer, watchdog: Watchdog
) -> RunReport:
    return RunReport(
        ending,
        message,
        cycles,
        wall_time,
        safety.summary(),
        watchdog.summary(),
        [event.to_dict() for event in safety.events],
    )


__all__ = ["ENDINGS", "RobotState", "RunReport", "run"]
