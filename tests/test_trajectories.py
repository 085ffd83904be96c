"""Trajectories: analytic derivatives against finite differences, limits of generic ones."""

from __future__ import annotations

import numpy as np
import pytest

from urpc.errors import InputError
from urpc.trajectories import (
    PaperTrajectory,
    QuinticTrajectory,
    SinusoidTrajectory,
    covered_span,
    generic_trajectory,
    home_configuration,
)


def assert_derivatives(trajectory, times, h=1e-5, tol=1e-6):
    """qd and qdd match central differences of q and qd (relative to the signal's scale)."""
    q, qd, qdd = trajectory.evaluate(times)
    q_plus, qd_plus, _ = trajectory.evaluate(times + h)
    q_minus, qd_minus, _ = trajectory.evaluate(times - h)
    scale_v = 1 + np.abs(qd).max()
    scale_a = 1 + np.abs(qdd).max()
    np.testing.assert_allclose((q_plus - q_minus) / (2 * h), qd, atol=tol * scale_v)
    np.testing.assert_allclose((qd_plus - qd_minus) / (2 * h), qdd, atol=tol * scale_a)


def test_paper_trajectory_is_the_papers():
    trajectory = PaperTrajectory()
    t = np.linspace(0, 8, 801)
    q, qd, _ = trajectory.evaluate(t)
    shape = np.sin(np.pi * t / 2) * np.sin(np.pi * t)
    np.testing.assert_allclose(q[:, 0], np.pi / 4 * shape, atol=1e-15)
    np.testing.assert_allclose(q[:, 1], -np.pi / 8 * shape, atol=1e-15)
    np.testing.assert_allclose(q[0], 0.0, atol=0)
    np.testing.assert_allclose(qd[0], 0.0, atol=0)
    # period 4 s
    q4, _, _ = trajectory.evaluate(t + 4.0)
    np.testing.assert_allclose(q4, q, atol=1e-12)
    assert_derivatives(trajectory, np.linspace(0.01, 7.9, 400))


def test_reference_matches_evaluate():
    trajectories = [
        PaperTrajectory(),
        SinusoidTrajectory([0.1, -0.2, 0.3], [0.4, 0.2, 0.1], [0.3, 0.5, 1.0], [0.0, 1.0, -2.0]),
        QuinticTrajectory([[0, 0], [1, -1], [0.5, 2]], [0, 1.5, 2.5]),
    ]
    for trajectory in trajectories:
        for t in (0.0, 0.37, 1.5, 2.2, 9.0):
            reference = trajectory.reference(t)
            q, qd, qdd = trajectory.evaluate(t)
            np.testing.assert_allclose(reference.q, q, rtol=1e-14, atol=1e-15)
            np.testing.assert_allclose(reference.qd, qd, rtol=1e-14, atol=1e-15)
            np.testing.assert_allclose(reference.qdd, qdd, rtol=1e-14, atol=1e-15)
            assert reference.q.shape == (trajectory.dof,)


def test_sinusoid_derivatives():
    trajectory = SinusoidTrajectory([0.1, -0.2], [0.4, 0.2], [0.3, 1.7], [0.2, -np.pi / 2])
    assert_derivatives(trajectory, np.linspace(0, 5, 300))
    np.testing.assert_allclose(
        trajectory.peak_velocity, [0.4 * 2 * np.pi * 0.3, 0.2 * 2 * np.pi * 1.7]
    )


