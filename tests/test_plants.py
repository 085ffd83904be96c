"""Tests of :mod:`urpc.sim.plants`.

References, each independent of the code under test:

* the textbook RR arm (``conftest.rr_closed_form``, no Pinocchio) integrated by scipy's DOP853 with
  tight tolerances, for the RK4 plant;
* Pinocchio's ``crba`` and ``nonLinearEffects`` for MuJoCo's mass matrix and bias forces (two
  implementations, two URDF parsers), and the textbook RR arm for MuJoCo alone;
* Richardson differences: halving an RK4 step divides the change in the trajectory by ~16.

MuJoCo is optional: its tests are skipped when ``mujoco`` is not installed.
"""

from __future__ import annotations

import sys

import numpy as np
import pinocchio as pin
import pytest
from conftest import PANDA_FINGERS, rr_closed_form
from scipy.integrate import solve_ivp

from urpc.errors import InputError, SimulationError
from urpc.model.robot import LinkInertial, Robot, load_robot
from urpc.sim.plants import PinocchioPlant, PlantState, make_plant

#: Open-loop agreement of the two plants at equal RK4 steps [rad or m]. Both integrate with the
#: same classical RK4 scheme and step, so they differ only by the rounding of two different
#: dynamics algorithms (~1e-15 per step), amplified by the unstable open-loop dynamics (measured:
#: rr 5e-15 and ur5 1e-13 over 2 s, panda 5e-11 over 1 s); 1e-8 keeps a margin of 200.
OPEN_LOOP_TOLERANCE = 1e-8
#: M and bias agreement, relative to the largest entry (measured: below 1e-14).
DYNAMICS_TOLERANCE = 1e-9

PAYLOAD = pin.Inertia(2.0, np.array([0.01, 0.02, 0.05]), np.diag([0.01, 0.02, 0.015]))

# A URDF with what the built-in robots lack: a continuous and a prismatic joint on unaligned axes,
# rotated joint origins, a massless moving link carrying a fixed link with a rotated, non-diagonal
# inertia, and joint damping and friction (which the plants must not model).
MIXED_URDF = """<?xml version="1.0"?>
<robot name="mixed">
  <link name="base"/>
  <joint name="spin" type="continuous">
    <parent link="base"/><child link="hub"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.3 -0.2 0.5"/>
    <axis xyz="0 0.6 0.8"/>
  </joint>
  <link name="hub"/>
  <joint name="hub_mount" type="fixed">
    <parent link="hub"/><child link="hub_mass"/>
    <origin xyz="0.05 0.1 -0.02" rpy="0.4 0.1 -0.7"/>
  </joint>
  <link name="hub_mass">
    <inertial>
      <origin xyz="0.02 0.03 0.1" rpy="0.2 0.5 -0.1"/>
      <mass value="3.0"/>
      <inertia ixx="0.05" ixy="0.004" ixz="-0.003" iyy="0.04" iyz="0.002" izz="0.03"/>
    </inertial>
    <visual><geometry><mesh filename="package://nowhere/hub.stl"/></geometry></visual>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="hub_mass"/><child link="carriage"/>
    <origin xyz="0.3 0 0.1" rpy="0 1.2 0"/>
    <axis xyz="1 1 0"/>
    <limit lower="-0.5" upper="0.5" effort="100" velocity="1"/>
  </joint>
  <link name="carriage">
    <inertial>
      <origin xyz="0.1 -0.05 0.02" rpy="0 0 0"/>
      <mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.015"/>
    </inertial>
    <collision><geometry><mesh filename="package://nowhere/carriage.stl"/></geometry></collision>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="carriage"/><child link="forearm"/>
    <origin xyz="0.2 0.1 0" rpy="-0.6 0 0.2"/>
    <axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="100" velocity="1"/>
    <dynamics damping="0.5" friction="0.2"/>
  </joint>
  <link name="forearm">
    <inertial>
      <origin xyz="0.0 0.2 0.05" rpy="0 0 0"/>
      <mass value="0.8"/>
      <inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.005" iyz="0" izz="0.02"/>
    </inertial>
  </link>
</robot>
"""


