"""Bad arguments to the Python API, as a notebook user passes them: one InputError naming the
argument (never a numpy or Pinocchio error from deep inside, a silently wrong result, or a safety
check that quietly stops checking). Each case was found by a sweep of the public API; the
valid calls next to them must still work."""

from __future__ import annotations

import numpy as np
import pytest

import urpc
from urpc import ControlLoop, SafetyLayer, Watchdog
from urpc.errors import InputError


@pytest.fixture(scope="module")
def rr():
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    return robot, box, controller


Z = np.zeros(2)
T6 = np.linspace(0.0, 1.0, 6)
Q6 = np.zeros((6, 2))


def _step_twice(controller, t0, t1):
    loop = ControlLoop(controller, urpc.PaperTrajectory())
    loop.step(t0, Z, Z)
    loop.step(t1, Z, Z)


#: name -> (call(robot, box, controller), the field the error names, words of its message)
CASES = {
    # the safety layer: a NaN or negative period, a pushing brake, another arm's vectors
    "safety_nan_period": (
        lambda r, b, c: SafetyLayer.for_robot(r, float("nan"), torque_rate_limit=10),
        "period",
        "finite number > 0",
    ),
    "safety_negative_period": (
        lambda r, b, c: SafetyLayer.for_robot(r, -1e-3, torque_rate_limit=10),
        "period",
        "finite number > 0",
    ),
    "safety_negative_damping": (
        lambda r, b, c: SafetyLayer.for_robot(r, 1e-3, damping=-5),
        "damping",
        "pushes the arm along its velocity",
    ),
    "safety_nan_damping": (
        lambda r, b, c: SafetyLayer.for_robot(r, 1e-3, damping=float("nan")),
        "damping",
        "finite",
    ),
    "safety_torque_of_one_joint": (
        lambda r, b, c: SafetyLayer.for_robot(r, 1e-3).limit(0.0, np.array([1.0])),
        "tau",
        "needs (2,)",
    ),
    "safety_state_of_one_joint": (
        lambda r, b, c: SafetyLayer.for_robot(r, 1e-3).check_state(0.0, np.zeros(1), np.zeros(1)),
        "q",
        "guards 2 joints",
    ),
    "safety_state_as_text": (
        lambda r, b, c: SafetyLayer.for_robot(r, 1e-3).check_state(0.0, "ab", Z),
        "q",
        "is not 2 numbers",
    ),
    "safety_torque_limits_of_three": (
        lambda r, b, c: SafetyLayer.for_robot(r, 1e-3, torque_limit=[1, 2, 3]),
        "torque_limit",
        "",
    ),
    "safety_margin_closes_the_range": (
        lambda r, b, c: SafetyLayer.for_robot(r, 1e-3, position_margin=10),
        "position_margin",
        "leave no allowed position",
    ),
    "safety_negative_velocity_limit": (
        lambda r, b, c: SafetyLayer([10, 10], 1e-3, velocity_limit=[-1, 1]),
        "velocity_limit",
        "must be > 0",
    ),
    "safety_reversed_limits": (
        lambda r, b, c: SafetyLayer([10, 10], 1e-3, position_limits=([1, 1], [-1, -1])),
        "position_limits",
        "give lower <= upper",
    ),
    "safety_no_joints": (lambda r, b, c: SafetyLayer([], 1e-3), "torque_limit", "one per joint"),
    # a robot's name instead of the Robot (AttributeError), a number for the names (TypeError)
    "safety_for_a_robot_name": (
        lambda r, b, c: SafetyLayer.for_robot("rr_planar", 1e-3),
        "robot",
        "expected a Robot (urpc.load_robot(...), controller.robot), got str (load it first: "
        "urpc.load_robot('rr_planar'))",
    ),
    "safety_number_for_joint_names": (
        lambda r, b, c: SafetyLayer([10, 10], 1e-3, joint_names=5),
        "joint_names",
        "5: expected a list of 2 joint names (strings), or None",
    ),
    "safety_text_for_joint_names": (
        lambda r, b, c: SafetyLayer([10, 10], 1e-3, joint_names="ab"),
        "joint_names",
        "expected a list of 2 joint names",
    ),
    # the watchdog: a NaN silence never trips, a text period
    "watchdog_nan_silence": (lambda r, b, c: Watchdog(1e-3, silence=float("nan")), "silence", ""),
    "watchdog_zero_silence": (lambda r, b, c: Watchdog(1e-3, silence=0), "silence", ""),
    "watchdog_infinite_period": (lambda r, b, c: Watchdog(float("inf")), "period", ""),
    "watchdog_text_period": (lambda r, b, c: Watchdog("1e-3"), "period", "not a number"),
    "watchdog_nan_budget": (
        lambda r, b, c: Watchdog(1e-3, late_budget=float("nan")),
        "late_budget",
        "must be an integer >= 0",
    ),
    # the loop: its epsilon judges met, its period must be the law's
    "loop_negative_epsilon": (
        lambda r, b, c: ControlLoop(c, urpc.PaperTrajectory(), epsilon=-1),
        "epsilon",
        "> 0",
    ),
    "loop_nan_epsilon": (
        lambda r, b, c: ControlLoop(c, urpc.PaperTrajectory(), epsilon=float("nan")),
        "epsilon",
        "> 0",
    ),
    "loop_period_not_the_laws": (
        lambda r, b, c: ControlLoop(c, urpc.PaperTrajectory(), period=2e-3),
        "period",
        "not the controller's period 0.001",
    ),
    "loop_without_controller": (
        lambda r, b, c: ControlLoop(None, urpc.PaperTrajectory()),
        "controller",
        "expected a controller",
    ),
    "loop_infinite_time": (
        lambda r, b, c: ControlLoop(c, urpc.PaperTrajectory()).step(float("inf"), Z, Z),
        "t",
        "expected a finite time [s]",
    ),
    "loop_text_time": (
        lambda r, b, c: ControlLoop(c, urpc.PaperTrajectory()).step("0", Z, Z),
        "t",
        "expected a finite time [s]",
    ),
    # time going back: the controller's state had advanced and the log went out of order
    "loop_time_going_back": (
        lambda r, b, c: _step_twice(c, 0.002, 0.001),
        "t",
        "t = 0.001 s is before the previous step's 0.002 s: loop time must not go back",
    ),
    "loop_result_before_a_step": (
        lambda r, b, c: ControlLoop(c, urpc.PaperTrajectory()).result(),
        "result",
        "call step() at least once",
    ),
    "delayed_law_state_of_other_shape": (
        lambda r, b, c: ControlLoop(
            urpc.synthesize(r, b, 1e-2, sample_period=1e-3, delay=1), urpc.PaperTrajectory()
        ).step(0.0, np.zeros((2, 1)), Z),
        "q",
        "",
    ),
    "delayed_law_nan_velocity": (
        lambda r, b, c: urpc.synthesize(r, b, 1e-2, sample_period=1e-3, delay=1).output(
            0.0,
            Z,
            np.array([0.0, np.nan]),
            urpc.PaperTrajectory().reference(0.0),
            np.zeros(3),
        ),
        "qd",
        "[ 0. nan]",
    ),
    # references: NaN, empty, 2-D or textual joints; non-positive limits and durations
    "paper_nan_amplitude": (
        lambda r, b, c: urpc.PaperTrajectory([np.nan, 0.1]),
        "amplitude",
        "finite",
    ),
    "paper_text_amplitude": (lambda r, b, c: urpc.PaperTrajectory("ab"), "amplitude", ""),
    "sinusoid_nan_home": (
        lambda r, b, c: urpc.SinusoidTrajectory([np.nan, 0], 0.1, 0.5),
        "home",
        "finite",
    ),
    "sinusoid_nan_amplitude": (
        lambda r, b, c: urpc.SinusoidTrajectory([0, 0], np.nan, 0.5),
        "amplitude",
        "finite",
    ),
    "sinusoid_infinite_frequency": (
        lambda r, b, c: urpc.SinusoidTrajectory([0, 0], 0.1, np.inf),
        "frequency",
        "finite",
    ),
    "sinusoid_no_joint": (lambda r, b, c: urpc.SinusoidTrajectory([], 0.1, 0.5), "home", ""),
    "sinusoid_2d_home": (
        lambda r, b, c: urpc.SinusoidTrajectory([[0, 0], [0, 0]], 0.1, 0.5),
        "home",
        "one number per joint",
    ),
    "quintic_no_joint": (
        lambda r, b, c: urpc.QuinticTrajectory(np.zeros((2, 0)), [0, 1]),
        "points",
        "",
    ),
    "quintic_ragged": (
        lambda r, b, c: urpc.QuinticTrajectory([[0, 0], [1]], [0, 1]),
        "points",
        "same number of joints",
    ),
    "waypoints_negative_speed": (
        lambda r, b, c: urpc.WaypointTrajectory([[0, 0], [1, 1]], velocity_limit=-1),
        "velocity_limit",
        "> 0",
    ),
    "waypoints_zero_minimum": (
        lambda r, b, c: urpc.WaypointTrajectory([[0, 0], [1, 1]], minimum=0),
        "minimum",
        "",
    ),
    "streamed_zero_duration": (
        lambda r, b, c: urpc.StreamedReference(Z).set_target([1, 1], 0.0, duration=0),
        "duration",
        "> 0",
    ),
    "streamed_nan_start": (lambda r, b, c: urpc.StreamedReference([np.nan, 0]), "q0", "finite"),
    "streamed_limits_of_three": (
        lambda r, b, c: urpc.StreamedReference(Z, velocity_limit=[1, 1, 1]),
        "velocity_limit",
        "one per joint",
    ),
    "streamed_target_of_three": (
        lambda r, b, c: urpc.StreamedReference(Z).set_target([1, 1, 1], 0.0),
        "target",
        "one per joint",
    ),
    "samples_transposed_velocities": (
        lambda r, b, c: urpc.from_samples(T6, Q6, np.zeros((2, 6))),
        "qd",
        "give qd as q",
    ),
    "samples_accelerations_of_three_joints": (
        lambda r, b, c: urpc.from_samples(T6, Q6, Q6, np.zeros((6, 3))),
        "qdd",
        "give qdd as q",
    ),
    "samples_accelerations_without_velocities": (
        lambda r, b, c: urpc.from_samples(T6, Q6, None, Q6),
        "qdd",
        "give the velocities too",
    ),
    "samples_3d_positions": (
        lambda r, b, c: urpc.from_samples(T6, np.zeros((6, 2, 2))),
        "q",
        "(samples, joints)",
    ),
    "samples_text_times": (lambda r, b, c: urpc.from_samples("abc", Q6), "t", ""),
    # synthesis, certificate, simulation, boxes
    "synthesize_a_name": (
        lambda r, b, c: urpc.synthesize("rr_planar", b, 1e-2),
        "robot",
        "expected a Robot",
    ),
    "synthesize_text_gain": (
        lambda r, b, c: urpc.synthesize(r, b, 1e-2, Kr="3"),
        "Kr",
        "not a number",
    ),
    "certify_zero_cells": (
        lambda r, b, c: urpc.certify(c, urpc.PaperTrajectory(), duration=1.0, cells=0),
        "cells",
        "integer >= 1",
    ),
    "certify_fractional_cells": (
        lambda r, b, c: urpc.certify(c, urpc.PaperTrajectory(), duration=1.0, cells=2.5),
        "cells",
        "integer >= 1",
    ),
    "simulate_negative_gain_integral": (
        lambda r, b, c: urpc.simulate(
            b.plant(), c, urpc.PaperTrajectory(), duration=0.01, q0=Z, controller_state0=[-0.01]
        ),
        "controller_state0",
        "must be >= 0",
    ),
    "generic_reference_of_a_name": (
        lambda r, b, c: urpc.generic_trajectory("rr_planar"),
        "robot",
        "expected a Robot",
    ),
    "lock_a_text": (
        lambda r, b, c: urpc.load_robot("ur5", locked_joints="shoulder_pan_joint"),
        "locked_joints",
        "give a list of joint names",
    ),
    "lock_at_a_text_position": (
        lambda r, b, c: urpc.load_robot("rr_planar", locked_joints={"joint1": "x"}),
        "locked_joints.joint1",
        "not a finite position",
    ),
    "load_controller_of_none": (lambda r, b, c: urpc.load_controller(None), "path", "got None"),
    "save_controller_to_none": (lambda r, b, c: c.save(None), "path", "got None"),
    "epsilon_beyond_a_double": (
        lambda r, b, c: urpc.synthesize(r, b, 10**400),
        "epsilon",
        "not a (double precision) number",
    ),
    "solver_negative_tolerance": (lambda r, b, c: urpc.SolverOptions(rtol=-1), "rtol", "> 0"),
    "solver_unknown_method": (
        lambda r, b, c: urpc.SolverOptions(method="foo"),
        "method",
        "valid: RK45",
    ),
    "box_of_none": (lambda r, b, c: urpc.parse_uncertainty(None, r), "document", "'links'"),
    "plant_with_negative_mass": (
        lambda r, b, c: b.plant({"link2": np.r_[-5.0, b.links[0].nominal[1:]]}),
        "point.link2",
        "the mass -5 kg; a mass must be >= 0",
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_bad_argument_is_one_error_naming_it(case, rr):
    call, field, words = CASES[case]
    with pytest.raises(InputError) as caught:
        call(*rr)
    message = str(caught.value)
    assert f"field '{field}'" in message, message
    assert words in message, message


def test_a_controller_file_nested_too_deep_is_refused(tmp_path):
    path = tmp_path / "deep.json"
    path.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(InputError, match="not a JSON controller file"):
        urpc.load_controller(path)


def test_the_valid_calls_next_to_them_still_work(rr):
    """The checks refuse only what is wrong: the same calls with valid arguments run."""
    robot, box, controller = rr
    safety = SafetyLayer.for_robot(robot, 1e-3, torque_rate_limit=1e4, damping=5)
    out, fault = safety.limit(0.0, [1.0, 2.0])  # a list is two numbers
    assert fault is None and np.allclose(out, [1.0, 2.0])
    assert safety.check_state(0.0, [0.1, 0.2], [0.0, 0.0]) is None
    assert np.allclose(safety.safe_command([1.0, -1.0]), [-5.0, 5.0])
    nan_state = safety.check_state(0.0, np.array([np.nan, 0.0]), Z)  # a fault, not an error
    assert nan_state is not None and nan_state.kind == "non_finite_state"
    unlimited = SafetyLayer([np.inf, 10], 1e-3, position_limits=([-np.inf, -1], [np.inf, 1]))
    assert unlimited.limit(0.0, np.array([1e6, 1e6]))[0].tolist() == [1e6, 10.0]
    assert Watchdog(1e-3, silence=0.02).silence == 0.02
    loop = ControlLoop(controller, urpc.PaperTrajectory(), period=1e-3, epsilon=1e-2)
    assert loop.step(0, Z, Z).shape == (2,)  # an integer time is a time
    assert loop.step(0.0, Z, Z).shape == (2,)  # the same time again: not going back
    loop.reset()
    assert loop.step(0.0, Z, Z).shape == (2,)  # a reset starts time again
    named = SafetyLayer([10, 10], 1e-3, joint_names=("shoulder", "elbow"))  # a tuple of names
    assert named.joint_names == ("shoulder", "elbow")
    trajectory = urpc.from_samples(T6, np.linspace(0, 1, 6), np.zeros(6))  # one joint, vectors
    assert trajectory.dof == 1
    streamed = urpc.StreamedReference(Z, velocity_limit=1.0, acceleration_limit=[2.0, 2.0])
    assert streamed.set_target([0.5, 0.5], 0.0) > 0
    point = {"link2": np.r_[0.0, box.links[0].nominal[1:]]}  # a massless body is physical
    assert box.plant(point).dof == 2
    assert controller.check_state([0.5]).tolist() == [0.5]
    symmetric = SafetyLayer([10, 10], 1e-3, position_limits=(-3.0, 3.0))  # one pair for all
    assert symmetric.lower.tolist() == [-2.98, -2.98] and symmetric.upper.tolist() == [2.98] * 2
    unbounded = SafetyLayer.for_robot(robot, 1e-3, torque_limit=np.inf)  # brake's default D: 1
    assert unbounded.damping.tolist() == [1.0, 1.0]
