"""The watchdogs on both sides, on a fake clock: the loop's late-cycle budget and silence limit,
the virtual arm's 20 ms torque timeout, and whole runs stopped by them."""

import dataclasses

import numpy as np
import pytest

import urpc
from urpc.errors import InputError
from urpc.robot.loop import ControlLoop
from urpc.robot.packet import seq_wrap
from urpc.robot.runner import run
from urpc.robot.safety import SafetyLayer
from urpc.robot.virtual import FakeClock, LockstepRobot, VirtualArm
from urpc.robot.watchdog import Watchdog


def test_trips_at_the_budget_not_before():
    dog = Watchdog(1e-3, late_budget=3)  # deadline 0.5 ms
    for k in range(3):
        assert dog.arrived(k, k * 1e-3)
        assert dog.answered(k * 1e-3, k * 1e-3 + 0.6e-3)
        assert not dog.tripped
    dog.arrived(3, 3e-3)
    dog.answered(3e-3, 3e-3 + 0.4e-3)  # on time: the run of late cycles restarts
    for k in range(4, 7):
        dog.arrived(k, k * 1e-3)
        dog.answered(k * 1e-3, k * 1e-3 + 0.6e-3)
    assert not dog.tripped and dog.consecutive == 3
    dog.arrived(7, 7e-3)
    dog.answered(7e-3, 7e-3 + 0.6e-3)
    assert dog.tripped and "4 consecutive late cycles (budget 3)" in dog.message
    assert dog.late_cycles == 7 and dog.cycles == 8


def test_lost_and_stale_samples():
    dog = Watchdog(1e-3)
    assert dog.arrived(10, 0.0) and dog.arrived(13, 0.003)
    assert not dog.arrived(12, 0.0031)  # older than the newest: stale
    assert dog.lost_samples == 2


def test_silence():
    dog = Watchdog(1e-3, silence=0.01)
    assert not dog.check_silence(5.0)  # nothing heard yet: not armed
    dog.arrived(0, 1.0)
    assert not dog.check_silence(1.0099)
    assert dog.check_silence(1.0101) and "no state" in dog.message


def test_arm_watchdog_brakes_after_20_ms_without_torque(rr_rig):
    robot, plant, _ = rr_rig
    arm = VirtualArm(plant, 1e-3)
    arm.check_watchdog(1.0)
    assert not arm.braked  # not armed before the first torque
    arm.receive(1.0, 0, robot.g(np.zeros(2)))
    arm.advance()
    assert not arm.check_watchdog(1.0 + 0.0199)
    assert arm.check_watchdog(1.0 + 0.0201)
    assert "stopped by watchdog: no torque for 20.1 ms" in arm.stop_reason
    q = arm.state.q
    arm.receive(1.03, 1, np.full(2, 500.0))  # ignored once braked
    arm.advance()
    assert np.array_equal(arm.state.q, q) and np.all(arm.state.qd == 0)


@dataclasses.dataclass
class Lockstep:
    """A whole run on the fake clock, and what it ran with."""

    report: object
    loop: ControlLoop
    safety: SafetyLayer
    arm: VirtualArm
    watchdog: Watchdog
    clock: FakeClock


def run_lockstep(rr_rig, response_time=1e-4, *, robot=LockstepRobot, duration=1.0, **watchdog):
    """The paper's reference for ``duration`` [s] at 1 kHz on the RR arm, through ``robot`` (a
    :class:`LockstepRobot` class answering after ``response_time``), on a fake clock."""
    model, plant, controller = rr_rig
    clock = FakeClock()
    arm = VirtualArm(plant, 1e-3)
    loop = ControlLoop(controller, urpc.PaperTrajectory())
    safety = SafetyLayer.for_robot(model, 1e-3, safe_mode="zero")
    dog = Watchdog(1e-3, **watchdog)
    report = run(robot(arm, clock, response_time), loop, safety, dog, duration, clock=clock)
    return Lockstep(report, loop, safety, arm, dog, clock)


