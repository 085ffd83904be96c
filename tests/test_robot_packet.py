"""The UDP wire format: round trips, sizes, and refusals of foreign datagrams."""

import numpy as np
import pytest

from urpc.errors import InputError
from urpc.robot import packet
from urpc.robot.udp import parse_address


def test_state_round_trip_is_exact_and_sized():
    q, qd = np.array([0.1, -2.5, 1e-17]), np.array([3.0, np.pi, -0.0])
    data = packet.encode_state(7, 0.007, q, qd, packet.STOPPED)
    assert len(data) == packet.state_size(3) == 24 + 48
    state = packet.decode_state(data, 3)
    assert state.seq == 7 and state.t == 0.007 and state.stopped
    assert np.array_equal(state.q, q) and np.array_equal(state.qd, qd)


def test_torque_round_trip_and_flags():
    tau = np.array([1.5, -1e3])
    data = packet.encode_torque(2**32 + 5, tau, packet.STOP)
    assert len(data) == packet.torque_size(2) == 32
    torque = packet.decode_torque(data, 2)
    assert torque.seq == 5 and torque.flags == packet.STOP  # seq wraps at 32 bits
    assert np.array_equal(torque.tau, tau)


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda d: d[:-8], "bytes"),
        (lambda d: b"XXXX" + d[4:], "magic"),
        (lambda d: d[:4] + bytes([9]) + d[5:], "version"),
    ],
)
def test_foreign_datagrams_are_refused(mutate, message):
    data = packet.encode_state(1, 0.0, np.zeros(2), np.zeros(2))
    with pytest.raises(packet.PacketError, match=message):
        packet.decode_state(mutate(data), 2)


def test_a_torque_packet_is_not_a_state_and_joint_count_is_checked():
    with pytest.raises(packet.PacketError):
        packet.decode_state(packet.encode_torque(0, np.zeros(6)), 2)
    data = packet.encode_torque(0, np.zeros(3))
    with pytest.raises(packet.PacketError, match="packet for 2 joints; this robot has 3"):
        packet.decode_torque(data[:5] + bytes([2]) + data[6:], 3)


def test_addresses_are_loopback_only():
    assert parse_address("udp://127.0.0.1:5000") == ("127.0.0.1", 5000)
    for bad in ("udp://10.0.0.2:5000", "tcp://127.0.0.1:5000", "udp://127.0.0.1"):
        with pytest.raises(InputError):
            parse_address(bad)


@pytest.mark.parametrize(
    "bad, words",
    [
        ("udp://", "gives no host and port"),
        ("udp://:47000", "'udp://:47000' gives no host before the port; expected udp://127"),
        ("udp://127.0.0.1:99999", "PORT 1-65535"),
        ("udp://localhost:5000/path", "has a path"),
        ("udp://127.0.0.1:5000?x=1", "has a query"),
        ("udp://user@127.0.0.1:5000", "has a user"),
    ],
)
def test_an_address_with_parts_a_robot_does_not_take_says_which(bad, words):
    with pytest.raises(InputError, match="robot-address") as caught:
        parse_address(bad)
    assert words in str(caught.value)


@pytest.mark.parametrize(
    "mutate, kind",
    [
        (lambda d: d[:-8], "size"),
        (lambda d: b"\x7e\x03\x8e\xbf" + d[4:], "magic"),
        (lambda d: d[:4] + bytes([9]) + d[5:], "version"),
        (lambda d: packet.encode_state(1, 0.0, np.zeros(3), np.zeros(3)), "joints"),
    ],
)
def test_a_refused_state_says_what_kind_of_wrong_it_is(mutate, kind):
    # A state for 3 joints was refused for its size only, so urpc run could not tell it from
    # garbage or another protocol version (and advised --lock for all three).
    data = packet.encode_state(1, 0.0, np.zeros(2), np.zeros(2))
    with pytest.raises(packet.PacketError) as caught:
        packet.decode_state(mutate(data), 2)
    assert caught.value.kind == kind
    assert caught.value.joints == (3 if kind == "joints" else None)
    assert caught.value.version == (9 if kind == "version" else None)
