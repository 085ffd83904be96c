"""The UDP wire format between a control loop and a (virtual) robot: two fixed-layout datagrams.

Every number is little-endian. ``n`` is the number of joints (1-255).

State, robot -> loop, ``24 + 16 n`` bytes::

    offset  size  type      field
    0       4     bytes     magic  b"URPS"
    4       1     uint8     version (1)
    5       1     uint8     n, number of joints
    6       2     uint16    flags: bit 0 STOPPED (the robot's watchdog braked the arm; no more
                            torque is applied), bit 1 LATE (the robot applied an old torque at
                            the sample before this one, none having arrived in time)
    8       4     uint32    seq, sample number, +1 per robot period (0 at the first sample)
    12      8     float64   t, robot time of the sample [s]
    20      4     -         reserved (0)
    24      8 n   float64   q, joint positions [rad or m]
    24+8n   8 n   float64   qd, joint velocities [rad/s or m/s]

Torque, loop -> robot, ``16 + 8 n`` bytes::

    0       4     bytes     magic  b"URPT"
    4       1     uint8     version (1)
    5       1     uint8     n
    6       2     uint16    flags: bit 0 HELLO (register this address to receive the states; the
                            torque is ignored), bit 1 STOP (end of run: brake the arm)
    8       4     uint32    seq, the seq of the state this torque answers
    12      4     -         reserved (0)
    16      8 n   float64   tau, joint torques [N m or N]

A datagram of the wrong magic, version, joint count or size is refused with :class:`PacketError`
(its ``kind`` says which).

**Sequence numbers wrap.** ``seq`` is 32 bits: at 1 kHz it wraps after about 49.7 days
(``2**32 - 1`` is followed by ``0``). Every decision on sequence numbers (newer, older, stale,
lost, which torque answers which sample) is made in serial-number arithmetic (RFC 1982) with
:func:`seq_diff` and :func:`seq_newer`, never with ``<`` on the raw numbers: ``b`` is newer than
``a`` when ``(b - a) mod 2**32`` lies in ``(0, 2**31)``. The arithmetic holds as long as the two
numbers compared are less than ``2**31`` samples apart (24.8 days at 1 kHz); a distance of exactly
``2**31``, which RFC 1982 leaves undefined, counts as older.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

from ..errors import UrpcError

VERSION = 1
STATE_MAGIC, TORQUE_MAGIC = b"URPS", b"URPT"
#: State flags.
STOPPED, LATE = 1, 2
#: Torque flags.
HELLO, STOP = 1, 2

#: Sequence numbers are taken modulo this (32 bits on the wire).
SEQ_MODULUS = 1 << 32
_SEQ_MASK = SEQ_MODULUS - 1
_SEQ_HALF = 1 << 31

_STATE_HEADER = struct.Struct("<4sBBHIdI")  # 24 bytes
_TORQUE_HEADER = struct.Struct("<4sBBHII")  # 16 bytes
MAX_JOINTS = 255


class PacketError(UrpcError, ValueError):
    """A datagram that is not a urpc packet of the expected kind and size.

    Attributes:
        kind: What is wrong: ``magic`` (not a urpc packet of this kind), ``version`` (another
            protocol version, in :attr:`version`), ``joints`` (a packet for another number of
            joints, in :attr:`joints`), ``size`` (a header that fits, a body that does not).
    """

    def __init__(self, message: str, kind: str = "size", *, version=None, joints=None):
        super().__init__(message)
        self.kind, self.version, self.joints = kind, version, joints


@dataclass(frozen=True, eq=False)
class StatePacket:
    seq: int
    t: float
    q: np.ndarray
    qd: np.ndarray
    flags: int = 0

    @property
    def stopped(self) -> bool:
        return bool(self.flags & STOPPED)


@dataclass(frozen=True, eq=False)
class TorquePacket:
    seq: int
    tau: np.ndarray
    flags: int = 0


def seq_diff(b: int, a: int) -> int:
    """The serial-number distance from ``a`` to ``b`` (RFC 1982): ``b - a`` reduced modulo
    ``2**32`` into ``[-2**31, 2**31)``. Positive: ``b`` is newer, by that many samples; ``0``:
    the same sample; negative: older. Exact across the wrap (``seq_diff(0, 2**32 - 1) == 1``) and
    for unwrapped counters too, while the true distance is below ``2**31``."""
    return ((b - a + _SEQ_HALF) & _SEQ_MASK) - _SEQ_HALF


def seq_newer(b: int, a: int) -> bool:
    """Whether sample ``b`` is newer than sample ``a`` in serial-number arithmetic."""
    return seq_diff(b, a) > 0


def seq_wrap(seq: int) -> int:
    """``seq`` as the wire carries it: modulo ``2**32``."""
    return seq & _SEQ_MASK


def state_size(n: int) -> int:
    return _STATE_HEADER.size + 16 * n


def torque_size(n: int) -> int:
    return _TORQUE_HEADER.size + 8 * n


def _joints(n: int) -> int:
    if not 1 <= n <= MAX_JOINTS:
        raise PacketError(f"{n} joints; a packet carries 1 to {MAX_JOINTS}", "joints", joints=n)
    return n


def encode_state(seq: int, t: float, q: np.ndarray, qd: np.ndarray, flags: int = 0) -> bytes:
    n = _joints(len(q))
    header = _STATE_HEADER.pack(STATE_MAGIC, VERSION, n, flags, seq_wrap(seq), t, 0)
    body = np.concatenate([q, qd]).astype("<f8", copy=False)
    return header + body.tobytes()


def decode_state(data: bytes, n: int) -> StatePacket:
    """The state in ``data``, which must be a version-1 state packet of ``n`` joints."""
    _check(data, STATE_MAGIC, n, state_size(n), "state")
    _, _, _, flags, seq, t, _ = _STATE_HEADER.unpack_from(data)
    body = np.frombuffer(data, dtype="<f8", offset=_STATE_HEADER.size).astype(float)
    return StatePacket(seq, t, body[:n], body[n:], flags)


def encode_torque(seq: int, tau: np.ndarray, flags: int = 0) -> bytes:
    n = _joints(len(tau))
    header = _TORQUE_HEADER.pack(TORQUE_MAGIC, VERSION, n, flags, seq_wrap(seq), 0)
    return header + np.asarray(tau, dtype="<f8").tobytes()


def hello_joints(data: bytes) -> int | None:
    """The joint count of ``data`` if it is a HELLO torque packet (of any joint count, even one
    whose size does not match it), else ``None``: lets a robot tell a controller for another
    arm from noise."""
    if len(data) < _TORQUE_HEADER.size:
        return None
    magic, version, joints, flags, _, _ = _TORQUE_HEADER.unpack_from(data)
    if magic != TORQUE_MAGIC or version != VERSION or not flags & HELLO:
        return None
    return joints


def decode_torque(data: bytes, n: int) -> TorquePacket:
    """The torque in ``data``, which must be a version-1 torque packet of ``n`` joints."""
    _check(data, TORQUE_MAGIC, n, torque_size(n), "torque")
    _, _, _, flags, seq, _ = _TORQUE_HEADER.unpack_from(data)
    tau = np.frombuffer(data, dtype="<f8", offset=_TORQUE_HEADER.size).astype(float)
    return TorquePacket(seq, tau, flags)


def _check(data: bytes, expected: bytes, n: int, size: int, what: str) -> None:
    """Refuse ``data`` unless it is a version-1 ``what`` packet of ``n`` joints and ``size``
    bytes, saying first what is most telling: the magic, the version, the joint count, the size."""
    magic = bytes(data[:4])
    if magic != expected:
        raise PacketError(f"magic {magic!r}; expected {expected!r}", "magic")
    if len(data) < 6:
        raise PacketError(f"{what} packet of {len(data)} bytes; expected {size}", "size")
    version, joints = data[4], data[5]
    if version != VERSION:
        raise PacketError(
            f"packet version {version}; this urpc speaks version {VERSION}",
            "version",
            version=version,
        )
    if joints != n:
        raise PacketError(
            f"packet for {joints} joints; this robot has {n}", "joints", joints=joints
        )
    if len(data) != size:
        raise PacketError(
            f"{what} packet of {len(data)} bytes; expected {size} for {n} joints", "size"
        )
