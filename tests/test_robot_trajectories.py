"""Trajectories from files and waypoints, the streamed setpoint, and the scenario kinds."""

import numpy as np
import pytest
import yaml

import urpc
from urpc.studies.scenario import build, load_scenario, run_scenario
from urpc.trajectory_sources import Approach, check_limits

ROBOTS = urpc.load_robot("rr_planar").urdf_path.parent


def rest_samples(n=401, duration=4.0):
    t = np.linspace(0, duration, n)
    s = (1 - np.cos(np.pi * t / duration)) / 2
    return t, np.stack([0.5 * s, -0.3 * s], 1)


def test_from_samples_interpolates_c2():
    t, q = rest_samples(41)
    trajectory = urpc.from_samples(t, q)
    position, velocity, acceleration = trajectory.evaluate(t)
    assert np.allclose(position, q, atol=1e-12)  # through every sample
    assert np.allclose(velocity[[0, -1]], 0, atol=1e-12)  # starts and ends at rest
    # C2: the acceleration is continuous across a knot
    left, right = trajectory.reference(t[20] - 1e-9), trajectory.reference(t[20] + 1e-9)
    assert np.allclose(left.qdd, right.qdd, atol=1e-5)
    exact = 0.5 * (np.pi / 4) ** 2 / 2 * np.cos(np.pi * 1.05 / 4)
    assert abs(trajectory.reference(1.05).qdd[0] - exact) < 1e-3


def test_samples_that_end_moving_warn_and_rest_to_rest_ones_do_not(recwarn):
    """From q alone the spline ends at rest: data that ends mid-motion is stopped within one
    sample interval (accelerations the data does not have), which the warning says."""
    t, q = rest_samples(201, 2.0)
    urpc.from_samples(t, q)
    assert not [w for w in recwarn if "moving" in str(w.message)]
    moving = np.stack([np.sin(np.pi * t / 2.2) ** 2, 0 * t], 1)  # ends at 0.77 rad/s
    with pytest.warns(UserWarning, match=r"the samples end moving \(joint 1 at 0\.7"):
        trajectory = urpc.from_samples(t, moving)
    # What the warning is about: the spline's last interval decelerates far harder than the data.
    data_acceleration = np.abs(np.diff(moving[:, 0], 2)).max() / (t[1] - t[0]) ** 2
    ending = trajectory.evaluate(np.linspace(t[-6], t[-1], 501))[2][:, 0]
    assert np.abs(ending).max() > 10 * data_acceleration


def test_given_velocities_are_honoured():
    t = np.linspace(0, 1, 11)
    q, qd = np.sin(t)[:, None], np.cos(t)[:, None]
    trajectory = urpc.FileTrajectory(t, q, qd)
    assert np.allclose(trajectory.evaluate(t)[1], qd, atol=1e-12)


def test_csv_jump_beyond_the_acceleration_limit_names_the_sample(tmp_path):
    t, q = rest_samples()
    q[200:, 0] += 0.01
    path = tmp_path / "jump.csv"
    np.savetxt(path, np.column_stack([t, q]), delimiter=",", header="t,q1,q2", comments="")
    trajectory = urpc.load_samples(path, 2)
    with pytest.raises(urpc.InputError) as info:
        check_limits(trajectory, urpc.load_robot("rr_planar"), acceleration_limit=10, source=path)
    message = str(info.value)
    assert (
        "acceleration of joint joint1" in message
        and "sample 199" in message
        and "line 201" in message
    )


def test_bad_files_get_one_clear_error(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("t,q1,speed\n0,0,0\n1,1,1\n")
    with pytest.raises(urpc.InputError, match="unknown column 'speed'"):
        urpc.load_samples(path, 2)
    path.write_text("t,q1,q2\n0,0,0\n0,1,1\n")
    with pytest.raises(urpc.InputError, match="times must increase strictly: sample 1"):
        urpc.load_samples(path, 2)


def test_waypoints_respect_the_limits():
    trajectory = urpc.WaypointTrajectory(
        [[0, 0], [1, -1], [0.5, 0]], velocity_limit=1.0, acceleration_limit=2.0
    )
    grid = np.linspace(0, trajectory.times[-1], 2001)
    _, qd, qdd = trajectory.evaluate(grid)
    assert np.abs(qd).max() <= 1.0 + 1e-9 and np.abs(qdd).max() <= 2.0 + 1e-9
    assert np.all(trajectory.evaluate(trajectory.times)[1] == 0)  # rest at every waypoint


def test_streamed_reference_stays_smooth_across_updates():
    reference = urpc.StreamedReference([0.0, 0.0], velocity_limit=1.0, acceleration_limit=4.0)
    reference.set_target([1.0, 0.5], t=0.0)
    before = reference.reference(0.4)
    reference.set_target([-0.5, 0.0], t=0.4)  # retargeted mid-motion
    after = reference.reference(0.4)
    assert np.allclose(before.q, after.q) and np.allclose(before.qd, after.qd)
    assert np.allclose(before.qdd, after.qdd)
    assert np.allclose(reference.reference(100.0).q, [-0.5, 0.0])


def test_approach_then_trajectory():
    approach = Approach(np.array([0.3, 0.0]), urpc.PaperTrajectory(), 2.0)
    assert np.allclose(approach.reference(0.0).q, [0.3, 0.0])
    assert np.allclose(approach.reference(2.5).q, urpc.PaperTrajectory().reference(0.5).q)


def test_file_and_waypoint_scenarios_run_end_to_end(tmp_path):
    t, q = rest_samples()
    np.savetxt(
        tmp_path / "traj.csv", np.column_stack([t, q]), delimiter=",", header="t,q1,q2", comments=""
    )
    base = {
        "robot": "rr_planar",
        "uncertainty": str(ROBOTS / "uncertainty.yaml"),
        "true_parameters": str(ROBOTS / "true_parameters.yaml"),
        "duration": 1.0,
    }
    for trajectory in (
        {"kind": "file", "path": "traj.csv", "acceleration_limit": 10},
        {"kind": "waypoints", "points": [[0, 0], [0.2, -0.1]]},
    ):
        path = tmp_path / "scenario.yaml"
        path.write_text(yaml.safe_dump({**base, "trajectory": trajectory}))
        outcome = run_scenario(load_scenario(path))
        assert outcome.metrics["met"], trajectory
    path.write_text(yaml.safe_dump({**base, "trajectory": {"kind": "file", "path": "nope.csv"}}))
    with pytest.raises(urpc.InputError, match="trajectory file '.*nope.csv' does not exist"):
        build(load_scenario(path))
