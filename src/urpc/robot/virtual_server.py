"""The process of ``urpc virtual-robot``: a :class:`~urpc.robot.virtual.VirtualArm` served in
wall-clock time at the robot's rate over UDP on 127.0.0.1 (:mod:`urpc.robot.packet`), with lost
packets (:func:`serve`), and what it reports when it stops (:class:`ServeReport`).

Per period it sends the measured state to the controller that registered (HELLO), waits for the
torque (with ``delay = 0`` up to ``wait`` of the period), integrates the period and waits for the
next tick; it stops when the arm is braked (its watchdog, or a STOP from the loop), after
``max_duration`` or when no controller registers within ``wait_for_client``.
"""

from __future__ import annotations

import select
import socket
import sys
import time
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .packet import (
    HELLO,
    STOP,
    PacketError,
    decode_torque,
    encode_state,
    hello_joints,
    torque_size,
)
from .udp import LOOPBACK
from .virtual import VirtualArm


@dataclass
class ServeReport:
    """What :func:`serve` did."""

    reason: str
    samples: int
    states_sent: int
    torques_received: int
    lost_states: int
    lost_torques: int
    bad_packets: int
    late_periods: int
    late_ticks: int
    stop_latency: float | None
    arm_joints: int
    #: The joint count of a controller for another arm that said HELLO, if one did.
    foreign_joints: int | None = None
    #: Torque packets dropped for a non-finite entry (also counted as malformed).
    non_finite_torques: int = 0
    #: Torques clipped to the arm's effort limits.
    clipped_torques: int = 0
    effort_limit: tuple[float, ...] = ()

    def lines(self) -> list[str]:
        lines = [self.reason]
        if self.foreign_joints is not None:
            lines.append(
                f"  a controller for {self.foreign_joints} joints said HELLO; this arm has "
                f"{self.arm_joints} (lock or unlock joints so that both have the same)"
            )
        if self.stop_latency is not None:
            lines.append(f"  arm braked {self.stop_latency * 1e3:.1f} ms after the last torque")
        lines.append(
            f"  packets: {self.states_sent} states sent ({self.lost_states} dropped on purpose), "
            f"{self.torques_received} torques received ({self.lost_torques} dropped on purpose), "
            f"{self.bad_packets} malformed"
            + (
                f" ({self.non_finite_torques} with a non-finite torque, dropped)"
                if self.non_finite_torques
                else ""
            )
        )
        if self.clipped_torques:
            limits = ", ".join(f"{x:g}" for x in self.effort_limit)
            lines.append(
                f"  torque: {self.clipped_torques} torques beyond the effort limits clipped to "
                f"them (+-[{limits}] N m)"
            )
        lines.append(
            f"  samples: {self.samples}; late cycles: {self.late_periods} periods without their "
            f"torque in time, {self.late_ticks} ticks started more than half a period late"
        )
        return lines


def serve(
    arm: VirtualArm,
    port: int,
    *,
    max_duration: float = 600.0,
    wait_for_client: float = 60.0,
    ready=None,
    clock=time.monotonic,
    sleep=time.sleep,
) -> ServeReport:
    """Run ``arm`` in wall-clock time at its period on ``udp://127.0.0.1:port`` until it is
    braked (its watchdog, or a STOP from the loop), ``max_duration`` [s] of robot time, or
    ``wait_for_client`` [s] without a HELLO. ``ready(port)`` is called once the socket is bound."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind((LOOPBACK, port))
    except OSError as exc:
        sock.close()
        raise InputError(
            f"cannot listen on udp://{LOOPBACK}:{port} ({exc.strerror})", field="port"
        ) from None
    sock.setblocking(False)
    port = sock.getsockname()[1]
    if ready is not None:
        ready(port)
    options, period, n = arm.options, arm.period, arm.dof
    rng = np.random.default_rng(options.seed + 1)
    size = torque_size(n)
    peer = None
    counts = dict(
        sent=0, received=0, lost_states=0, lost_torques=0, bad=0, late_ticks=0, foreign=None
    )
    reason = None

    def drain(until: float, need_current: bool) -> None:
        nonlocal peer, reason
        while True:
            remaining = until - clock()
            if need_current and arm.has_torque_for_current():
                remaining = 0.0
            ready_, _, _ = select.select([sock], [], [], max(0.0, remaining))
            if not ready_:
                return
            try:
                data, sender = sock.recvfrom(65536)
            except (BlockingIOError, ConnectionRefusedError):
                continue
            if len(data) != size:
                counts["bad"] += 1
                joints = hello_joints(data)
                if joints is not None and peer is None:
                    # A controller for another arm: one state back, so that it can say why it
                    # refuses it; this arm keeps waiting for its own controller.
                    counts["foreign"] = joints
                    q, qd = arm.measure()
                    try:
                        sock.sendto(encode_state(arm.wire_seq, 0.0, q, qd, arm.flags()), sender)
                    except OSError:
                        pass
                continue
            try:
                packet = decode_torque(data, n)
            except PacketError:
                counts["bad"] += 1
                continue
            if packet.flags & HELLO:
                peer = sender
                continue
            if packet.flags & STOP:
                arm.brake(clock(), "stopped on request of the controller (end of run)")
                reason = arm.stop_reason
                return
            if options.loss and rng.random() < options.loss:
                counts["lost_torques"] += 1
                continue
            if arm.receive(clock(), packet.seq, packet.tau) or arm.braked:
                counts["received"] += 1
            else:  # a non-finite torque: malformed, dropped (arm.rejected)
                counts["bad"] += 1

    try:
        start = clock()
        while peer is None:
            if clock() - start > wait_for_client:
                return _serve_report(
                    f"no controller registered within {wait_for_client:g} s", arm, counts
                )
            drain(clock() + 0.05, False)
        tick = clock()
        limit = int(max_duration / period)
        while arm.seq < limit and reason is None:
            now = clock()
            if now - tick > 0.5 * period:
                counts["late_ticks"] += 1
            if arm.check_watchdog(now):
                reason = arm.stop_reason
            q, qd = arm.measure()
            data = encode_state(arm.wire_seq, arm.seq * period, q, qd, arm.flags())
            if options.loss and rng.random() < options.loss:
                counts["lost_states"] += 1
            else:
                try:
                    sock.sendto(data, peer)
                    counts["sent"] += 1
                except OSError:
                    pass
            if reason is not None:
                break
            if options.delay == 0:
                drain(tick + options.wait * period, True)
            else:
                drain(tick, False)
            arm.advance()
            tick += period
            remaining = tick - clock()
            if remaining > 0:
                drain(tick, False) if options.delay == 1 else sleep(remaining)
            elif remaining < -5 * period:  # far behind (machine stalled): skip ahead, counted
                tick = clock()
        if reason is None:
            reason = f"stopped after the maximum duration of {max_duration:g} s"
        return _serve_report(reason, arm, counts)
    finally:
        sock.close()


def _serve_report(reason: str, arm: VirtualArm, counts: dict) -> ServeReport:
    latency = None
    if arm.stopped_at is not None and arm.last_torque_time is not None and "watchdog" in reason:
        latency = arm.stopped_at - arm.last_torque_time
    return ServeReport(
        reason,
        arm.seq,
        counts["sent"],
        counts["received"],
        counts["lost_states"],
        counts["lost_torques"],
        counts["bad"],
        arm.late,
        counts["late_ticks"],
        latency,
        arm.dof,
        counts["foreign"],
        arm.rejected,
        arm.clipped,
        tuple(float(x) for x in arm.effort_limit),
    )


def say(line: str) -> None:
    print(line, flush=True)
    sys.stdout.flush()
