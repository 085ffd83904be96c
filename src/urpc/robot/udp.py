"""UDP on the loopback interface: the address form, the loop-side client of a (virtual) robot.

Addresses are ``udp://127.0.0.1:PORT`` (or ``udp://localhost:PORT``); nothing else is accepted,
so a virtual robot and a loop never talk beyond this machine. Packets: :mod:`urpc.robot.packet`.
"""

from __future__ import annotations

import select
import socket
import time
from urllib.parse import urlsplit

import numpy as np

from ..errors import InputError
from .interface import RobotState
from .packet import HELLO, STOP, PacketError, decode_state, encode_torque, seq_newer, state_size

LOOPBACK = "127.0.0.1"


def parse_address(text: str, field: str = "robot-address") -> tuple[str, int]:
    """``(host, port)`` of ``udp://127.0.0.1:PORT``.

    Raises:
        InputError: another scheme, a host that is not the loopback, a missing or bad port.
    """
    parts = urlsplit(text)
    expected = "expected udp://127.0.0.1:PORT (loopback only, PORT 1-65535)"
    if parts.scheme != "udp":
        raise InputError(f"{text!r} is not a udp:// address; {expected}", field=field)
    if not parts.netloc:
        raise InputError(f"{text!r} gives no host and port; {expected}", field=field)
    extra = [
        name
        for name, value in (
            ("a path", parts.path),
            ("a query", parts.query),
            ("a fragment", parts.fragment),
            ("a user", parts.username),
        )
        if value
    ]
    if extra:
        raise InputError(
            f"{text!r} has {' and '.join(extra)}, which a robot address does not take; {expected}",
            field=field,
        )
    if not parts.hostname:
        raise InputError(f"{text!r} gives no host before the port; {expected}", field=field)
    if parts.hostname not in ("127.0.0.1", "localhost"):
        raise InputError(f"host {parts.hostname!r} is not the loopback; {expected}", field=field)
    try:
        port = parts.port
    except ValueError:
        port = None
    if not port:
        raise InputError(f"{text!r} has no valid port; {expected}", field=field)
    return LOOPBACK, port


def check_port(port: int, field: str = "port") -> int:
    if not 1 <= port <= 65535:
        raise InputError(f"{port} is not a port; valid: 1-65535", field=field)
    return port


class UdpRobot:
    """The loop's side of a UDP robot (:class:`~urpc.robot.interface.RobotInterface`).

    On construction it binds an ephemeral loopback port and registers with the robot (a HELLO
    packet, repeated by :meth:`read_state` until the first state arrives).

    Args:
        address: ``udp://127.0.0.1:PORT`` of the robot.
        dof: Number of joints.
        period: The robot's period [s].
        clock: The clock of :attr:`RobotState.received` (``time.monotonic``).

    Attributes:
        received, sent, bad_packets, dropped: Packet counters (``dropped``: states overtaken by a
            newer one before the loop read them).

    :meth:`read_state` returns the newest of the queued states by sequence number in
    serial-number arithmetic (:func:`~urpc.robot.packet.seq_newer`; across the 32-bit wrap too),
    not the last to arrive: a datagram reordered behind a newer one is dropped, not answered.
    """

    def __init__(self, address: str, dof: int, period: float, clock=time.monotonic):
        self.host, self.port = parse_address(address)
        self.dof, self.period = dof, float(period)
        self._clock = clock
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._socket.bind((LOOPBACK, 0))
        self._socket.setblocking(False)
        self._size = state_size(dof)
        self.received = self.sent = self.bad_packets = self.dropped = 0
        self.last_error: str | None = None
        #: Why the last datagram refused was refused (:class:`PacketError`, its ``kind``).
        self.last_refusal: PacketError | None = None
        self._registered = False
        self._stopped = False
        self._hello()

    def _hello(self) -> None:
        self._send(encode_torque(0, np.zeros(self.dof), HELLO))

    def _send(self, data: bytes) -> None:
        try:
            self._socket.sendto(data, (self.host, self.port))
            self.sent += 1
        except OSError as exc:  # nobody listening yet (ICMP port unreachable): retried
            self.last_error = str(exc)

    def read_state(self, timeout: float) -> RobotState | None:
        end = self._clock() + timeout
        newest = None
        while True:
            wait = 0.0 if newest is not None else max(0.0, end - self._clock())
            ready, _, _ = select.select([self._socket], [], [], min(wait, 0.05))
            if not ready:
                if newest is not None:
                    return newest
                if self._clock() >= end:
                    return None
                if not self._registered:
                    self._hello()
                continue
            try:
                data = self._socket.recv(65536)
            except (BlockingIOError, ConnectionRefusedError):
                continue
            try:
                packet = decode_state(data, self.dof)
            except PacketError as exc:
                self.bad_packets += 1
                self.last_error = str(exc)
                self.last_refusal = exc
                continue
            self.received += 1
            self._registered = True
            if newest is not None:
                self.dropped += 1
                if not seq_newer(packet.seq, newest.seq):  # reordered: older than the one held
                    continue
            newest = RobotState(
                packet.seq, packet.t, packet.q, packet.qd, self._clock(), packet.stopped
            )

    def send_torque(self, seq: int, tau: np.ndarray) -> None:
        self._send(encode_torque(seq, tau))

    def stop(self) -> None:
        if not self._stopped:
            self._stopped = True
            for _ in range(3):  # a lost datagram must not leave the arm waiting for its watchdog
                self._send(encode_torque(0, np.zeros(self.dof), STOP))
            self._socket.close()

    def counters(self) -> dict[str, int]:
        return {
            "received": self.received,
            "sent": self.sent,
            "bad_packets": self.bad_packets,
            "overtaken": self.dropped,
        }
