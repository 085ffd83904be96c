"""What the virtual arm does with a torque it cannot apply as sent: a non-finite one is dropped
and counted as malformed (the arm's watchdog brakes it if no valid torque follows), one beyond
the effort limits is clipped to them, and a plant that diverges brakes the arm with the reason
instead of ending the process with a bad-input error (fuzzing: NaN made `urpc virtual-robot`
exit 2 quoting a numpy repr, 1e308 was integrated raw)."""

import socket
import threading

import numpy as np
import pytest

from urpc.errors import SimulationError
from urpc.robot.packet import HELLO, STOP, decode_state, encode_torque
from urpc.robot.virtual import VirtualArm
from urpc.robot.virtual_server import serve


@pytest.mark.parametrize("bad", [[np.nan, 0.0], [np.inf, -np.inf]], ids=["nan", "inf"])
def test_a_non_finite_torque_is_dropped_and_counted(rr_rig, bad):
    _, plant, _ = rr_rig
    arm = VirtualArm(plant, 1e-3)
    assert not arm.receive(0.0, 0, np.array(bad))
    assert arm.rejected == 1 and not arm.armed and arm.torques == 0
    assert arm.receive(0.0, 0, np.zeros(2)) and arm.armed
    arm.advance()
    assert not arm.receive(0.001, 1, np.array(bad))
    arm.advance()  # the last valid torque holds; the period is late, the state finite
    assert arm.late == 1 and np.isfinite(arm.state.q).all() and not arm.braked


def test_a_torque_beyond_the_effort_limits_is_clipped_to_them(rr_rig):
    _, plant, _ = rr_rig
    arm = VirtualArm(plant, 1e-3)
    assert np.array_equal(arm.effort_limit, [1000.0, 1000.0])  # the URDF's
    assert arm.receive(0.0, 0, np.array([1e308, -5.0]))
    assert arm.clipped == 1
    arm.advance()
    assert np.array_equal(arm.applied, [1000.0, -5.0]) and np.isfinite(arm.state.qd).all()


def test_a_plant_that_diverges_brakes_the_arm_with_the_reason(rr_rig, monkeypatch):
    _, plant, _ = rr_rig
    arm = VirtualArm(plant, 1e-3)
    arm.receive(0.0, 0, np.zeros(2))

    def diverge(tau, duration):
        raise SimulationError("the pinocchio plant diverged at t = 0.001 s")

    monkeypatch.setattr(arm.plant, "step", diverge)
    arm.advance()
    assert arm.braked and arm.stop_reason == "stopped: the pinocchio plant diverged at t = 0.001 s"
    assert np.all(arm.state.qd == 0)


def test_the_server_drops_a_non_finite_torque_and_reports_it(rr_rig):
    """In process, over UDP on 127.0.0.1: HELLO, one state, a NaN torque, STOP; the arm is never
    armed (so no wall-clock watchdog is involved) and the report counts the packet."""
    _, plant, _ = rr_rig
    arm = VirtualArm(plant, 1e-3)
    ports, reports = [], []
    ready = threading.Event()

    def on_ready(port):
        ports.append(port)
        ready.set()

    server = threading.Thread(
        target=lambda: reports.append(
            serve(arm, 0, max_duration=60, wait_for_client=60, ready=on_ready)
        )
    )
    server.start()
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        assert ready.wait(30)
        address = ("127.0.0.1", ports[0])
        client.settimeout(30)
        client.sendto(encode_torque(0, np.zeros(2), HELLO), address)
        state = decode_state(client.recv(65536), 2)
        client.sendto(encode_torque(state.seq, np.array([np.nan, 0.0])), address)
        client.sendto(encode_torque(0, np.zeros(2), STOP), address)
        server.join(60)
    finally:
        client.close()
    (report,) = reports
    assert report.reason == "stopped on request of the controller (end of run)"
    assert report.bad_packets == 1 and report.non_finite_torques == 1
    assert report.torques_received == 0 and arm.rejected == 1
    assert "1 malformed (1 with a non-finite torque, dropped)" in report.lines()[1]