@pytest.fixture(scope="module")
def mujoco():
    return pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def mixed(tmp_path_factory):
    """The hand-written chain, rigid: its URDF's <dynamics> (damping 0.5, friction 0.2 on the
    elbow) are only nominal values for a box's joints: section."""
    path = tmp_path_factory.mktemp("urdf") / "mixed.urdf"
    path.write_text(MIXED_URDF)
    return load_robot(path)


@pytest.fixture(scope="module")
def mixed_with_friction(mixed):
    """The chain with the drives its URDF declares, and an armature on the slide."""
    np.testing.assert_array_equal(mixed.urdf_dynamics, [[0, 0, 0.5], [0, 0, 0.2]])
    assert not mixed.joint_parameters.any()
    return mixed.with_joint_parameters(np.vstack([[0.0, 0.3, 0.0], mixed.urdf_dynamics]))


@pytest.fixture(scope="module")
def rr_true(rr, rr_box, rr_true_point):
    return rr_box.plant(rr, rr_true_point)


def _robots(request, rr_true, mixed) -> dict[str, Robot]:
    ur5 = request.getfixturevalue("ur5")
    return {
        "rr": request.getfixturevalue("rr"),
        "rr_true": rr_true,
        "ur5": ur5,
        "ur5_payload": ur5.with_payload("payload", "wrist_3_link", PAYLOAD),
        "ur5_locked": load_robot("ur5", locked_joints={"wrist_3_joint": 0.7, "elbow_joint": 2.5}),
        "panda": request.getfixturevalue("panda"),
        "panda_open_fingers": load_robot(
            "panda", locked_joints={PANDA_FINGERS[0]: 0.02, PANDA_FINGERS[1]: 0.01}
        ),
        "mixed": mixed,
        "mixed_payload": mixed.with_payload(
            "tool",
            "forearm",
            pin.Inertia(0.5, np.array([0.1, 0.0, 0.2]), np.diag([1, 2, 2.5]) / 1e3),
        ),
    }


def _record(robot: Robot, q0: np.ndarray, periods: int, period: float, seed: int):
    """Torques of a stabilized run of the Pinocchio plant (gravity compensation, a PD pull back
    to ``q0`` and random accelerations held 50 ms), and that run's positions. Replayed open loop,
    the torques must reproduce the positions on any correct plant."""
    rng = np.random.default_rng(seed)
    plant = PinocchioPlant(robot)
    q, qd = plant.reset(q0)
    inertia = robot.M(q0)
    torques, positions = np.empty((periods, robot.dof)), np.empty((periods + 1, robot.dof))
    positions[0] = q0
    for k in range(periods):
        if k % 50 == 0:
            acceleration = rng.uniform(-20.0, 20.0, robot.dof)
        torques[k] = robot.g(q) + inertia @ (acceleration - 25.0 * (q - q0) - 10.0 * qd)
        q, qd = plant.step(torques[k], period)
        positions[k + 1] = q
    return torques, positions


def _replay(plant, q0, torques, period) -> np.ndarray:
    plant.reset(q0)
    return np.array([q0] + [plant.step(tau, period).q for tau in torques])


def _start(robot: Robot, seed: int) -> np.ndarray:
    lower, upper = robot.position_limits
    return np.random.default_rng(seed).uniform(np.maximum(lower, -2.0), np.minimum(upper, 2.0))