def test_quintic_derivatives_and_continuity():
    points = [[0.0, 0.0], [1.0, -1.0], [0.5, 2.0], [0.5, 2.0]]
    times = [0.5, 1.5, 2.5, 4.0]
    trajectory = QuinticTrajectory(points, times)
    # inside segments (finite differences do not straddle a knot there)
    interior = np.concatenate(
        [np.linspace(a + 1e-3, b - 1e-3, 100) for a, b in zip(times[:-1], times[1:], strict=True)]
    )
    assert_derivatives(trajectory, interior)
    # passes through the via points at rest; holds before and after
    q, qd, qdd = trajectory.evaluate(np.array(times))
    np.testing.assert_allclose(q, points, atol=1e-15)
    np.testing.assert_allclose(qd, 0.0, atol=1e-15)
    np.testing.assert_allclose(qdd, 0.0, atol=1e-12)
    q, qd, qdd = trajectory.evaluate(np.array([0.0, 10.0]))
    np.testing.assert_allclose(q, [points[0], points[-1]])
    np.testing.assert_allclose(qd, 0.0)
    # C2 across a knot: both sides agree
    for knot in times[1:-1]:
        left = trajectory.evaluate(knot - 1e-9)
        right = trajectory.evaluate(knot + 1e-9)
        for a, b in zip(left, right, strict=True):
            np.testing.assert_allclose(a, b, atol=1e-6)
    # peak velocity of one segment is 15/8 distance/duration
    t = np.linspace(0.5, 1.5, 10001)
    _, qd, _ = trajectory.evaluate(t)
    np.testing.assert_allclose(np.abs(qd).max(axis=0), 15 / 8 * np.array([1.0, 1.0]), rtol=1e-6)


@pytest.mark.parametrize("kind", ["sinusoid", "quintic"])
@pytest.mark.parametrize("robot_name", ["rr", "ur5", "panda"])
def test_generic_trajectory_respects_limits(request, robot_name, kind):
    robot = request.getfixturevalue(robot_name)
    trajectory = generic_trajectory(robot, kind, velocity_fraction=0.5)
    assert trajectory.dof == robot.dof
    t = np.linspace(0, 20, 20001)
    q, qd, qdd = trajectory.evaluate(t)
    lower, upper = robot.position_limits
    assert np.all(q >= lower - 1e-12) and np.all(q <= upper + 1e-12)
    assert np.all(np.abs(qd) <= 0.5 * robot.velocity_limit + 1e-9)
    assert np.all(np.isfinite(qdd))
    # it actually moves every joint, around the middle of the limits
    assert np.all(np.ptp(q, axis=0) > 0)
    np.testing.assert_allclose(q.mean(axis=0), home_configuration(robot), atol=0.3)
    assert_derivatives(trajectory, np.linspace(0.013, 19.9, 500))


def test_generic_sinusoid_slows_down_for_tight_velocity_limits(rr):
    fast = generic_trajectory(rr, "sinusoid", velocity_fraction=1.0, frequency=2.0)
    slow = generic_trajectory(rr, "sinusoid", velocity_fraction=0.01, frequency=2.0)
    assert np.all(fast.peak_velocity <= rr.velocity_limit + 1e-12)
    np.testing.assert_allclose(slow.peak_velocity, 0.01 * rr.velocity_limit)
    # starts at rest
    np.testing.assert_allclose(slow.reference(0.0).qd, 0.0, atol=1e-15)


def test_a_joint_with_an_empty_range_is_held_still_with_a_warning(tmp_path):
    """A URDF that writes ``lower = upper = 0`` (example-robot-data's double_pendulum): the
    generic reference cannot move that joint, and says so instead of tracking a flat line."""
    import urpc

    urdf = tmp_path / "pendulum.urdf"
    urdf.write_text(
        '<robot name="pendulum"><link name="base"/>'
        '<joint name="free" type="revolute"><parent link="base"/><child link="a"/>'
        '<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10" velocity="2"/></joint>'
        '<link name="a"><inertial><mass value="1"/><origin xyz="0 0 0.1"/>'
        '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
        '<joint name="stuck" type="revolute"><parent link="a"/><child link="b"/>'
        '<origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>'
        '<limit lower="0" upper="0" effort="0" velocity="0"/></joint>'
        '<link name="b"><inertial><mass value="1"/><origin xyz="0 0 0.1"/>'
        '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
        "</robot>"
    )
    robot = urpc.load_robot(urdf)
    with pytest.warns(UserWarning, match=r"holds joints \['stuck'\] still"):
        trajectory = generic_trajectory(robot)
    states = [trajectory.reference(t).q for t in np.linspace(0.0, 4.0, 9)]
    assert np.ptp([q[0] for q in states]) > 0.1 and np.ptp([q[1] for q in states]) == 0.0


