"""The loop's latency watchdog: late cycles and a silent robot, measured on a clock the caller
passes in (so that its logic is tested with a controllable clock, not with wall time).

A cycle is **late** when its torque was sent more than ``deadline`` [s] after its state arrived
(default: half a period, so that a robot that waits for the torque, :mod:`urpc.robot.virtual`
with no delay, still gets it within the period). The watchdog **trips** when more than
``late_budget`` consecutive cycles are late, or when no state has arrived for ``silence`` [s]
(default :data:`SILENCE`: a robot that stops talking is the robot's fault, which its own watchdog
handles; the loop only has to notice it is gone); the loop then sends the safe command and stops with
:attr:`Watchdog.message`. Every late cycle and every sample lost on the way (a gap in the
sequence numbers) is counted. Sequence numbers are compared in serial-number arithmetic
(:func:`urpc.robot.packet.seq_diff`), so the wrap of the 32-bit ``seq`` (``2**32 - 1``, then
``0``) is one step, not a stale sample.
"""

from __future__ import annotations

from ..validation import checked_count, positive_number
from .packet import seq_diff

#: Default longest time without a state before the watchdog trips [s].
SILENCE = 0.05


class Watchdog:
    """Deadline misses of a control loop with period ``period`` [s].

    Args:
        period: The control period [s].
        deadline: Largest time from a state's arrival to its torque being sent [s]; default
            ``period / 2``.
        late_budget: Consecutive late cycles tolerated; one more trips the watchdog.
        silence: Longest time without a state [s] before it trips; default
            :data:`SILENCE`, and never less than ``(late_budget + 1) * period``.

    Attributes:
        late_cycles: Late cycles so far.
        consecutive: The current run of consecutive late cycles.
        cycles: Cycles answered.
        lost_samples: Samples the robot numbered but the loop never received.
        worst_response: Largest state-to-torque time seen [s].
        message: Why it tripped, or ``None``.
    """

    def __init__(self, period: float, *, deadline=None, late_budget: int = 5, silence=None):
        self.period = positive_number("period", period, "a finite number > 0 [s]")
        self.deadline = (
            0.5 * self.period
            if deadline is None
            else positive_number("deadline", deadline, "a finite number > 0 [s]")
        )
        self.late_budget = checked_count(
            "late_budget", late_budget, 0, " (late cycles allowed in a row)"
        )
        floor = (self.late_budget + 1) * self.period
        self.silence = (
            max(SILENCE, floor)
            if silence is None
            else positive_number("silence", silence, "a finite number > 0 [s]")
        )
        self.late_cycles = 0
        self.consecutive = 0
        self.cycles = 0
        self.lost_samples = 0
        self.worst_response = 0.0
        self.message: str | None = None
        self._last_seq: int | None = None
        self._last_arrival: float | None = None

    @property
    def tripped(self) -> bool:
        return self.message is not None

    def arrived(self, seq: int, received: float) -> bool:
        """Note a state ``seq`` that arrived at ``received`` [s]; False for a stale one (a seq
        not newer than the last in serial-number arithmetic, so across the 32-bit wrap too),
        which the loop must not answer."""
        if self._last_seq is not None:
            gap = seq_diff(seq, self._last_seq)
            if gap <= 0:
                return False
            self.lost_samples += gap - 1
        self._last_seq = seq
        self._last_arrival = received
        return True

    def answered(self, received: float, sent: float) -> bool:
        """Note that the torque for a state that arrived at ``received`` was sent at ``sent``
        [s]; returns whether the cycle was late (and trips past the budget)."""
        self.cycles += 1
        response = sent - received
        self.worst_response = max(self.worst_response, response)
        if response <= self.deadline:
            self.consecutive = 0
            return False
        self.late_cycles += 1
        self.consecutive += 1
        if self.consecutive > self.late_budget and self.message is None:
            self.message = (
                f"{self.consecutive} consecutive late cycles (budget {self.late_budget}): the "
                f"torque left {response * 1e3:.3g} ms after the state, deadline "
                f"{self.deadline * 1e3:.3g} ms"
            )
        return True

    def check_silence(self, now: float) -> bool:
        """Whether the robot has been silent for longer than ``silence`` at ``now`` [s] (trips)."""
        if self._last_arrival is None:
            return False
        quiet = now - self._last_arrival
        if quiet > self.silence and self.message is None:
            self.message = f"no state from the robot for {quiet * 1e3:.3g} ms (limit {self.silence * 1e3:.3g} ms)"
        return self.tripped

    def summary(self) -> dict:
        return {
            "cycles": self.cycles,
            "late_cycles": self.late_cycles,
            "late_fraction": self.late_cycles / self.cycles if self.cycles else 0.0,
            "lost_samples": self.lost_samples,
            "worst_response_s": self.worst_response,
            "deadline_s": self.deadline,
            "late_budget": self.late_budget,
            "tripped": self.message,
        }
