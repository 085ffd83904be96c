"""Robot models: Pinocchio's M, C, g against independent references, loading and copies."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
from conftest import PANDA_FINGERS, rr_closed_form

from urpc.errors import InputError
from urpc.model.robot import load_robot
from urpc.model.uncertainty import inertia_from_physical


def test_rr_arm_matches_textbook_model_inside_the_box(rr, rr_box):
    rng = np.random.default_rng(0)
    for _ in range(50):
        q, qd = rng.uniform(-np.pi, np.pi, 2), rng.normal(size=2) * 3
        m2, lc2, I2 = rng.uniform(5, 10), rng.uniform(0.5, 0.525), rng.uniform(5 / 12, 20 / 12)
        values = rr_box.link_box("link2").nominal.copy()
        values[[0, 1, 6]] = m2, lc2, I2  # mass, com_x, iyy
        plant = rr_box.plant(rr, {"link2": values})
        M, C, g = rr_closed_form(q, qd, m2, lc2, I2)
        np.testing.assert_allclose(plant.M(q), M, atol=1e-10, rtol=0)
        np.testing.assert_allclose(plant.C(q, qd), C, atol=1e-10, rtol=0)
        np.testing.assert_allclose(plant.g(q), g, atol=1e-10, rtol=0)


def test_christoffel_property_mdot_minus_2c_is_skew(ur5):
    rng = np.random.default_rng(1)
    q, qd = rng.normal(size=6), rng.normal(size=6)
    h = 1e-6
    Mdot = (ur5.M(q + h * qd) - ur5.M(q - h * qd)) / (2 * h)
    N = Mdot - 2 * ur5.C(q, qd)
    np.testing.assert_allclose(N + N.T, 0, atol=1e-6)


def test_example_robot_data_arms_load(ur5, panda):
    assert ur5.dof == 6 and panda.dof == 7
    assert "panda_finger_joint1" not in panda.joint_names
    # The fingers' mass is carried by joint 7 after locking.
    hand_mass = sum(link.inertia.mass for link in panda.links if link.joint_index == 7)
    assert np.isclose(panda.model.inertias[7].mass, hand_mass)
    assert len(load_robot("panda", locked_joints=PANDA_FINGERS).joint_names) == 7


def test_link_inertias_sum_to_pinocchio_bodies(panda):
    # Pinocchio merged links joined by fixed joints; the per-link data must add up to its bodies.
    for j in range(1, panda.model.njoints):
        total = pin.Inertia.Zero()
        for link in panda.links:
            if link.joint_index == j:
                total += link.placement.act(link.inertia)
        np.testing.assert_allclose(
            total.toDynamicParameters(), panda.model.inertias[j].toDynamicParameters(), atol=1e-12
        )


def test_true_plant_copy_changes_only_its_link(rr):
    heavy = rr.with_link_inertias(
        {"link2": inertia_from_physical([10, 0.525, 0, 0, 1, 0, 1, 0, 0, 1])}
    )
    assert heavy.link("link2").inertia.mass == 10 and rr.link("link2").inertia.mass == 5
    assert heavy.model.inertias[1] == rr.model.inertias[1]


def test_payload_adds_its_mass_to_the_gravity_torque(rr):
    q = np.zeros(2)
    payload = pin.Inertia(2.0, np.array([0.3, 0.0, 0.0]), np.eye(3) * 1e-3)
    loaded = rr.with_payload("payload", "link2", payload)
    # The payload sits 0.3 m along link 2 (1.3 m from joint 1): gravity torques grow by m g0 x.
    np.testing.assert_allclose(loaded.g(q) - rr.g(q), [2 * 9.81 * 1.3, 2 * 9.81 * 0.3], atol=1e-12)


def test_continuous_joints_are_angles():
    robot = load_robot("double_pendulum_continuous")
    assert robot.joint_kinds == ("continuous", "continuous") and robot.dof == 2
    q = np.array([0.4, -1.1])
    config = robot.configuration(q)
    assert config.shape == (4,)
    np.testing.assert_allclose(robot.angles(config), q)
    # Gravity torque is 2 pi periodic in the angles.
    np.testing.assert_allclose(robot.g(q), robot.g(q + 2 * np.pi), atol=1e-12)


def _write(tmp_path, body: str, name="robot.urdf"):
    path = tmp_path / name
    path.write_text(body)
    return path


LINK = """<link name="{n}"><inertial><origin xyz="0 0 0.1"/><mass value="{m}"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>"""


def _urdf(joint_type="revolute", mass=1.0, extra=""):
    return f"""<robot name="test"><link name="base"/>{LINK.format(n="l1", m=mass)}
