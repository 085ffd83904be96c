"""The 32-bit sequence number's wrap (``2**32 - 1``, then ``0``; about 49.7 days at 1 kHz): every
newer / older / stale / lost decision is serial-number arithmetic (RFC 1982), so a run across
the wrap is the same run as one far from it. All on the fake clock, except the one test of the
UDP client, which uses loopback sockets but no timing."""

import socket

import numpy as np
import pytest

import urpc
from urpc.robot import packet
from urpc.robot.loop import ControlLoop
from urpc.robot.packet import SEQ_MODULUS, seq_diff, seq_newer, seq_wrap
from urpc.robot.runner import run
from urpc.robot.safety import SafetyLayer
from urpc.robot.udp import UdpRobot
from urpc.robot.virtual import ArmOptions, FakeClock, LockstepRobot, VirtualArm
from urpc.robot.watchdog import Watchdog

TOP = SEQ_MODULUS - 1  # 2**32 - 1, the last number before the wrap


@pytest.mark.parametrize(
    "b, a, distance",
    [
        (0, TOP, 1),
        (1, TOP - 1, 3),
        (TOP - 1, 1, -3),
        (TOP, 0, -1),
        (5, 5, 0),
        (2**31 - 1, 0, 2**31 - 1),  # the farthest still newer
        (2**31, 0, -(2**31)),  # exactly half-way: undefined in RFC 1982, counted older
        (SEQ_MODULUS + 2, TOP, 3),  # an unwrapped counter against a wrapped one
    ],
)
def test_serial_distance(b, a, distance):
    assert seq_diff(b, a) == distance
    assert seq_newer(b, a) is (distance > 0)


def test_serial_distance_matches_the_unwrapped_one_for_every_pair_near_the_wrap():
    near = range(SEQ_MODULUS - 6, SEQ_MODULUS + 6)  # 2**32 - 6 .. 2**32 + 5, unwrapped
    for i in near:
        for j in near:
            assert seq_diff(seq_wrap(i), seq_wrap(j)) == i - j
            assert seq_newer(seq_wrap(i), seq_wrap(j)) is (i > j)


def test_packets_carry_the_wrapped_number():
    data = packet.encode_state(SEQ_MODULUS + 1, 0.0, np.zeros(2), np.zeros(2))
    assert packet.decode_state(data, 2).seq == 1
    assert packet.decode_torque(packet.encode_torque(TOP, np.zeros(2)), 2).seq == TOP


def test_watchdog_across_the_wrap_with_lost_and_reordered_samples():
    dog = Watchdog(1e-3)
    assert dog.arrived(TOP - 1, 0.000) and dog.arrived(TOP, 0.001)
    assert dog.arrived(0, 0.002)  # the wrap is one step: newer, nothing lost
    assert dog.lost_samples == 0
    assert dog.arrived(2, 0.004)  # 1 lost
    assert not dog.arrived(TOP, 0.0041)  # reordered from before the wrap: stale
    assert not dog.arrived(1, 0.0042)  # the lost one, late: stale
    assert not dog.arrived(2, 0.0043)  # a duplicate: stale
    assert dog.lost_samples == 1
    assert dog.arrived(5, 0.007) and dog.lost_samples == 3


def lockstep_run(rr_rig, first_seq, *, delay=0, robot_class=LockstepRobot, duration=0.05):
    robot, plant, controller = rr_rig
    clock = FakeClock()
    arm = VirtualArm(plant, 1e-3, ArmOptions(delay=delay), first_seq=first_seq)
    lockstep = robot_class(arm, clock, 1e-4)
    loop = ControlLoop(controller, urpc.PaperTrajectory())
    safety = SafetyLayer.for_robot(robot, 1e-3)
    watchdog = Watchdog(1e-3)
    report = run(lockstep, loop, safety, watchdog, duration, clock=clock)
    return report, loop, arm, lockstep, safety


