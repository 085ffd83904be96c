"""The Slotine-Li regressor against Pinocchio's own M (crba), C (computeCoriolisMatrix) and g
(computeGeneralizedGravity), on the nominal robots and on plant copies with other inertias; the
placement map of link parameters against ``SE3.act`` on random physical inertias."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from urpc.model.regressor import SlotineLiRegressor, link_regressor_map, placement_matrix
from urpc.model.robot import load_robot


def random_state(rng: np.random.Generator, dof: int, scale: float = 1.0):
    """``(q, qd, qd_a, qdd_a)``: angles in [-pi, pi] [rad], rates and accelerations of magnitude
    ``scale`` [rad/s], ``5 scale`` [rad/s^2]."""
    q = rng.uniform(-np.pi, np.pi, dof)
    qd, qd_a = scale * rng.normal(size=dof), scale * rng.normal(size=dof)
    return q, qd, qd_a, 5.0 * scale * rng.normal(size=dof)


def slotine_li_torque(robot, q, qd, qd_a, qdd_a) -> tuple[np.ndarray, float]:
    """``M qdd_a + C qd_a + g`` from Pinocchio's matrices, and the magnitude of its terms."""
    terms = [robot.M(q) @ qdd_a, robot.C(q, qd) @ qd_a, robot.g(q)]
    return sum(terms), max(float(np.abs(t).max()) for t in terms)


def random_physical_inertia(rng: np.random.Generator) -> pin.Inertia:
    """A physically consistent rigid body: mass [kg], CoM [m], a rotated principal inertia."""
    moments = rng.uniform(0.1, 1.0, 3)
    moments[2] = rng.uniform(abs(moments[0] - moments[1]), moments[0] + moments[1])
    rotation = pin.exp3(rng.normal(size=3))
    return pin.Inertia(
        rng.uniform(0.2, 5.0),
        rng.normal(scale=0.2, size=3),
        rotation @ np.diag(moments) @ rotation.T,
    )


@pytest.fixture(scope="module")
def pendulum():
    """Continuous joints: Pinocchio's configuration is (cos, sin) per joint."""
    return load_robot("double_pendulum_continuous")


@pytest.fixture(scope="module", params=["rr", "ur5", "panda", "pendulum"])
def robot(request):
    return request.getfixturevalue(request.param)


def test_regressor_times_nominal_parameters_is_the_dynamics(robot):
    rng = np.random.default_rng(1)
    regressor = SlotineLiRegressor(robot)
    pi0 = robot.nominal_parameters
    for scale in (1.0, 1.0, 1.0, 20.0):
        state = random_state(rng, robot.dof, scale)
        Y = regressor(*state)
        assert Y.shape == (robot.dof, 10 * robot.dof)
        expected, magnitude = slotine_li_torque(robot, *state)
        np.testing.assert_allclose(Y @ pi0, expected, rtol=0, atol=1e-10 * magnitude)


def test_regressor_does_not_depend_on_the_inertias(robot):
    """``Y_SL`` of the nominal robot times a plant's parameters is the plant's dynamics."""
    rng = np.random.default_rng(2)
    links = robot.moving_link_names[-3:]
    plant = robot.with_link_inertias({name: random_physical_inertia(rng) for name in links})
    regressor = SlotineLiRegressor(robot)
    for _ in range(3):
        state = random_state(rng, robot.dof)
        expected, magnitude = slotine_li_torque(plant, *state)
        np.testing.assert_allclose(
            regressor(*state) @ plant.nominal_parameters, expected, rtol=0, atol=1e-10 * magnitude
        )


def test_scaled_regressor_is_exactly_four_times(robot):
    rng = np.random.default_rng(3)
    regressor = SlotineLiRegressor(robot)
    state = random_state(rng, robot.dof)
    out = np.empty((robot.dof, 10 * robot.dof))
    scaled = regressor.scaled(*state, out=out)
    assert scaled is out
    np.testing.assert_array_equal(regressor(*state) * SlotineLiRegressor.SCALE, scaled)


def test_placement_matrix_is_the_action_on_inertias():
    rng = np.random.default_rng(4)
    assert np.array_equal(placement_matrix(pin.SE3.Identity()), np.eye(10))
    for _ in range(20):
        placement = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(scale=0.5, size=3))
        A = placement_matrix(placement)
        inertia = random_physical_inertia(rng)
        acted = placement.act(inertia).toDynamicParameters()
        np.testing.assert_allclose(A @ inertia.toDynamicParameters(), acted, rtol=1e-12, atol=1e-12)


def test_link_regressor_map_moves_link_parameters_into_bodies(panda):
    """The map of links at non-trivial placements (the hand, fixed to the flange with a
    rotation): body parameters of a plant = nominal ones + B (link parameter changes)."""
    rng = np.random.default_rng(5)
    names = ["panda_link3", "panda_link7", "panda_hand"]
    new = {name: random_physical_inertia(rng) for name in names}
    plant = panda.with_link_inertias(new)
    change = np.concatenate(
        [
            new[name].toDynamicParameters() - panda.link(name).inertia.toDynamicParameters()
            for name in names
        ]
    )
    B = link_regressor_map(panda, names)
    np.testing.assert_allclose(
        panda.nominal_parameters + B @ change, plant.nominal_parameters, rtol=1e-12, atol=1e-12
    )
    # And through the regressor: Y_SL @ B regresses the links' own parameters.
    state = random_state(rng, panda.dof)
    Y = SlotineLiRegressor(panda)(*state)
    expected, magnitude = slotine_li_torque(plant, *state)
    nominal, _ = slotine_li_torque(panda, *state)
    np.testing.assert_allclose(Y @ B @ change, expected - nominal, rtol=0, atol=1e-10 * magnitude)


def test_link_regressor_map_rejects_base_links(ur5):
    with pytest.raises(ValueError, match="fixed to the base"):
        link_regressor_map(ur5, ["base_link"])
