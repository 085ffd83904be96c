"""urpc.model.regressor_balls: the Newton-Euler recursion in ball arithmetic, against Pinocchio.

Every enclosure is checked against Pinocchio itself (the independent reference): at points (zero
radius) the midpoint equals Pinocchio's value to rounding and the radius covers the difference;
over boxes, every Pinocchio evaluation at points drawn in the box (corners included) lies in the
enclosure; the derivative of a jet holds Pinocchio's central finite differences along random
straight curves whose position and rate lie in the boxes.
"""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin
import pytest
from conftest import PANDA_FINGERS
from test_rigorous import TREE_URDF

from urpc.model.regressor_balls import Ball, BallRegressor, Jet, parameters_of
from urpc.model.robot import load_robot


@pytest.fixture(scope="module", params=["rr_planar", "ur5", "panda", "tree"])
def robot(request, tmp_path_factory):
    if request.param == "tree":
        path = tmp_path_factory.mktemp("tree") / "tree.urdf"
        path.write_text(TREE_URDF)
        return load_robot(path)
    locked = PANDA_FINGERS if request.param == "panda" else ()
    return load_robot(request.param, locked_joints=locked)


def _regressor(robot, q, v, a):
    data = robot.model.createData()
    return pin.computeJointTorqueRegressor(robot.model, data, robot.configuration(q), v, a)


def _draws(rng, center, radius, count):
    """Points of the box: its corners along a random sign pattern, then uniform draws."""
    n = center.shape[-1]
    signs = [np.array(s) for s in itertools.islice(itertools.product((-1, 1), repeat=n), 4)]
    corners = [center + s * radius for s in signs]
    return corners + [center + rng.uniform(-1, 1, n) * radius for _ in range(count)]


def test_points_equal_pinocchio(robot):
    rng = np.random.default_rng(1)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    for _ in range(5):
        q, v, a = rng.standard_normal((3, robot.dof))
        Y = regressor.evaluate(Ball.point(q), Ball.point(v), Ball.point(a))
        reference = _regressor(robot, q, v, a)
        assert np.all(np.abs(Y.mid - reference) <= Y.rad + 1e-13 * (1 + np.abs(reference)))
        assert np.max(Y.rad) < 1e-10
        tau = regressor.torques(Ball.point(q), Ball.point(v), Ball.point(a), pi[None])
        rnea = pin.rnea(robot.model, robot.model.createData(), robot.configuration(q), v, a)
        assert np.allclose(tau.mid[0], rnea, atol=1e-12)


def test_boxes_hold_pinocchio_evaluations(robot):
    rng = np.random.default_rng(2)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    armature = np.diag(robot.model.armature)
    n, batch = robot.dof, 6
    centers = rng.standard_normal((3, batch, n))
    radii = np.array([0.03, 0.2, 0.5])[:, None, None] * np.ones((3, batch, n))
    q, v, a = (Ball(c, r) for c, r in zip(centers, radii, strict=True))
    Y = regressor.evaluate(q, v, a)
    M = regressor.mass_matrices(q, pi[None])
    C = regressor.coriolis_matrices(q, v, pi[None])
    for b in range(batch):
        qs = _draws(rng, q.mid[b], q.rad[b], 12)
        vs = _draws(rng, v.mid[b], v.rad[b], 12)
        as_ = _draws(rng, a.mid[b], a.rad[b], 12)
        for qq, vv, aa in zip(qs, vs, as_, strict=True):
            assert np.all(np.abs(_regressor(robot, qq, vv, aa) - Y.mid[b]) <= Y.rad[b])
            assert np.all(np.abs(robot.M(qq) - armature - M.mid[b, 0]) <= M.rad[b, 0])
            assert np.all(np.abs(robot.C(qq, vv) - C.mid[b, 0]) <= C.rad[b, 0])