# ============================================================================== Plant API
def test_pinocchio_plant_matches_textbook_rr(rr_true):
    """RK4 on Pinocchio's ABA against DOP853 on the closed-form RR arm (true parameters)."""
    m2, lc2, I2 = 10.0, 0.525, 20 / 12
    period, q0, qd0 = 0.01, np.array([0.3, -0.5]), np.array([0.5, 0.0])
    torques = np.random.default_rng(0).uniform(-100.0, 100.0, (100, 2)) + [150.0, 50.0]
    plant = make_plant("pinocchio", rr_true)
    plant.reset(q0, qd0)
    x = np.concatenate((q0, qd0))
    for tau in torques:

        def rhs(t, x, tau=tau):
            M, C, g = rr_closed_form(x[:2], x[2:], m2, lc2, I2)
            return np.concatenate((x[2:], np.linalg.solve(M, tau - C @ x[2:] - g)))

        x = solve_ivp(rhs, (0, period), x, method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
        q, qd = plant.step(tau, period)
        assert np.abs(q - x[:2]).max() < 1e-9
        assert np.abs(qd - x[2:]).max() < 1e-8
    assert np.ptp(x[:2]) > 0.5  # the arm really moved
    assert plant.time == pytest.approx(1.0)


def test_pinocchio_plant_rk4_converges_to_fourth_order(ur5):
    """Halving the step divides the change of the trajectory by ~16 (measured 16.3 and 16.2)."""
    robot = ur5.with_payload("payload", "wrist_3_link", PAYLOAD)
    rng = np.random.default_rng(3)
    q0 = rng.uniform(-1, 1, robot.dof)
    g0 = robot.g(q0)
    torques = g0 + 0.3 * np.maximum(np.abs(g0), 1.0) * rng.uniform(-1, 1, (25, robot.dof))
    runs = [_replay(PinocchioPlant(robot, max_step=h), q0, torques, 0.02) for h in (0.02, 0.01, 5e-3, 2.5e-3)]  # fmt: skip
    changes = [np.abs(a - b).max() for a, b in zip(runs, runs[1:], strict=False)]
    assert 14 < changes[0] / changes[1] < 19
    assert 14 < changes[1] / changes[2] < 19


def test_state_reset_and_repr(rr):
    plant = make_plant("pinocchio", rr, max_step=5e-4)
    assert isinstance(plant, PinocchioPlant) and plant.dof == 2 and plant.max_step == 5e-4
    state = plant.reset([0.1, 0.2])
    assert isinstance(state, PlantState)
    np.testing.assert_array_equal(state.qd, [0.0, 0.0])
    state.q[0] = 99.0  # the state is a copy
    assert plant.state.q[0] == 0.1
    q, qd = plant.step(np.zeros(2), 0.003)
    assert plant.time == pytest.approx(0.003) and qd[0] < 0  # falls under gravity
    assert "PinocchioPlant('rr_planar'" in repr(plant)


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda p: p.reset([0.0]), "q"),
        (lambda p: p.reset([0.0, 0.0], [np.nan, 0.0]), "qd"),
        (lambda p: p.step([0.0, 0.0, 0.0], 1e-3), "torque"),
        (lambda p: p.step([np.inf, 0.0], 1e-3), "torque"),
        (lambda p: p.step(["a", 0.0], 1e-3), "torque"),
        (lambda p: p.step([0.0, 0.0], 0.0), "duration"),
        (lambda p: p.step([0.0, 0.0], "soon"), "duration"),
    ],
)
def test_bad_inputs_name_the_field(rr, call, field):
    plant = PinocchioPlant(rr)
    with pytest.raises(InputError) as info:
        call(plant)
    assert info.value.field == field


def test_divergence_raises(rr):
    plant = PinocchioPlant(rr)
    plant.reset([0.0, 0.0])
    with pytest.raises(SimulationError, match="diverged"):
        plant.step([1e300, 1e300], 1e-3)


def test_make_plant_errors(rr):
    with pytest.raises(InputError, match="unknown plant 'bullet'; valid: pinocchio, mujoco"):
        make_plant("bullet", rr)
    with pytest.raises(InputError, match="unknown option.*substeps.*valid: max_step"):
        make_plant("pinocchio", rr, substeps=4)
    with pytest.raises(InputError, match="max_step"):
        make_plant("pinocchio", rr, max_step=-1.0)