<joint name="j1" type="{joint_type}"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="10" velocity="1"/></joint>{extra}</robot>"""


@pytest.mark.parametrize("joint_type", ["floating", "planar"])
def test_unsupported_joint_types_are_named(tmp_path, joint_type):
    with pytest.raises(InputError, match=f"joint 'j1' has type '{joint_type}'"):
        load_robot(_write(tmp_path, _urdf(joint_type)))


def test_malformed_urdf_names_the_file(tmp_path):
    path = _write(tmp_path, "<robot name='x'><link name='a'></robot")
    with pytest.raises(InputError, match="robot.urdf"):
        load_robot(path)


def test_missing_file_and_unknown_name():
    with pytest.raises(InputError, match="does not exist"):
        load_robot("/nonexistent/arm.urdf")
    with pytest.raises(InputError, match="did you mean 'panda'"):
        load_robot("pandaa")


def test_joint_moving_no_mass_is_refused(tmp_path):
    with pytest.raises(InputError, match="joint 'j1' moves no mass"):
        load_robot(
            _write(
                tmp_path,
                _urdf(mass=0.0)
                .replace('ixx="0.01"', 'ixx="0"')
                .replace('iyy="0.01"', 'iyy="0"')
                .replace('izz="0.01"', 'izz="0"'),
            )
        )


def test_negative_mass_in_urdf(tmp_path):
    with pytest.raises(InputError, match="link.l1.inertial"):
        load_robot(_write(tmp_path, _urdf(mass=-1.0)))


def test_unknown_locked_joint_lists_the_joints():
    with pytest.raises(InputError, match="cannot lock unknown joint 'finger'.*panda_finger_joint1"):
        load_robot("panda", locked_joints=["finger"])


def test_locked_joint_position_is_used():
    robot = load_robot("panda", locked_joints={name: 0.04 for name in PANDA_FINGERS})
    assert robot.locked_joints == {name: 0.04 for name in PANDA_FINGERS}
    assert robot.dof == 7


# ----------------------------------------------------------------------------- URDF structure
def test_a_mimic_joint_is_refused_unless_locked_with_its_leader():
    """The Panda's second finger mimics the first: two independent joints would be simulated."""
    with pytest.raises(InputError, match=r"panda\.urdf.*'panda_finger_joint2' mimics joint"):
        load_robot("panda")
    with pytest.raises(InputError, match="lock both"):
        load_robot("panda", locked_joints=["panda_finger_joint2"])
    assert load_robot("panda", locked_joints=PANDA_FINGERS).dof == 7


def test_every_mimic_pair_is_in_the_suggested_lock_list():
    """Baxter has a mimic pair per gripper: one suggestion covers both (and works as given)."""
    with pytest.raises(InputError) as caught:
        load_robot("baxter")
    suggested = re.search(r"--lock (\w+(?:,\w+)*)", str(caught.value)).group(1).split(",")
    assert len(suggested) == 4 and "1 more mimic pair is in that list" in str(caught.value)
    assert load_robot("baxter", locked_joints=suggested).dof == 15


def test_a_mimic_joint_in_a_urdf_file_names_file_and_joint(tmp_path):
    second = """<link name="l2"><inertial><mass value="1"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="10" velocity="1"/><mimic joint="j1" multiplier="2"/></joint>"""
    path = _write(tmp_path, _urdf(extra=second))
    with pytest.raises(InputError, match=r"robot\.urdf: field 'joint\.j2\.mimic'.*'j2' mimics"):
        load_robot(path)
    # A fixed joint never moves: its mimic element has no effect (talos's grippers carry some).
    fixed = second.replace('type="revolute"', 'type="fixed"')
    assert load_robot(_write(tmp_path, _urdf(extra=fixed), "fixed_mimic.urdf")).dof == 1
    assert load_robot("talos_left_arm").dof == 7


