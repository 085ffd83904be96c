"""Real joints (issue 12): armature, viscous damping and Coulomb friction, each uncertain.

References: Pinocchio plants rebuilt per sample for the rigid part and the closed-form joint terms
(with the set-valued Coulomb law at its extremes near zero velocity) for the bound; a scalar ODE
integrated by scipy for the plant; MuJoCo's own treatment of armature, damping and frictionloss
as the independent cross-check.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from conftest import ROOT
from scipy.integrate import solve_ivp

import urpc
from urpc.model.joint_dynamics import STICTION_VELOCITY, friction_shape
from urpc.model.parameter_box import JOINTS
from urpc.model.uncertainty import outside_box, parse_uncertainty
from urpc.sim.plants import make_plant
from urpc.studies.scenario import run_scenario

UR5_DRIVES = {
    "joints": {
        "shoulder_pan_joint": {"armature": [0.2, 0.6], "damping": [0.5, 5], "friction": "50%",
                               "nominal": {"armature": 0.4, "damping": 2, "friction": 3}},
        "elbow_joint": {"armature": "50%", "friction": [1, 4], "nominal": {"armature": 0.3}},
        "wrist_3_joint": {"damping": [0.2, 1.5], "friction": [0.5, 1.5]},
    },
    "links": {"forearm_link": {"mass": "20%", "com_x": "+-0.02"}},
}  # fmt: skip


@pytest.fixture(scope="module")
def ur5_box(ur5):
    return parse_uncertainty(UR5_DRIVES, ur5)


# ------------------------------------------------------------------------------ the format
def test_nominal_values_follow_the_documented_rules(rr):
    box = parse_uncertainty(
        {
            "joints": {
                "joint1": {"armature": [0.1, 0.3]},  # the URDF's 0 lies outside
                "joint2": {"friction": "50%", "nominal": {"friction": 2}},
            }
        },
        rr,
    )
    joints = box.joints
    assert joints.nominal[0, 0] == pytest.approx(0.2)  # the middle of [0.1, 0.3]
    assert (joints.lower[2, 1], joints.upper[2, 1]) == (1.0, 3.0)
    assert not joints.uncertain[:, 1][:2].any()  # joint2's armature and damping stay exact
    nominal = box.nominal_robot(rr)
    np.testing.assert_array_equal(nominal.joint_parameters, joints.nominal)
    q = np.array([0.3, -1.1])
    np.testing.assert_allclose(nominal.M(q) - rr.M(q), np.diag([0.2, 0.0]), atol=1e-14)


def test_a_relative_interval_around_zero_with_a_negative_end_is_refused(rr):
    with pytest.raises(urpc.InputError, match="negative lower end"):
        parse_uncertainty({"joints": {"joint1": {"damping": "+-0.5"}}}, rr)


def test_a_locked_joint_has_no_drive(panda):
    with pytest.raises(urpc.InputError, match="'panda_finger_joint1' is locked"):
        parse_uncertainty({"joints": {"panda_finger_joint1": {"friction": [0, 1]}}}, panda)


def test_urdf_dynamics_are_nominal_values_for_a_joints_section():
    z1 = urpc.load_robot("z1")  # its URDF has <dynamics damping="1" friction="1"> (2 on joint 2)
    assert not z1.joint_parameters.any()  # loaded rigid
    np.testing.assert_array_equal(z1.urdf_dynamics[1], [1, 2, 1, 1, 1, 1, 1])
    assert parse_uncertainty({"links": {}}, z1).joints is None  # no section: a rigid arm
    box = parse_uncertainty({"joints": {"joint1": {"friction": "10%"}}}, z1)
    assert (box.joints.lower[2, 0], box.joints.upper[2, 0]) == pytest.approx((0.9, 1.1))
    # Listed or not, every joint then has its URDF drive (exact where not listed).
    np.testing.assert_array_equal(box.joints.nominal[1:], z1.urdf_dynamics)
    assert box.joints.uncertain.sum() == 1 and box.nominal_robot(z1).has_joint_friction


def test_parameter_point_joints_and_outside_box(tmp_path, ur5, ur5_box):
    path = tmp_path / "point.yaml"
    path.write_text("joints: {shoulder_pan_joint: {friction: 4.4, armature: 0.7}}\n")
    point = urpc.load_parameter_point(path, ur5, ur5_box)
    plant = ur5_box.plant(ur5, point)
    assert plant.joint_parameters[2, 0] == 4.4 and plant.joint_parameters[0, 0] == 0.7
    assert outside_box(ur5_box, point) == ["shoulder_pan_joint.armature"]


def test_vertices_and_draws_cover_the_joint_box(ur5_box):
    joints = ur5_box.joints
    n_links = sum(int(b.uncertain.sum()) for b in ur5_box.links)
    assert ur5_box.n_uncertain == n_links + int(joints.uncertain.sum())
    ends = np.stack([ur5_box.vertex(k).joints for k in range(0, 2**ur5_box.n_uncertain, 97)])
    on_an_end = (ends == joints.lower) | (ends == joints.upper)
    assert on_an_end.all()
    draws = np.stack([ur5_box.sample(np.random.default_rng(k)).joints for k in range(50)])
    assert (draws >= joints.lower).all() and (draws <= joints.upper).all()
    assert draws[:, joints.uncertain].std(axis=0).min() > 0


# ------------------------------------------------------------------------------ the bound
def _true_w(plant, nominal, q, qd, qd_a, qdd_a, coulomb):
    """The mismatch with Pinocchio's rigid terms and the closed-form joint terms (the plant's drive
    torque at ``qd`` minus the nominal drive along ``qd_a``), for a Coulomb friction torque
    ``coulomb`` (a member of the set-valued law at ``qd``)."""
    _, damping, _ = plant.joint_parameters
    _, damping0, friction0 = nominal.joint_parameters
    rigid = (
        (plant.M(q) - nominal.M(q)) @ qdd_a  # armature included on both sides
        + (plant.C(q, qd) - nominal.C(q, qd)) @ qd_a
        + plant.g(q)
        - nominal.g(q)
    )
    return rigid + damping * qd - damping0 * qd_a + coulomb - friction0 * friction_shape(qd_a)


def _coulomb_members(friction, qd, rng):
    """Members of the set-valued law at ``qd``: ``Fc sign(qd)`` where sliding; both ends and a
    random point of ``[-Fc, Fc]`` inside the stiction band (the regularized plants lie there)."""
    sliding = np.abs(qd) >= STICTION_VELOCITY
    members = [np.where(sliding, friction * np.sign(qd), sign * friction) for sign in (-1, 1)]
    members.append(
        np.where(sliding, friction * np.sign(qd), friction * rng.uniform(-1, 1, qd.size))
    )
    return members


@pytest.mark.parametrize("method", ["vertex", "hull", "rigorous"])
def test_the_bound_encloses_the_joint_terms_on_plants_of_the_box(method, ur5, ur5_box):
    bound = urpc.make_bound(method, ur5, ur5_box)
    nominal = ur5_box.nominal_robot(ur5)
    rng = np.random.default_rng(7)
    n_states = 8 if method == "rigorous" else 40
    scales = [1e-5, 5e-4, STICTION_VELOCITY, 2e-3, 1.0, 0.0]  # inside, at and past the band
    violations = checks = 0
    for k in range(n_states):
        q = rng.uniform(-np.pi, np.pi, 6)
        qd = scales[k % len(scales)] * rng.choice([-1, 1], 6) * rng.uniform(0.5, 1.0, 6)
        if k % len(scales) == 2:
            qd = STICTION_VELOCITY * rng.choice([-1, 1], 6)  # exactly on the band's edge
        qd_a, qdd_a = rng.uniform(-1, 1, 6), rng.uniform(-5, 5, 6)
        lower, upper = bound.enclose(q, qd, qd_a, qdd_a)
        points = [ur5_box.sample(rng) for _ in range(4)]
        points += [ur5_box.vertex(int(rng.integers(2**ur5_box.n_uncertain))) for _ in range(4)]
        for point in points:
            plant = ur5_box.plant(ur5, point)
            for coulomb in _coulomb_members(plant.joint_parameters[2], qd, rng):
                w = _true_w(plant, nominal, q, qd, qd_a, qdd_a, coulomb)
                violations += int(np.sum((w < lower) | (w > upper)))
                checks += 6
    assert checks > 0 and violations == 0


def test_the_joint_part_is_the_exact_range(ur5):
    """Each joint parameter enters one row once: the enclosure is the range over the box's
    vertices (closed form), up to the rounding inflation."""
    box = parse_uncertainty({"joints": UR5_DRIVES["joints"]}, ur5)
    bound = urpc.make_bound("vertex", ur5, box)
    joints = box.joints
    rng = np.random.default_rng(3)
    for _ in range(20):
        q, qd_a = rng.uniform(-3, 3, 6), rng.uniform(-1, 1, 6)
        qd = rng.uniform(0.01, 1, 6) * rng.choice([-1, 1], 6)  # sliding: sign known
        qdd_a = rng.uniform(-5, 5, 6)
        lower, upper = bound.enclose(q, qd, qd_a, qdd_a)
        corners = [
            (ends[0] - joints.nominal[0]) * qdd_a
            + ends[1] * qd
            - joints.nominal[1] * qd_a
            + ends[2] * np.sign(qd)
            - joints.nominal[2] * friction_shape(qd_a)
            for ends in (
                np.where(np.array(bits)[:, None], joints.upper, joints.lower)
                for bits in np.ndindex(2, 2, 2)
            )
        ]
        np.testing.assert_allclose(lower, np.min(corners, axis=0), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(upper, np.max(corners, axis=0), rtol=1e-9, atol=1e-9)


def test_inertia_bounds_carry_the_armature_interval(ur5, ur5_box):
    from urpc.model.inertia_bounds import InertiaBounds

    bounds = InertiaBounds(ur5, ur5_box)
    rng = np.random.default_rng(5)
    for _ in range(6):
        q = rng.uniform(-3, 3, 6)
        plant = ur5_box.plant(ur5, ur5_box.vertex(int(rng.integers(2**ur5_box.n_uncertain))))
        M = plant.M(q)
        assert np.linalg.eigvalsh(M - bounds.lower(q))[0] >= -1e-10
        assert np.linalg.eigvalsh(bounds.upper(q) - M)[0] >= -1e-10
    # The armature's own ends are reached: the lower bound is no heavier than the lightest drive.
    q = np.zeros(6)
    light = ur5_box.plant(ur5, {JOINTS: ur5_box.joints.lower})
    assert np.linalg.eigvalsh(light.M(q) - bounds.lower(q))[0] >= -1e-10


# ------------------------------------------------------------------------------ the plants
@pytest.fixture(scope="module")
def pendulum(rr):
    """The RR arm with joint 2 locked: one joint, with armature, damping and friction."""
    robot = urpc.load_robot("rr_planar", locked_joints=["joint2"])
    return robot.with_joint_parameters(np.array([[0.3], [0.8], [2.0]]))


def _scalar_reference(robot, tau, q0, qd0, duration):
    """The set-valued law while sliding, integrated by scipy: ``(M + Ia) qdd = tau - g(q) - Dv qd
    - Fc sign(qd)`` (``M`` of the locked arm is constant about the fixed axis)."""
    inertia = float(robot.M(np.zeros(1))[0, 0])  # armature included
    _, damping, friction = robot.joint_parameters[:, 0]

    def f(t, x):
        g = float(robot.g(np.array([x[0]]))[0])
        return [x[1], (tau - g - damping * x[1] - friction * np.sign(x[1])) / inertia]

    return solve_ivp(f, (0, duration), [q0, qd0], rtol=1e-11, atol=1e-12).y[:, -1]


def test_the_pinocchio_plant_matches_the_scalar_law_while_sliding(pendulum):
    plant = make_plant("pinocchio", pendulum)
    plant.reset(np.array([0.2]), np.array([0.5]))
    for _ in range(300):
        state = plant.step(np.array([200.0]), 1e-3)
    assert state.qd[0] > 0.1  # slid the whole time
    reference = _scalar_reference(pendulum, 200.0, 0.2, 0.5, 0.3)
    # Lie splitting is first order in the friction: error ~ h (1e-4 s) times the friction rate.
    assert abs(state.q[0] - reference[0]) < 2e-5
    assert abs(state.qd[0] - reference[1]) < 2e-4


def test_a_joint_held_below_its_friction_sticks_within_the_band(pendulum):
    plant = make_plant("pinocchio", pendulum)
    q0 = np.array([0.7])
    holding = float(pendulum.g(q0)[0]) + 0.5 * pendulum.joint_parameters[2, 0]
    plant.reset(q0)
    speeds = []
    for _ in range(500):
        state = plant.step(np.array([holding]), 1e-3)
        speeds.append(abs(state.qd[0]))
    assert max(speeds) < STICTION_VELOCITY  # creeps inside the band, as documented
    assert abs(state.q[0] - q0[0]) <= STICTION_VELOCITY * 0.5
    # Past the friction it breaks away, as the set-valued law from rest does.
    breaking = float(pendulum.g(q0)[0]) + 3.0 * pendulum.joint_parameters[2, 0]
    plant.reset(q0)
    for _ in range(200):
        state = plant.step(np.array([breaking]), 1e-3)
    reference = _scalar_reference(pendulum, breaking, q0[0], 1e-12, 0.2)
    assert abs(state.q[0] - reference[0]) < 1e-4


def test_mujoco_agrees_with_pinocchio_on_open_loop_responses(ur5, ur5_box):
    pytest.importorskip("mujoco")
    rng = np.random.default_rng(11)
    worst = 0.0
    for index in rng.integers(0, 2**ur5_box.n_uncertain, 3):
        robot = ur5_box.plant(ur5, ur5_box.vertex(int(index)))
        states = []
        for kind in ("pinocchio", "mujoco"):
            plant = make_plant(kind, robot)
            plant.reset(np.zeros(6), np.array([0.5, -0.5, 0.3, 0.2, -0.2, 0.0]))
            for k in range(400):
                tau = np.array([5.0, 60.0, 20.0, 1.0, 1.0, 0.4]) * np.cos(3.0 * k * 1e-3)
                state = plant.step(tau, 1e-3)
            states.append(state)
        worst = max(worst, np.abs(states[0].q - states[1].q).max())
    assert worst < 1e-3  # rad after 0.4 s (measured 2.2e-4), sticking phases included


# ------------------------------------------------------------------------------ closed loop
@pytest.mark.parametrize("plant", ["pinocchio", "mujoco"])
@pytest.mark.parametrize("name", ["ur5/joint_friction", "panda/joint_friction"])
def test_the_joint_friction_scenarios_meet_epsilon(name, plant):
    if plant == "mujoco":
        pytest.importorskip("mujoco")
    scenario = urpc.load_scenario(name).with_overrides(duration=3.0, plant=plant)
    result = run_scenario(scenario)
    assert result.metrics["met"], result.metrics


def test_the_certificate_counts_the_joint_terms(rr, rr_box):
    """The same controller settings, box with and without drives: the drives' mismatch can
    only raise the floor (Coulomb counts as disturbance), and the floor stays finite."""
    drives = dataclasses.replace(
        rr_box,
        joints=parse_uncertainty(
            {
                "joints": {
                    "joint1": {"armature": [0.1, 0.3], "friction": [0.5, 1.5]},
                    "joint2": {"damping": [0, 2], "friction": [0.2, 0.6]},
                }
            },  # fmt: skip
            rr,
        ).joints,
    )
    floors = []
    for box in (rr_box, drives):
        controller = urpc.synthesize(rr, box, epsilon=1e-2, sample_period=5e-4)
        certificate = urpc.certify(
            controller, urpc.PaperTrajectory(), duration=4.0, disturbance_bound=1.0
        )
        floors.append(certificate.epsilon_floor)
    assert np.isfinite(floors[1]) and floors[1] > floors[0]


def test_the_controller_compensates_the_nominal_drive_along_the_reference(ur5, ur5_box):
    """The compiled call the control step uses adds exactly ``Ia0 qdd_a + Dv0 qd_a + Fc0
    sat(qd_a / v_s)`` (closed form) to the nominal torque, and the same enclosure as
    :meth:`JointBox.enclose`."""
    bound = urpc.make_bound("vertex", ur5, ur5_box)
    joints = ur5_box.joints
    rng = np.random.default_rng(2)
    for scale in (1.0, 5e-4):
        qd, qd_a, qdd_a = (scale * rng.uniform(-1, 1, 6) for _ in range(3))
        torque, lower, upper = np.zeros(6), np.zeros(6), np.zeros(6)
        bound.add_joint_terms(lower, upper, qd, qd_a, qdd_a, torque=torque)
        expected = (
            joints.nominal[0] * qdd_a
            + joints.nominal[1] * qd_a
            + joints.nominal[2] * np.clip(qd_a / STICTION_VELOCITY, -1, 1)
        )
        np.testing.assert_allclose(torque, expected, rtol=1e-14, atol=1e-15)
        np.testing.assert_array_equal((lower, upper), joints.enclose(qd, qd_a, qdd_a))


def test_check_lists_the_drives_and_says_when_urdf_dynamics_are_unused(tmp_path, capsys):
    from urpc.cli import main

    box = str(ROOT / "robots" / "ur5" / "uncertainty_joint_friction.yaml")
    assert main(["check", "ur5", "--uncertainty", box, "--json"]) == 0
    drives = json.loads(capsys.readouterr().out)["drives"]
    assert len(drives) == 18 and all(d["uncertain"] for d in drives)
    assert {d["unit"] for d in drives} == {"kg m^2", "N m s/rad", "N m"}
    rigid = tmp_path / "box.yaml"
    rigid.write_text("links: {}\n")
    assert main(["check", "z1", "--uncertainty", str(rigid)]) == 0
    out = capsys.readouterr().out
    assert "drives       none: rigid joints; the URDF's <dynamics> on joint1" in out