def test_make_plant_without_mujoco(rr, monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # makes `import mujoco` fail
    with pytest.raises(InputError, match=r"pip install 'urpc\[mujoco\]'"):
        make_plant("mujoco", rr)


# ============================================================================== MuJoCo model
@pytest.mark.parametrize(
    "name",
    [
        "rr",
        "rr_true",
        "ur5",
        "ur5_payload",
        "ur5_locked",
        "panda",
        "panda_open_fingers",
        "mixed",
        "mixed_payload",
    ],
)
def test_mujoco_dynamics_equal_pinocchio(mujoco, request, rr_true, mixed, name):
    robot = _robots(request, rr_true, mixed)[name]
    plant = make_plant("mujoco", robot)
    rng = np.random.default_rng(7)
    for _ in range(10):
        q, qd = rng.uniform(-4, 4, robot.dof), rng.uniform(-2, 2, robot.dof)
        M = robot.M(q)
        bias = pin.nonLinearEffects(robot.model, robot.data, robot.configuration(q), qd)
        np.testing.assert_allclose(plant.mass_matrix(q), M, rtol=0, atol=DYNAMICS_TOLERANCE * np.abs(M).max())  # fmt: skip
        np.testing.assert_allclose(plant.bias_forces(q, qd), bias, rtol=0, atol=DYNAMICS_TOLERANCE * np.abs(bias).max())  # fmt: skip


def test_mujoco_rr_equals_textbook(mujoco, rr_true):
    """MuJoCo alone against the closed-form RR arm: no Pinocchio computation in the loop."""
    plant = make_plant("mujoco", rr_true)
    for q, qd in [([0.3, -1.2], [0.5, 2.0]), ([2.0, 0.7], [-1.0, 0.3])]:
        M, C, g = rr_closed_form(np.array(q), np.array(qd), 10.0, 0.525, 20 / 12)
        np.testing.assert_allclose(plant.mass_matrix(q), M, rtol=1e-12)
        np.testing.assert_allclose(plant.bias_forces(q, qd), C @ qd + g, rtol=1e-12)


def test_mujoco_model_settings(mujoco, mixed_with_friction):
    robot = mixed_with_friction.with_payload("tool", "forearm", PAYLOAD)
    plant = make_plant("mujoco", robot)
    model = plant.model
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    np.testing.assert_array_equal(model.opt.gravity, robot.model.gravity.linear)
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    # The elbow's Coulomb friction is MuJoCo's frictionloss constraint; no other constraint.
    assert not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    assert model.ngeom == 0 and model.nu == 0 and model.neq == 0
    assert not model.jnt_limited.any() and not np.any(model.jnt_stiffness)
    armature, damping, friction = robot.joint_parameters
    np.testing.assert_array_equal(model.dof_armature, armature)
    np.testing.assert_array_equal(model.dof_damping, damping)
    np.testing.assert_array_equal(model.dof_frictionloss, friction)
    assert damping.tolist() == [0.0, 0.0, 0.5] and friction.tolist() == [0.0, 0.0, 0.2]
    assert armature.tolist() == [0.0, 0.3, 0.0]
    rigid = make_plant("mujoco", robot.with_joint_parameters(np.zeros((3, 3)))).model
    assert rigid.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    assert model.body("tool").mass[0] == PAYLOAD.mass
    assert sum(model.body_mass) == pytest.approx(sum(link.inertia.mass for link in robot.links))


def test_mujoco_errors(mujoco, rr, tmp_path):
    heavier = [
        LinkInertial(
            lk.name,
            lk.joint_index,
            lk.placement,
            pin.Inertia(2.0 * lk.inertia.mass, lk.inertia.lever, 2.0 * lk.inertia.inertia),
        )
        if lk.name == "link2"
        else lk
        for lk in rr.links
    ]  # links that disagree with the Pinocchio model they come with
    with pytest.raises(InputError, match="do not add up"):
        make_plant("mujoco", Robot(rr.model, heavier, "rr", rr.urdf_path))
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='x'><link name='a'>")
    with pytest.raises(InputError, match="cannot read the URDF") as info:
        make_plant("mujoco", Robot(rr.model, rr.links, "rr", broken))
    assert info.value.source == str(broken)


# ============================================================================== trajectories
@pytest.mark.parametrize(
    ("name", "duration"),
    [("rr_true", 2.0), ("ur5_payload", 2.0), ("panda", 1.0), ("mixed_payload", 2.0)],
)
def test_open_loop_trajectories_agree(mujoco, request, rr_true, mixed, name, duration):
    """1 kHz zero-order-hold torques recorded on the Pinocchio plant, replayed open loop on MuJoCo.

    The panda runs 1 s: its open-loop motion is unstable enough (light wrist links) that rounding
    differences grow by ~1e3 per 0.5 s, reaching 1e-4 rad after 2 s.
    """
    robot = _robots(request, rr_true, mixed)[name]
    period = 1e-3
    q0 = _start(robot, seed=1)
    torques, positions = _record(robot, q0, round(duration / period), period, seed=2)
    replayed = _replay(make_plant("mujoco", robot), q0, torques, period)
    assert np.ptp(positions, axis=0).max() > 0.2  # a real motion
    assert np.abs(replayed - positions).max() < OPEN_LOOP_TOLERANCE


def test_mujoco_rk4_converges_to_fourth_order(mujoco, ur5):
    """MuJoCo's RK4 is classical RK4: the Richardson ratios match the Pinocchio plant's."""
    robot = ur5.with_payload("payload", "wrist_3_link", PAYLOAD)
    rng = np.random.default_rng(3)
    q0 = rng.uniform(-1, 1, robot.dof)
    g0 = robot.g(q0)
    torques = g0 + 0.3 * np.maximum(np.abs(g0), 1.0) * rng.uniform(-1, 1, (25, robot.dof))
    steps = (0.02, 0.01, 5e-3)
    mj = [_replay(make_plant("mujoco", robot, max_step=h), q0, torques, 0.02) for h in steps]
    pn = [_replay(PinocchioPlant(robot, max_step=h), q0, torques, 0.02) for h in steps]
    assert 14 < np.abs(mj[0] - mj[1]).max() / np.abs(mj[1] - mj[2]).max() < 19
    for a, b in zip(mj, pn, strict=True):  # same scheme and step: only rounding differs
        assert np.abs(a - b).max() < 1e-12


def test_mujoco_continuous_joint_is_an_unwrapped_angle(mujoco, mixed):
    plant = make_plant("mujoco", mixed)
    reference = PinocchioPlant(mixed)
    for p in (plant, reference):
        p.reset([3.0, 0.8, 2.0], [20.0, 0.0, 0.0])  # slide and elbow beyond their URDF limits
        for _ in range(100):
            state = p.step(np.zeros(3), 1e-3)
    assert state.q[0] > np.pi + 0.5  # the continuous joint turned past pi without wrapping
    np.testing.assert_allclose(plant.state.q, reference.state.q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(plant.state.qd, reference.state.qd, rtol=0, atol=1e-9)


def test_box_plant_uses_its_own_robot(rr, rr_box, rr_true_point):
    """The short form builds the same plant as the explicit-robot form, checked on Pinocchio's
    mass matrix at a random state; a hand-built box without a robot is refused."""
    from urpc.model.parameter_box import ParameterBox

    short, explicit = rr_box.plant(rr_true_point), rr_box.plant(rr, rr_true_point)
    q = np.array([0.3, -1.1])
    masses = [pin.crba(p.model, p.model.createData(), q) for p in (short, explicit)]
    np.testing.assert_allclose(masses[0], masses[1], rtol=0, atol=0)
    nominal = pin.crba(rr.model, rr.model.createData(), q)
    assert not np.allclose(masses[0], nominal)  # the point moved the plant off the nominal
    assert rr_box.robot is rr
    with pytest.raises(InputError, match="not parsed for a robot"):
        ParameterBox(links=rr_box.links).plant(rr_true_point)
    with pytest.raises(InputError, match="takes a Robot first"):
        rr_box.plant(rr_true_point, rr_true_point)