def test_a_closed_kinematic_loop_is_reported_as_such(tmp_path):
    """A link with two parents (crashed the C++ URDF parser), and a cycle with no root."""
    closing = """<joint name="closing" type="revolute"><parent link="l1"/><child link="base"/>
<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="1"/></joint>"""
    path = _write(tmp_path, _urdf(extra=closing))
    with pytest.raises(InputError, match="closed kinematic loop.*form a cycle"):
        load_robot(path)
    second_parent = closing.replace('<child link="base"/>', '<child link="l1"/>')
    path = _write(tmp_path, _urdf(extra=second_parent), "two_parents.urdf")
    with pytest.raises(InputError, match="closed kinematic loop: link 'l1' is the child of"):
        load_robot(path)


# ----------------------------------------------------------------------------- locked joints
def test_a_lock_outside_the_limits_is_refused_not_clipped(tmp_path):
    with pytest.raises(InputError, match=r"cannot lock joint 'panda_joint1' at 10: outside"):
        load_robot("panda", locked_joints={**dict.fromkeys(PANDA_FINGERS, 0.0), "panda_joint1": 10})
    # A lock by name locks at 0; a joint whose limits exclude 0 is refused, naming them.
    path = _write(tmp_path, _urdf().replace('lower="-1" upper="1"', 'lower="0.33" upper="2"'))
    robot_with_two = path.read_text().replace(
        "</robot>",
        """<link name="l2"><inertial><mass value="1"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="1 0 0"/>
<origin xyz="0 0 0.2"/><limit lower="-1" upper="1" effort="10" velocity="1"/></joint></robot>""",
    )
    path.write_text(robot_with_two)
    with pytest.raises(InputError, match=r"at 0 \(a lock given by name only.*\[0\.33, 2\]"):
        load_robot(path, locked_joints=["j1"])
    assert load_robot(path, locked_joints={"j1": 0.33}).locked_joints == {"j1": 0.33}


def test_a_continuous_joint_can_be_locked_at_an_angle():
    full = load_robot("double_pendulum_continuous")
    locked = load_robot("double_pendulum_continuous", locked_joints={"joint1": 0.7})
    assert locked.dof == 1 and locked.locked_joints == {"joint1": 0.7}
    for angle in (0.3, -2.0):
        np.testing.assert_allclose(
            locked.g(np.array([angle])), full.g(np.array([0.7, angle]))[1:], atol=1e-12
        )
        np.testing.assert_allclose(
            locked.M(np.array([angle])), full.M(np.array([0.7, angle]))[1:, 1:], atol=1e-12
        )
    by_name = load_robot("double_pendulum_continuous", locked_joints=["joint2"])
    np.testing.assert_allclose(
        by_name.g(np.array([0.4])), full.g(np.array([0.4, 0.0]))[:1], atol=1e-12
    )


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda r: r.M(np.zeros(3)), "q"),
        (lambda r: r.g(np.zeros(1)), "q"),
        (lambda r: r.C(np.zeros(2), np.zeros(5)), "qd"),
        (lambda r: r.inverse_dynamics(np.zeros(2), np.zeros(2), np.zeros(3)), "qdd"),
        (lambda r: r.forward_dynamics(np.zeros(2), np.zeros(2), np.zeros(1)), "tau"),
        (lambda r: r.M("abc"), "q"),
    ],
)
def test_dynamics_of_a_state_of_the_wrong_size_name_the_vector(rr, call, field):
    """Not Pinocchio's multi-line C++ ValueError: one InputError naming the vector."""
    with pytest.raises(InputError) as info:
        call(rr)
    assert info.value.field == field
    message = str(info.value)
    assert ("2 joints" in message or "2 numbers" in message) and "From file" not in message