def test_invalid_trajectories(rr):
    with pytest.raises(InputError, match="valid: sinusoid, quintic"):
        generic_trajectory(rr, "circle")
    with pytest.raises(InputError, match="amplitude_fraction"):
        generic_trajectory(rr, amplitude_fraction=1.5)
    with pytest.raises(InputError, match="increase strictly"):
        QuinticTrajectory([[0.0], [1.0]], [1.0, 1.0])
    with pytest.raises(InputError, match="shape"):
        SinusoidTrajectory([0.0, 0.0], [1.0, 2.0, 3.0], 1.0)


# ============================================================================ periods
@pytest.mark.parametrize(
    "trajectory, period",
    [
        (PaperTrajectory(), 4.0),
        (SinusoidTrajectory(home=(0.0, 1.0), amplitude=0.3, frequency=(0.25, 0.375)), 8.0),
        (SinusoidTrajectory(home=(0.0, 1.0), amplitude=(0.3, 0.0), frequency=(0.5, 0.1)), 2.0),
        (SinusoidTrajectory(home=(0.0,), amplitude=0.2, frequency=1.0, phase=0.7), 1.0),
    ],
)
def test_a_declared_period_repeats_the_reference(trajectory, period):
    """``q_d``, ``qd_d``, ``qdd_d`` at ``t + P`` equal those at ``t`` (random ``t``), and no
    shorter candidate ``P / k`` repeats them."""
    assert trajectory.period() == period
    rng = np.random.default_rng(0)
    t = rng.uniform(0, 20, 50)
    for now, later in zip(trajectory.evaluate(t), trajectory.evaluate(t + period), strict=True):
        np.testing.assert_allclose(later, now, atol=1e-9)
    for k in (2, 3):
        shifted = trajectory.evaluate(t + period / k)[0]
        assert np.max(np.abs(shifted - trajectory.evaluate(t)[0])) > 1e-3


def test_frequencies_with_no_short_common_period_have_none():
    """0.1 and 0.3 Hz are not binary fractions: their exact common period is astronomically long;
    the generic sinusoid's spread frequencies likewise; a joint at rest everywhere has none."""
    assert SinusoidTrajectory((0.0, 0.0), 0.2, (0.1, 0.3)).period() is None
    spread = 0.25 * np.linspace(1.0, 1.5, 6)  # the generic sinusoid's, for six joints
    assert SinusoidTrajectory(np.zeros(6), 0.2, spread).period() is None
    assert SinusoidTrajectory((0.0,), 0.0, 1.0).period() is None
    assert QuinticTrajectory([[0.0], [1.0]], [0.0, 1.0]).period() is None


def test_the_covered_span_is_one_period_unless_a_subclass_recomputes_the_reference():
    trajectory = PaperTrajectory()
    assert covered_span(trajectory, 119.0) == pytest.approx(4.0, rel=1e-11)
    assert covered_span(trajectory, 4.0) == 4.0  # not shorter than the duration
    assert covered_span(trajectory, 3.0) == 3.0

    class Faster(PaperTrajectory):
        def evaluate(self, t):  # a different reference that inherits the paper's period
            return super().evaluate(1.3 * np.asarray(t))

    assert covered_span(Faster(), 119.0) == 119.0

    class Declared(Faster):
        def period(self):
            return 4.0 / 1.3

    assert covered_span(Declared(), 119.0) == pytest.approx(4.0 / 1.3, rel=1e-11)