def test_a_stalling_loop_is_stopped_by_its_watchdog_with_the_safe_command(rr_rig):
    # On time for 100 cycles, then every answer takes 0.8 ms (deadline 0.5 ms).
    done = run_lockstep(rr_rig, lambda seq: 1e-4 if seq < 100 else 8e-4, late_budget=5)
    report, safety, arm = done.report, done.safety, done.arm
    assert report.ending == "watchdog" and "6 consecutive late cycles" in report.message
    assert report.cycles == 106 and safety.counts["watchdog"] == 1
    assert np.array_equal(safety.last_torque, np.zeros(2))  # the safe command was the last one
    assert arm.braked  # robot.stop() after the fault


def silent_after(samples):
    class Silent(LockstepRobot):
        def read_state(self, timeout):
            if self.arm.seq >= samples:
                self.clock.advance(timeout)
                return None
            return super().read_state(timeout)

    return Silent


def test_a_silent_robot_trips_the_loop(rr_rig):
    report = run_lockstep(rr_rig, robot=silent_after(50), silence=0.01).report
    assert report.ending == "watchdog" and "no state from the robot" in report.message
    assert report.cycles == 51  # samples 0..50, then silence


def test_the_silence_limit_is_not_stretched_by_the_late_budget():
    # It was max(50 ms, (late_budget + 1) periods): 100 s with the loaded machine's budget.
    assert Watchdog(1e-3, late_budget=100000).silence == 0.05
    assert Watchdog(0.1).silence == 0.5  # a slow robot: five of its periods
    with pytest.raises(InputError, match="less than 2 periods") as caught:
        Watchdog(1e-3, silence=1.5e-3)
    assert caught.value.field == "silence"


def test_a_silent_robot_ends_a_run_with_a_huge_late_budget_within_the_silence_limit(rr_rig):
    done = run_lockstep(rr_rig, robot=silent_after(100), late_budget=100000)
    report = done.report
    assert report.ending == "watchdog" and "no state from the robot for 5" in report.message
    assert done.clock() < 0.1 + 0.05 + 0.002  # the last state, the 50 ms limit, one read timeout


class JumpingSeq(LockstepRobot):
    """From sample 100 on, sequence numbers 2**31 + 5 ahead: older in serial arithmetic."""

    def read_state(self, timeout):
        state = super().read_state(timeout)
        if self.arm.seq < 100:
            return state
        return dataclasses.replace(state, seq=seq_wrap(state.seq + 2**31 + 5))


def test_stale_states_are_silence_and_the_message_says_so(rr_rig):
    done = run_lockstep(rr_rig, robot=JumpingSeq)
    report, safety, dog = done.report, done.safety, done.watchdog
    assert report.ending == "watchdog", report.message
    assert report.cycles == 100 and done.clock() < 0.1 + 0.05 + 0.002
    assert "no new state from the robot for 5" in report.message
    assert "stale states arrived, their sequence numbers not advancing past 99" in report.message
    assert dog.stale_states == safety.counts["stale_state"] >= 49
    assert report.watchdog["stale_states"] == dog.stale_states


class Slow(LockstepRobot):
    """Fresh states, one seq apart, but three periods of clock time apart."""

    def read_state(self, timeout):
        if self._pending_read:
            self.clock.advance(3e-3)
        return super().read_state(timeout)


def test_a_run_ends_by_its_duration_plus_the_grace_on_the_clock(rr_rig):
    done = run_lockstep(rr_rig, robot=Slow)
    report = done.report
    assert report.ending == "watchdog" and "of clock time for 0.66" in report.message
    assert "allowed: 2 s" in report.message
    assert 2.0 < done.clock() < 2.01  # duration 1 s + the grace of 1 s


class Overtaken(LockstepRobot):
    """Every other sample overtaken by the next (a loaded loop answers the newest)."""

    def read_state(self, timeout):
        state = super().read_state(timeout)
        if self.arm.seq % 2:
            self.send_torque(state.seq, np.zeros(self.dof))  # keep the arm's schedule
            state = super().read_state(timeout)
        return state


def test_a_run_ends_when_loop_time_reaches_the_duration(rr_rig):
    # It counted answered cycles: with every other sample overtaken it ran twice its duration.
    done = run_lockstep(rr_rig, robot=Overtaken, duration=0.2)
    report, loop, dog = done.report, done.loop, done.watchdog
    assert report.ok, report.message
    assert loop.series()["t"][-1] == pytest.approx(0.2) and dog.lost_samples == 100
    assert report.cycles == 101
