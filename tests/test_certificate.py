"""The certificate against simulations it must not contradict, and its reports.

The floor is a claim about every plant of the box: a simulation of any plant (vertices included)
under the certified law must end below ``max(epsilon, epsilon_floor)``. Runs where the gains
saturate (epsilon far below the floor) test the floor itself.
"""

from __future__ import annotations

import numpy as np
import pytest

import urpc
from urpc.control.certificate import certify
from urpc.trajectories import PaperTrajectory

DURATION = 3.0


def _final_error(result, window: float = 2.0) -> float:
    keep = result.t >= result.t[-1] - window
    return float(result.error_norm[keep].max())


@pytest.mark.parametrize("period", [1e-3, 1e-4])
def test_the_floor_bounds_every_vertex_plant_once_the_gains_saturate(rr, rr_box, period):
    """The floor is the ultimate bound once phi has reached its ceiling: start there (the state
    s = s_max) and ask for an epsilon far below the floor so that it never stops adapting."""
    controller = urpc.synthesize(rr, rr_box, 1e-4, sample_period=period, Kr=30.0)
    certificate = certify(controller, PaperTrajectory(), duration=DURATION, disturbance_bound=10.0)
    assert np.isfinite(certificate.epsilon_floor) and not certificate.certified
    saturated = np.array([(controller.phi_max - controller.phi_P) / controller.phi_I])
    for vertex in (0, 3, 5, 7):
        result = urpc.simulate(
            rr_box.plant(rr, rr_box.vertex(vertex)), controller, PaperTrajectory(),
            duration=DURATION, q0=np.zeros(2), disturbance_bound=10.0,
            seed=vertex, controller_state0=saturated,
        )  # fmt: skip
        assert _final_error(result) <= certificate.epsilon_floor, (vertex, certificate.summary())


def test_a_certified_1_khz_run_meets_epsilon_on_the_corners_of_table_1(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3)
    certificate = certify(controller, PaperTrajectory(), duration=10.0, disturbance_bound=10.0)
    assert certificate.certified, certificate.summary()
    for vertex in (0, 7):  # the light and the heavy corner
        result = urpc.simulate(
            rr_box.plant(rr, rr_box.vertex(vertex)), controller, PaperTrajectory(),
            duration=DURATION, q0=np.zeros(2), disturbance_bound=10.0,
            seed=vertex,
        )  # fmt: skip
        assert result.metrics["met"] and _final_error(result) <= 1e-2


def test_the_paper_law_under_a_hold_is_not_certified(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3, sampled_law="paper")
    certificate = certify(controller, PaperTrajectory(), duration=4.0, disturbance_bound=10.0)
    assert not certificate.certified
    assert certificate.failed[0].name.startswith("paper law")
    assert "implicit" in certificate.failed[0].explanation


def test_an_uncertified_period_names_the_failed_condition_and_the_period_that_works(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-3, sample_period=1e-3)
    certificate = certify(controller, PaperTrajectory(), duration=4.0, disturbance_bound=10.0)
    assert not certificate.certified
    assert certificate.failed[0].name == "ultimate bound below epsilon"
    assert f"{certificate.max_sample_period:.3g} s" in certificate.failed[0].explanation
    assert 0 < certificate.max_sample_period < 1e-3
    faster = urpc.synthesize(rr, rr_box, 1e-3, sample_period=certificate.max_sample_period * 0.99)
    again = certify(faster, PaperTrajectory(), duration=4.0, disturbance_bound=10.0)
    assert again.certified, again.summary()


def test_continuous_time_theorem_2_is_certified_for_any_epsilon(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-3)
    certificate = certify(controller, PaperTrajectory(), duration=4.0, disturbance_bound=10.0)
    assert certificate.certified and certificate.epsilon_floor == 0.0
    # Theorem 2 needs no disturbance bound in continuous time.
    assert certify(controller, PaperTrajectory(), duration=4.0).certified
    names = {c.name for c in certificate.conditions}
    assert {"Theorem 2: kappa_I > 0", "Theorem 2: phi_I > 0"} <= names


def test_a_sampled_certificate_needs_the_disturbance_bound(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-4)
    certificate = certify(controller, PaperTrajectory(), duration=4.0)
    assert not certificate.certified
    assert certificate.failed[0].name == "disturbance bound given"


def test_certificate_json_has_the_documented_fields(rr, rr_box):
    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-4)
    data = certify(controller, PaperTrajectory(), duration=4.0, disturbance_bound=10.0).to_dict()
    assert {"certified", "epsilon_floor", "max_sample_period", "conditions"} <= set(data)
    assert all({"name", "holds", "value", "limit"} <= set(c) for c in data["conditions"])


def test_the_floor_bounds_sampled_ur5_plants_once_the_gains_saturate(ur5):
    """Another arm, another box (the shipped UR5 box: payload 0-3 kg, wrist masses), plants
    drawn at vertices and inside, a generic reference; saturated gains as above."""
    from urpc.trajectories import generic_trajectory

    box = urpc.load_uncertainty("ur5", ur5)
    period = 2e-4
    controller = urpc.synthesize(ur5, box, 1e-5, sample_period=period, Kr=30.0)
    nominal = box.nominal_robot(ur5)
    trajectory = generic_trajectory(nominal)
    certificate = certify(controller, trajectory, duration=2.0, disturbance_bound=2.0)
    assert np.isfinite(certificate.epsilon_floor), certificate.summary()
    saturated = np.array([(controller.phi_max - controller.phi_P) / controller.phi_I])
    rng = np.random.default_rng(3)
    points = [box.vertex(0), box.vertex(2**box.n_uncertain - 1), box.sample(rng)]
    for k, point in enumerate(points):
        result = urpc.simulate(
            box.plant(ur5, point), controller, trajectory, duration=2.0,
            q0=trajectory.reference(0.0).q, disturbance_bound=2.0,
            seed=k, controller_state0=saturated,
        )  # fmt: skip
        assert _final_error(result, 1.0) <= certificate.epsilon_floor, (k, certificate.summary())


SLIDER = """<robot name="slider"><link name="base"/>
<link name="cart"><inertial><origin xyz="0 0 0"/><mass value="2.0"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
<joint name="x" type="prismatic"><parent link="base"/><child link="cart"/><axis xyz="1 0 0"/>
<limit lower="-1" upper="1" effort="100" velocity="2"/></joint></robot>"""


def test_a_one_joint_robot_is_certified_and_runs(tmp_path):
    """One joint: Pinocchio hands back the regressor's single row as a vector."""
    from urpc.trajectories import generic_trajectory

    (tmp_path / "slider.urdf").write_text(SLIDER)
    robot = urpc.load_robot(tmp_path / "slider.urdf")
    box = urpc.parse_uncertainty({"links": {"cart": {"mass": "20%"}}}, robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    assert controller.bound.regressor(*np.zeros((4, 1))).shape == (1, 10)
    trajectory = generic_trajectory(robot)
    certificate = certify(controller, trajectory, duration=2.0, disturbance_bound=1.0)
    assert certificate.certified, certificate.summary()
    result = urpc.simulate(
        box.plant(robot, box.vertex(1)), controller, trajectory, duration=2.0,
        q0=trajectory.reference(0.0).q, disturbance_bound=1.0,
    )  # fmt: skip
    assert result.metrics["met"]