def test_christoffel_matrices_hold_pinocchio(robot):
    """``C(q; e_k)`` for every unit velocity, built from the pairs ``k <= i`` only, holds
    Pinocchio's Coriolis matrix at points of the box, for two parameter vectors at once."""
    rng = np.random.default_rng(5)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    scaled = pi * rng.uniform(0.8, 1.2, pi.shape)  # another model: C is linear in pi
    n, batch = robot.dof, 4
    q = Ball(rng.standard_normal((batch, n)), np.full((batch, n), 0.05))
    each = regressor.christoffel_matrices(q, Ball.point(np.stack([pi, scaled])))
    assert each.mid.shape == (batch, n, 2, n, n)
    model, data = _model_with(robot, scaled)
    for b in range(batch):
        for qq in _draws(rng, q.mid[b], q.rad[b], 6):
            for k in range(n):
                unit = np.eye(n)[k]
                for p, C in enumerate(
                    (
                        robot.C(qq, unit),
                        pin.computeCoriolisMatrix(model, data, robot.configuration(qq), unit),
                    )
                ):
                    slack = 1e-13 * (1 + np.abs(C))  # Pinocchio's own rounding
                    assert np.all(np.abs(C - each.mid[b, k, p]) <= each.rad[b, k, p] + slack)


def test_christoffel_slopes_hold_pinocchio_differences(robot):
    """``d C(q; e_k) / d q_l`` over boxes holds Pinocchio's central differences of its Coriolis
    matrix along each coordinate, at points of the box, for two parameter vectors at once."""
    rng = np.random.default_rng(9)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    scaled = pi * rng.uniform(0.8, 1.2, pi.shape)
    n, batch, h = robot.dof, 3, 1e-5
    q = Ball(rng.standard_normal((batch, n)), np.full((batch, n), 0.04))
    slopes = regressor.christoffel_slopes(q, Ball.point(np.stack([pi, scaled])))
    assert slopes.mid.shape == (batch, n, n, 2, n, n)
    model, data = _model_with(robot, scaled)

    def coriolis(p: int, qq: np.ndarray, unit: np.ndarray) -> np.ndarray:
        if p == 0:
            return robot.C(qq, unit)
        return pin.computeCoriolisMatrix(model, data, robot.configuration(qq), unit).copy()

    for b in range(batch):
        for qq in _draws(rng, q.mid[b], q.rad[b] - h, 3):
            for l, k, p in itertools.product(range(n), range(n), range(2)):
                unit = np.eye(n)[k]
                _assert_holds_difference(
                    slopes[b, l, k, p],
                    lambda x, p=p, unit=unit: coriolis(p, x, unit),
                    qq,
                    l,
                    h,
                    (l, k, p),
                )


def test_coriolis_slopes_hold_pinocchio_differences(robot):
    """``d C(q, qd) / d q_l`` over boxes of ``q`` at a point velocity holds Pinocchio's central
    differences of its Coriolis matrix along each coordinate, at points of the box."""
    rng = np.random.default_rng(11)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    n, batch, h = robot.dof, 3, 1e-5
    q = Ball(rng.standard_normal((batch, n)), np.full((batch, n), 0.04))
    qd = rng.standard_normal((batch, n))
    slopes = regressor.coriolis_slopes(q, qd, pi[None])
    assert slopes.mid.shape == (batch, n, 1, n, n)
    for b in range(batch):
        for qq in _draws(rng, q.mid[b], q.rad[b] - h, 3):
            for l in range(n):
                _assert_holds_difference(
                    slopes[b, l, 0], lambda x, v=qd[b]: robot.C(x, v), qq, l, h, l
                )


def _model_with(robot, parameters: np.ndarray):
    """A copy of the robot's Pinocchio model with the bodies' standard ``parameters`` (10 per
    joint body), and its data."""
    model = robot.model.copy()
    for j in range(robot.dof):
        model.inertias[j + 1] = pin.Inertia.FromDynamicParameters(parameters[10 * j : 10 * j + 10])
    return model, model.createData()


def _assert_holds_difference(enclosed: Ball, f, q: np.ndarray, l: int, h: float, where):
    """``enclosed`` holds the central difference of ``f`` along coordinate ``l`` at ``q``."""
    step = h * np.eye(len(q))[l]
    difference = (f(q + step) - f(q - step)) / (2 * h)
    slack = 1e-6 * (1 + np.abs(difference))  # the difference's own error
    assert np.all(np.abs(difference - enclosed.mid) <= enclosed.rad + slack), where


