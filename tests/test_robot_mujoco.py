"""The virtual robot's MuJoCo backend (``VirtualArm(..., backend="mujoco")``, ``urpc virtual-robot
--plant mujoco``) against its Pinocchio backend.

Reference: the Pinocchio arm under the same torques. Both backends integrate each period with the
same classical RK4 scheme and the same step (two steps per period), MuJoCo's ``mjINT_RK4`` and the
Pinocchio plant's own, so they differ only by the rounding of two dynamics algorithms (CRBA and a
solve against ABA, ~1e-15 per step), amplified by the arm's sensitivity: measured at most 9e-16
(rad, rad/s) in the states and 3e-12 N m in the closed loop's torques (peak 466 N m) over these
runs. ``TOLERANCE`` keeps six orders of margin for other machines' rounding and is still far below
what a wrong model (a mass, a lever, a joint order, a torque applied one period off) would give:
the states move by ~0.1 rad, a torque mismatch of 1 N m over one period shifts them by ~1e-7 rad.
"""

from __future__ import annotations

import numpy as np
import pytest

import urpc
from urpc.robot.loop import ControlLoop
from urpc.robot.runner import run
from urpc.robot.safety import SafetyLayer
from urpc.robot.virtual import ArmOptions, FakeClock, LockstepRobot, VirtualArm
from urpc.robot.watchdog import Watchdog

pytest.importorskip("mujoco")

#: Agreement of the two backends' states [rad, rad/s] (module docstring).
TOLERANCE = 1e-9
BACKENDS = ("pinocchio", "mujoco")


@pytest.mark.parametrize("delay", [0, 1])
def test_mujoco_arm_follows_the_pinocchio_arm_under_the_same_torques(rr_rig, delay):
    """500 periods of seeded torques around gravity compensation, sent as a loop would (the
    torque answering each sample), then silence until the arm's watchdog brakes: the same
    measured states at every sample, and both arms braked at the same sample, held still."""
    _, plant, _ = rr_rig
    arms = {
        backend: VirtualArm(plant, 1e-3, ArmOptions(delay=delay), q0=[0.3, -0.4], backend=backend)
        for backend in BACKENDS
    }
    assert [arm.plant.kind for arm in arms.values()] == list(BACKENDS)
    rng = np.random.default_rng(7)
    states = {backend: [] for backend in BACKENDS}
    for k in range(530):
        tau = None
        if k < 500:
            q = arms["pinocchio"].state[0]
            tau = plant.g(q) + rng.normal(0.0, 20.0, 2)
        for backend, arm in arms.items():
            arm.check_watchdog(k * 1e-3)
            states[backend].append(np.concatenate(arm.measure()))
            if tau is not None:
                arm.receive(k * 1e-3 + 1e-4, arm.wire_seq, tau)
            arm.advance()
    pin, mj = np.array(states["pinocchio"]), np.array(states["mujoco"])
    assert np.ptp(pin[:500, :2], axis=0).min() > 0.05  # a real motion
    np.testing.assert_allclose(mj, pin, rtol=0, atol=TOLERANCE)
    # The last torque arrived at 0.4991 s: braked at the first check more than 20 ms later,
    # 0.520 s; the periods in between (but the first with delay 1) held it and counted late.
    for arm in arms.values():
        assert arm.braked and arm.stopped_at == pytest.approx(0.520)
        assert arm.late == 20 - delay
    assert np.all(pin[-5:, 2:] == 0) and np.all(mj[-5:, 2:] == 0)  # braked: held still


def _lockstep(plant, controller, robot, backend, delay):
    clock = FakeClock()
    arm = VirtualArm(plant, 1e-3, ArmOptions(delay=delay), q0=[0.02, -0.02], backend=backend)
    loop = ControlLoop(controller, urpc.PaperTrajectory())
    safety = SafetyLayer.for_robot(robot, 1e-3)
    report = run(LockstepRobot(arm, clock, 1e-4), loop, safety, Watchdog(1e-3), 1.0, clock=clock)
    return report, loop, safety


def test_closed_loop_through_the_robot_loop_on_the_mujoco_arm(rr):
    """The delayed interval law, the safety layer and the watchdog in lock step with the MuJoCo
    arm behind a one-sample delay (paper's arm, shipped true plant, 1 s): the run completes, no
    intervention, the law tracks within epsilon, and the logged states and torques are the
    Pinocchio arm's run."""
    box = urpc.load_uncertainty("rr_planar", rr)
    plant = box.plant(rr, urpc.load_parameter_point("rr_planar", rr, box))
    controller = urpc.synthesize(rr, box, 1e-2, sample_period=1e-3, delay=1)
    runs = {backend: _lockstep(plant, controller, rr, backend, 1) for backend in BACKENDS}
    report, loop, safety = runs["mujoco"]
    assert report.cycles == runs["pinocchio"][0].cycles
    assert report.ok and report.cycles == 1001
    assert safety.total == 0
    mj, pin = loop.series(), runs["pinocchio"][1].series()
    np.testing.assert_allclose(mj["q"], pin["q"], rtol=0, atol=TOLERANCE)
    np.testing.assert_allclose(mj["torque_sent"], pin["torque_sent"], rtol=1e-6, atol=1e-6)
    error = np.linalg.norm(mj["q_desired"] - mj["q"], axis=1)
    assert error[-250:].max() < 1e-2  # epsilon over the last quarter
