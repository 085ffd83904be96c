"""The safety layer: clipping and counting, rate limits, state faults, the safe commands."""

import numpy as np
import pytest

import urpc
from urpc.robot.safety import SafetyLayer


def layer(**options):
    return SafetyLayer(
        [10.0, 5.0],
        1e-3,
        position_limits=(np.array([-1.0, -1.0]), np.array([1.0, 1.0])),
        velocity_limit=[2.0, 2.0],
        **options,
    )


def test_torque_above_the_limit_is_clipped_and_counted():
    safety = layer()
    out, fault = safety.limit(0.0, np.array([12.0, -1.0]))
    assert fault is None and out.tolist() == [10.0, -1.0] and safety.clipped
    out, _ = safety.limit(0.001, np.array([1.0, -7.0]))
    assert out.tolist() == [1.0, -5.0]
    out, _ = safety.limit(0.002, np.array([1.0, 1.0]))
    assert not safety.clipped
    assert safety.counts["torque_limit"] == 2 and safety.total == 2
    assert [e.joints for e in safety.events] == [(0,), (1,)]


def test_torque_rate_is_limited_from_the_last_command():
    safety = layer(torque_rate_limit=1000.0)  # 1 N m per 1 ms period
    out, _ = safety.limit(0.0, np.array([3.0, 0.5]))
    assert out.tolist() == [1.0, 0.5]
    out, _ = safety.limit(0.001, np.array([3.0, 0.5]))
    assert out.tolist() == [2.0, 0.5]
    assert safety.counts["torque_rate"] == 2


def test_state_faults():
    safety = layer(position_margin=0.1, velocity_margin=0.25)
    assert safety.check_state(0.0, np.array([0.89, 0.0]), np.array([1.49, 0.0])) is None
    assert safety.check_state(0.0, np.array([0.91, 0.0]), np.zeros(2)).kind == "position_limit"
    assert safety.check_state(0.0, np.zeros(2), np.array([0.0, -1.51])).kind == "velocity_limit"
    fault = safety.check_state(0.0, np.array([np.nan, 0.0]), np.zeros(2))
    assert fault.kind == "non_finite_state" and fault.joints == (0,)
    assert safety.counts["position_limit"] == safety.counts["velocity_limit"] == 1


def test_a_non_finite_torque_is_a_fault_and_gives_the_safe_command():
    safety = layer(safe_mode="zero")
    out, fault = safety.limit(0.5, np.array([np.inf, 0.0]))
    assert fault.kind == "non_finite_torque" and out.tolist() == [0.0, 0.0]


def test_damping_brake_opposes_motion_within_the_limits():
    safety = layer(damping=4.0)
    assert safety.safe_command(np.array([1.0, -2.0])).tolist() == [-4.0, 5.0]
    assert layer(safe_mode="zero").safe_command(np.array([1.0, 1.0])).tolist() == [0.0, 0.0]


def test_defaults_come_from_the_urdf_efforts():
    robot = urpc.load_robot("ur5")
    safety = SafetyLayer.for_robot(robot, 1e-3)
    assert np.array_equal(safety.torque_limit, robot.effort_limit)
    with pytest.raises(urpc.InputError, match="safe mode"):
        SafetyLayer.for_robot(robot, 1e-3, safe_mode="hover")


def test_a_finite_state_far_out_is_out_of_range_not_non_finite():
    # q @ q overflowed for 1e300 (with a numpy warning): it was reported as a non-finite state.
    import warnings

    safety = layer()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fault = safety.check_state(0.1, np.array([1e300, 0.0]), np.zeros(2))
        assert fault.kind == "position_limit" and "joint 1 at 1e+300" in fault.detail
        fault = safety.check_state(0.1, np.zeros(2), np.array([0.0, -1e200]))
        assert fault.kind == "velocity_limit"
        out, fault = safety.limit(0.1, np.array([1e300, -1e300]))
    assert fault is None and out.tolist() == [10.0, -5.0]  # clipped, not a non-finite torque
    fault = safety.check_state(0.2, np.array([np.nan, 1e300]), np.zeros(2))
    assert fault.kind == "non_finite_state" and fault.joints == (0,)
