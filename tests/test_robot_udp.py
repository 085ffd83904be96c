"""Wall-clock runs against the virtual robot process over UDP on 127.0.0.1: short, with lenient
deadlines (a loaded 2-core machine must not fail them; real-time figures are the benchmark's)."""

import json
import re
import subprocess
import sys
import time

import pytest

URPC = [sys.executable, "-m", "urpc"]


def start_robot(*options):
    process = subprocess.Popen(
        [
            *URPC,
            "virtual-robot",
            "rr_planar",
            "--port",
            "0",
            "--wait",
            "60",
            "--max-duration",
            "60",
            *options,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = process.stdout.readline()
    match = re.search(r"ready on udp://127\.0\.0\.1:(\d+)", line)
    assert match, line + process.stderr.read()
    return process, int(match.group(1))


def finish(process, timeout=60):
    out, err = process.communicate(timeout=timeout)
    return out, err


#: Lenient watchdogs for runs that test the loop: a loaded machine's late cycles, and its
#: stalls of the robot's process (the silence limit no longer grows with the late budget).
LENIENT = ["--late-budget", "100000", "--deadline-ms", "50", "--silence-ms", "250"]
#: The robot's own watchdog for runs that test the loop, not the watchdog: a loaded machine can
#: starve the loop's process for more than the default 20 ms (the watchdog has its own tests).
PATIENT_ROBOT = ["--watchdog-ms", "250"]


@pytest.mark.parametrize(
    "robot_options",
    [[], ["--first-seq", str(2**32 - 300)]],
    ids=["seq-from-0", "seq-across-the-32-bit-wrap"],
)
def test_run_meets_epsilon_against_the_virtual_robot(robot_options):
    """Also with the robot's sequence numbers wrapping (2**32 - 1, then 0) 0.3 s into the run:
    the loop keeps answering, nothing is taken for stale."""
    robot, port = start_robot(*robot_options, *PATIENT_ROBOT)
    try:
        done = subprocess.run(
            [
                *URPC,
                "run",
                "rr_planar/s3_ic1",
                "--robot-address",
                f"udp://127.0.0.1:{port}",
                "--duration",
                "1.5",
                "--json",
                *LENIENT,
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        out, _ = finish(robot)
    summary = json.loads(done.stdout)
    assert done.returncode == 0, done.stderr
    assert summary["ending"] == "completed" and summary["met"], summary
    # samples overtaken under load leave gaps in loop time, not extra cycles: the run ends when
    # loop time reaches 1.5 s
    assert summary["cycles"] + summary["lost_samples"] >= 1501 and summary["cycles"] >= 300
    assert (
        "deadline_misses" in summary
        and summary["safety_interventions"] == summary["interventions"]["torque_limit"]
    )
    assert "stopped on request of the controller" in out
    assert summary["interventions"]["stale_state"] == 0


def test_killing_the_loop_makes_the_robot_brake():
    robot, port = start_robot()
    loop = subprocess.Popen(
        [
            *URPC,
            "run",
            "rr_planar/s3_ic1",
            "--robot-address",
            f"udp://127.0.0.1:{port}",
            "--duration",
            "30",
            *LENIENT,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert loop.stderr.readline().startswith("run: connected to")
        time.sleep(0.5)  # a few hundred cycles
        loop.kill()
        loop.wait(timeout=10)
        out, _ = finish(robot)
    finally:
        if loop.poll() is None:
            loop.kill()
    assert "stopped by watchdog: no torque for" in out, out
    latency = float(re.search(r"arm braked ([\d.]+) ms after the last torque", out).group(1))
    assert latency >= 20.0 and latency < 250.0  # 20 ms plus at most a few late ticks under load


def test_no_robot_is_one_error_line():
    done = subprocess.run(
        [*URPC, "run", "rr_planar/s3_ic1", "--robot-address", "udp://10.1.2.3:5000"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2 and done.stderr.startswith("error:") and "loopback" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_scenario_that_declares_an_actuation_delay_the_law_ignores_is_warned_about(tmp_path):
    """``urpc run`` cannot change the robot's delay: when the scenario says the robot applies
    each torque one sample late and the law does not predict over it, the run says so (and the
    summary records both), rather than silently dropping the scenario's field."""
    import yaml
    from conftest import RR_DIR

    shipped = RR_DIR / "scenarios" / "s3_ic1.yaml"
    data = yaml.safe_load(shipped.read_text())
    for key in ("uncertainty", "true_parameters"):
        data[key] = str((shipped.parent / data[key]).resolve())
    data["actuation_delay"] = 1
    data["controller_options"] = {"interval": {"sampled_law": "implicit"}}
    scenario = tmp_path / "delayed.yaml"
    scenario.write_text(yaml.safe_dump(data))
    robot, port = start_robot("--delay", "1", *PATIENT_ROBOT)
    try:
        done = subprocess.run(
            [*URPC, "run", str(scenario), "--robot-address", f"udp://127.0.0.1:{port}",
             "--duration", "0.3", "--json", *LENIENT],
            capture_output=True, text=True, timeout=120,
        )  # fmt: skip
    finally:
        finish(robot)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["actuation_delay"] == 1 and summary["delay"] == 0, summary
    assert "1 sample(s) late (actuation_delay)" in done.stderr and "--delay 1" in done.stderr


def test_a_robot_with_another_number_of_joints_is_named_on_both_sides():
    """A 1-joint virtual robot (joint2 locked) and a 2-joint loop: the loop says which joints it
    expects and that the robot's states do not fit; the robot says a controller for 2 joints
    said HELLO. Neither side starts the arm."""
    process, port = start_robot("--lock", "joint2", "--wait", "6")
    done = subprocess.run(
        [*URPC, "run", "rr_planar/s3_ic1", "--robot-address", f"udp://127.0.0.1:{port}"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    out, _ = finish(process)
    assert done.returncode == 2 and done.stderr.startswith("error:"), done.stderr
    assert "Traceback" not in done.stderr and done.stderr.count("\n") == 1
    assert "2 joints (joint1, joint2)" in done.stderr and "--lock" in done.stderr
    assert "a controller for 2 joints said HELLO; this arm has 1" in out
    assert "0 states sent" in out  # the arm never started


def test_a_silence_limit_shorter_than_two_periods_is_one_error_line():
    done = subprocess.run(
        [*URPC, "run", "rr_planar/s3_ic1", "--robot-address", "udp://127.0.0.1:9",
         "--silence-ms", "1.5"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith("error: field 'silence-ms': 1.5 ms is less than two")


def _fake_robot(states):
    """A UDP 'robot' on 127.0.0.1 answering every datagram with ``states()``; returns its port
    and a function that stops it."""
    import socket
    import threading

    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(0.2)
    done = threading.Event()

    def answer():
        while not done.is_set():
            try:
                _, peer = sock.recvfrom(65536)
            except OSError:
                continue
            sock.sendto(states(), peer)

    thread = threading.Thread(target=answer, daemon=True)
    thread.start()

    def stop():
        done.set()
        thread.join(5)
        sock.close()

    return sock.getsockname()[1], stop


@pytest.mark.parametrize(
    "kind, words",
    [
        ("version", "speaks packet version 9; this urpc speaks version 1"),
        ("garbage", "answers with datagrams that are not urpc state packets"),
    ],
)
def test_a_robot_of_another_protocol_is_told_apart_from_another_arm(kind, words):
    """The message advised 'lock or unlock joints (--lock)', an option urpc run does not have,
    for a version mismatch and for garbage alike."""
    import numpy as np

    from urpc.robot.packet import encode_state

    def states():
        data = bytearray(encode_state(0, 0.0, np.zeros(2), np.zeros(2)))
        if kind == "version":
            data[4] = 9
        else:
            data[:4] = b"\x7e\x03\x8e\xbf"
        return bytes(data)

    port, stop = _fake_robot(states)
    try:
        done = subprocess.run(
            [*URPC, "run", "rr_planar/s3_ic1", "--robot-address", f"udp://127.0.0.1:{port}"],
            capture_output=True, text=True, timeout=120,
        )  # fmt: skip
    finally:
        stop()
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith("error: field 'robot-address': ") and words in done.stderr
    assert "--lock" not in done.stderr and "Traceback" not in done.stderr