@pytest.mark.parametrize("delay", [0, 1])
def test_a_run_across_the_wrap_is_the_run_far_from_it(rr_rig, delay):
    """Started 2 samples before the wrap (2**32 - 2, 2**32 - 1, 0, 1, ...), with and without
    the one-sample delay (the torque answering 2**32 - 1 applies over the period of 0): the
    same torques, states and loop times, bit for bit, as a run numbered from 0."""
    far, loop_far, arm_far, _, _ = lockstep_run(rr_rig, 0, delay=delay)
    near, loop_near, arm_near, _, _ = lockstep_run(rr_rig, TOP - 1, delay=delay)
    assert far.ok and near.ok and near.cycles == far.cycles == 51
    assert near.watchdog["lost_samples"] == 0 and near.safety["counts"]["stale_state"] == 0
    assert arm_near.late == arm_far.late == 0  # every torque found the period it answers
    a, b = loop_far.series(), loop_near.series()
    for name in ("t", "q", "qd", "torque", "torque_sent"):
        assert np.array_equal(a[name], b[name]), name
    assert np.array_equal(b["t"], np.arange(51) * 1e-3)
    assert arm_near.wire_seq == seq_wrap(TOP - 1 + arm_near.seq) < 100


class LossyReordered(LockstepRobot):
    """The lock-step robot behind a network that, at the wrap, holds back the state numbered
    2**32 - 1 until after 0 (reordered) and loses the state numbered 1."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.held = None
        self.delivered: list[int] = []

    def read_state(self, timeout):
        if self.held is not None and self.delivered and self.delivered[-1] == 0:
            state, self.held = self.held, None  # the late one, after its successor
        else:
            state = super().read_state(timeout)
            if state.seq == TOP:
                self.held = state
                state = super().read_state(timeout)  # its period passes without a torque
            if state.seq == 1:
                state = super().read_state(timeout)  # lost
        self.delivered.append(state.seq)
        return state


def test_lost_and_reordered_states_at_the_wrap(rr_rig):
    report, loop, arm, robot, safety = lockstep_run(
        rr_rig, TOP - 2, robot_class=LossyReordered, duration=0.03
    )
    assert robot.delivered[:6] == [TOP - 2, TOP - 1, 0, TOP, 2, 3]
    assert report.ok
    # 2**32 - 1 and 1 never answered: 2 lost; 2**32 - 1, when it came, was stale and ignored.
    assert report.watchdog["lost_samples"] == 2
    assert safety.counts["stale_state"] == 1
    assert "sample 4294967295 arrived after sample 0; ignored" in safety.events[0].detail
    assert safety.events[0].t == pytest.approx(2e-3)  # its own time, not 2**32 periods later
    # Loop time keeps the gaps of the lost samples and counts on across the wrap.
    t = loop.series()["t"]
    assert np.allclose(t[:5], [0.0, 1e-3, 3e-3, 5e-3, 6e-3], rtol=0, atol=1e-15)
    assert np.all(np.diff(t)[3:] == pytest.approx(1e-3))
    # The arm held the last torque over the two unanswered periods, and no more.
    assert arm.late == 2


def test_udp_client_returns_the_newest_state_across_the_wrap():
    """Three states queued out of order around the wrap: the client answers the newest by serial
    number (1), not the last to arrive (0), and counts the two it passed over."""
    robot_side = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    robot_side.bind(("127.0.0.1", 0))
    client = UdpRobot(f"udp://127.0.0.1:{robot_side.getsockname()[1]}", 2, 1e-3)
    try:
        _, address = robot_side.recvfrom(65536)  # the HELLO: the client's address
        for seq in (TOP, 1, 0):
            robot_side.sendto(packet.encode_state(seq, 0.0, np.zeros(2), np.zeros(2)), address)
        state = client.read_state(1.0)  # loopback datagrams are queued when sendto returns
        assert client.received == 3 and state.seq == 1 and client.dropped == 2
    finally:
        client.stop()
        robot_side.close()