def test_mass_matrix_curvatures_hold_second_differences(robot):
    """``d^2 M / dq_k dq_j`` over boxes (jets of jets) holds Pinocchio's central second
    differences at points of the box, corners included, for two parameter vectors at once."""
    rng = np.random.default_rng(7)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    scaled = pi * rng.uniform(0.8, 1.2, pi.shape)
    n, batch, h = robot.dof, 2, 1e-4
    q = Ball(rng.standard_normal((batch, n)), np.full((batch, n), 0.03))
    H = regressor.mass_matrix_curvatures(q, np.stack([pi, scaled]))
    assert H.mid.shape == (batch, n, n, 2, n, n)
    model, data = _model_with(robot, scaled)

    def mass(which, x):
        if which == 0:
            return robot.M(x)
        M = pin.crba(model, data, robot.configuration(x))
        return np.triu(M) + np.triu(M, 1).T

    eye = np.eye(n) * h
    for b in range(batch):
        for qq in _draws(rng, q.mid[b], q.rad[b], 2):
            for which in (0, 1):
                for k, j in itertools.product(range(n), repeat=2):
                    second = (
                        mass(which, qq + eye[k] + eye[j]) - mass(which, qq + eye[k] - eye[j])
                        - mass(which, qq - eye[k] + eye[j]) + mass(which, qq - eye[k] - eye[j])
                    ) / (4 * h * h)  # fmt: skip
                    slack = 1e-5 * (1 + np.abs(second))  # the difference's own error
                    error = np.abs(second - H.mid[b, k, j, which])
                    assert np.all(error <= H.rad[b, k, j, which] + slack), (k, j)


def test_jets_hold_finite_differences(robot):
    """d/dt of Y_SL and M along q(t) = q0 + t qd0 etc. (every input moving at its rate)."""
    rng = np.random.default_rng(3)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    n, batch, h = robot.dof, 4, 1e-6
    boxes = [Ball(rng.standard_normal((batch, n)), np.full((batch, n), 0.05)) for _ in range(4)]
    rates = [Ball(rng.standard_normal((batch, n)), np.full((batch, n), 0.3)) for _ in range(4)]
    jets = [Jet(x, dx) for x, dx in zip(boxes, rates, strict=True)]
    SL = regressor.slotine_li(*jets)
    M = regressor.mass_matrices(jets[0], pi[None])

    def slotine_li(q, qd, qd_a, qdd_a):
        Y0 = _regressor(robot, q, np.zeros(n), qdd_a)
        return (
            Y0
            + (_regressor(robot, q, qd + qd_a, 0 * q) - _regressor(robot, q, qd - qd_a, 0 * q)) / 4
        )

    for b in range(batch):
        for _ in range(6):
            x0 = [x.mid[b] + rng.uniform(-1, 1, n) * x.rad[b] * 0.99 for x in boxes]
            dx = [x.mid[b] + rng.uniform(-1, 1, n) * x.rad[b] for x in rates]
            ahead = [x + h * d for x, d in zip(x0, dx, strict=True)]
            behind = [x - h * d for x, d in zip(x0, dx, strict=True)]
            derivative = (slotine_li(*ahead) - slotine_li(*behind)) / (2 * h)
            slack = 1e-5 * (1 + np.abs(derivative))  # the finite difference's own error
            assert np.all(np.abs(derivative - SL.dot.mid[b]) <= SL.dot.rad[b] + slack)
            assert np.all(np.abs(slotine_li(*x0) - SL.val.mid[b]) <= SL.val.rad[b])
            dM = (robot.M(ahead[0]) - robot.M(behind[0])) / (2 * h)
            assert np.all(np.abs(dM - M.dot.mid[b, 0]) <= M.dot.rad[b, 0] + 1e-5 * (1 + np.abs(dM)))


def test_radius_grows_with_the_box():
    """A tight box gives a tight enclosure: the radius of M over a box of half-width r is of
    order r times the derivative (no blow-up), and exactly zero-width boxes give rounding only."""
    robot = load_robot("ur5")
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    q = np.full((1, robot.dof), 0.4)
    widths = [regressor.mass_matrices(Ball(q, np.full_like(q, r)), pi[None]).rad.max()
              for r in (1e-4, 1e-3, 1e-2)]  # fmt: skip
    assert widths[1] / widths[0] == pytest.approx(10, rel=0.05)
    assert widths[2] / widths[1] == pytest.approx(10, rel=0.1)
