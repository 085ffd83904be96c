"""The loop's latency watchdog: late cycles and a silent robot, measured on a clock the caller
passes in (so that its logic is tested with a controllable clock, not with wall time).

A cycle is **late** when its torque was sent more than ``deadline`` [s] after its state arrived
(default: half a period, so that a robot that waits for the torque, :mod:`urpc.robot.virtual`
with no delay, still gets it within the period). The watchdog **trips** when more than
``late_budget`` consecutive cycles are late, or when no **fresh** state (one newer than every
state before it) has arrived for ``silence`` [s] (default :data:`SILENCE`, at least
:data:`SILENCE_PERIODS` periods; a robot that stops talking is the robot's fault, which its own
watchdog handles; the loop only has to notice it is gone). The silence limit is its own quantity:
a large ``late_budget`` (a loaded machine's) does not stretch it. Stale states (sequence numbers
that do not advance: a robot restarted, or a counter that jumped by ``2**31`` or more) are not
answered and do not count as the robot talking; the message then says how many arrived. The loop
then sends the safe command and stops with :attr:`Watchdog.message`. Every late cycle and every sample lost on the way (a gap in the
sequence numbers) is counted. Sequence numbers are compared in serial-number arithmetic
(:func:`urpc.robot.packet.seq_diff`), so the wrap of the 32-bit ``seq`` (``2**32 - 1``, then
``0``) is one step, not a stale sample.
"""

from __future__ import annotations

from ..errors import InputError
from ..validation import checked_count, positive_number
from .packet import seq_diff

#: Default longest time without a fresh state before the watchdog trips [s].
SILENCE = 0.05
#: The default silence limit is at least this many periods (a slow robot's states are that far
#: apart), and a given one at least :data:`MIN_SILENCE_PERIODS` (less trips between two states).
SILENCE_PERIODS = 5
MIN_SILENCE_PERIODS = 2


class Watchdog:
    """Deadline misses of a control loop with period ``period`` [s].

    Args:
        period: The control period [s].
        deadline: Largest time from a state's arrival to its torque being sent [s]; default
            ``period / 2``.
        late_budget: Consecutive late cycles tolerated; one more trips the watchdog.
        silence: Longest time without a fresh state [s] before it trips; default
            ``max(SILENCE, SILENCE_PERIODS * period)`` (50 ms at 1 kHz), whatever the
            ``late_budget``; at least two periods.

    Attributes:
        late_cycles: Late cycles so far.
        consecutive: The current run of consecutive late cycles.
        cycles: Cycles answered.
        lost_samples: Samples the robot numbered but the loop never received.
        stale_states: States ignored because their sequence number was not newer.
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
        if silence is None:
            self.silence = max(SILENCE, SILENCE_PERIODS * self.period)
        else:
            self.silence = positive_number("silence", silence, "a finite number > 0 [s]")
            if self.silence < MIN_SILENCE_PERIODS * self.period:
                raise InputError(
                    f"{self.silence:g} s is less than {MIN_SILENCE_PERIODS} periods "
                    f"({MIN_SILENCE_PERIODS * self.period:g} s): the watchdog would trip between "
                    "two states; give at least two periods",
                    field="silence",
                )
        self.late_cycles = 0
        self.consecutive = 0
        self.cycles = 0
        self.lost_samples = 0
        self.stale_states = 0
        self.worst_response = 0.0
        self.message: str | None = None
        self._last_seq: int | None = None
        self._last_arrival: float | None = None  # of the last fresh state
        self._stale_since = 0  # stale states since the last fresh one
        self._stale_seq: int | None = None  # the latest of them

    @property
    def tripped(self) -> bool:
        return self.message is not None

    def arrived(self, seq: int, received: float) -> bool:
        """Note a state ``seq`` that arrived at ``received`` [s]; False for a stale one (a seq
        not newer than the last in serial-number arithmetic, so across the 32-bit wrap too),
        which the loop must not answer; it is counted and does not reset the silence limit."""
        if self._last_seq is not None:
            gap = seq_diff(seq, self._last_seq)
            if gap <= 0:
                self.stale_states += 1
                self._stale_since += 1
                self._stale_seq = seq
                return False
            self.lost_samples += gap - 1
        self._last_seq = seq
        self._last_arrival = received
        self._stale_since = 0
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
        """Whether no fresh state has arrived for longer than ``silence`` at ``now`` [s]
        (trips). Stale states do not count: a robot whose sequence numbers stopped advancing is
        as gone as a silent one, and the message says which it was."""
        if self._last_arrival is None:
            return False
        quiet = now - self._last_arrival
        if quiet > self.silence and self.message is None:
            limit = f"(limit {self.silence * 1e3:.3g} ms)"
            if self._stale_since:
                self.message = (
                    f"no new state from the robot for {quiet * 1e3:.4g} ms {limit}: "
                    f"{self._stale_since} stale state{'s' if self._stale_since != 1 else ''} "
                    f"arrived, their sequence numbers not advancing past {self._last_seq} (the "
                    f"latest: {self._stale_seq}; a robot restarted, or a counter that jumped by "
                    "2**31 or more)"
                )
            else:
                self.message = f"no state from the robot for {quiet * 1e3:.4g} ms {limit}"
        return self.tripped

    def summary(self) -> dict:
        return {
            "cycles": self.cycles,
            "late_cycles": self.late_cycles,
            "late_fraction": self.late_cycles / self.cycles if self.cycles else 0.0,
            "lost_samples": self.lost_samples,
            "stale_states": self.stale_states,
            "silence_s": self.silence,
            "worst_response_s": self.worst_response,
            "deadline_s": self.deadline,
            "late_budget": self.late_budget,
            "tripped": self.message,
        }
