"""urpc.model.ball_kernels: the compiled Newton-Euler pass, against Pinocchio.

The paths that the kernel adds to the recursion of ``tests/test_regressor_balls.py`` are checked
here on their own, against Pinocchio (the independent reference), on every robot of that file
(the branched ``tree`` has a prismatic joint and unaligned axes): parameter rows of every kind
(zero, unit, sparse, intervals, out of body order), jets of jets through the general path, jets
sharing their value along a batch axis (evaluated as one value with several derivatives), the
Hessian algebra of ``mass_matrix_curvatures`` against the hyper-dual numbers it replaces, and
gravity scaled.
"""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin
import pytest
from test_regressor_balls import _draws, _regressor, robot  # noqa: F401 - the fixture

from urpc.model import ball_kernels as kernels
from urpc.model.regressor_balls import Ball, BallRegressor, Jet, parameters_of


def _rows(rng, pi: np.ndarray, dof: int) -> np.ndarray:
    """Parameter rows of every kind, out of body order: the model's, unit vectors (+-1) of the
    last and first bodies, one scaled entry, a zero row, two bodies at once."""
    size = 10 * dof
    eye = np.eye(size)
    rows = [
        eye[size - 3],
        pi,
        np.zeros(size),
        -eye[2],
        2.5 * eye[10 * (dof // 2) + 4],
        eye[size - 1] + eye[0],
        pi * rng.uniform(0.5, 1.5, size),
        eye[1],
    ]
    return np.stack(rows)


def test_parameter_rows_of_every_kind_hold_pinocchio(robot):  # noqa: F811
    """``torques`` with parameter rows of every kind and as intervals holds ``Y(q, v, a) pi`` of
    Pinocchio's regressor for parameter points drawn in the intervals, at points of the box."""
    rng = np.random.default_rng(11)
    regressor = BallRegressor(robot)
    n, batch = robot.dof, 3
    rows = _rows(rng, parameters_of(robot), n)
    radii = np.abs(rows) * 0.01
    radii[0] = 0.0  # a unit row stays exact
    parameters = Ball(rows, radii)
    q, v, a = (
        Ball(rng.standard_normal((batch, n)), np.full((batch, n), r)) for r in (0.02, 0.1, 0.3)
    )
    tau = regressor.torques(q, v, a, parameters)
    assert tau.mid.shape == (batch, len(rows), n)
    assert np.all(tau.mid[:, 2] == 0) and np.all(tau.rad[:, 2] == 0)  # the zero row
    for b in range(batch):
        for qq, vv, aa in zip(
            *(_draws(rng, x.mid[b], x.rad[b], 4) for x in (q, v, a)), strict=True
        ):
            Y = _regressor(robot, qq, vv, aa)
            for pi in (rows, rows + radii * rng.uniform(-1, 1, rows.shape)):
                exact = pi @ Y.T
                slack = 1e-12 * (1 + np.abs(Y).max() * np.abs(pi).sum(-1, keepdims=True))
                assert np.all(np.abs(exact - tau.mid[b]) <= tau.rad[b] + slack)


def test_jets_of_jets_hold_second_differences(robot):  # noqa: F811
    """The general jet-of-jets path (``evaluate`` at ``q + s dq1 + t dq2`` with ``v``, ``a``
    moving too): its ``d^2 / ds dt`` part holds Pinocchio's central second differences."""
    rng = np.random.default_rng(12)
    regressor = BallRegressor(robot)
    n, h = robot.dof, 1e-4
    q0 = Ball(rng.standard_normal((1, n)), np.full((1, n), 0.01))
    d1, d2 = rng.standard_normal((2, 1, n))
    v0, a0 = rng.standard_normal((2, 1, n))
    dv = rng.standard_normal((1, n))

    def point(x):
        return Ball.point(x)

    q = Jet(Jet(q0, point(d1)), Jet(point(d2), point(np.zeros((1, n)))))
    v = Jet(Jet(point(v0), point(dv)), point(np.zeros((1, n))))  # v moves along s only
    Y = regressor.evaluate(q, v, point(a0))
    assert isinstance(Y.dot.dot, Ball)

    def Y_at(x, s, t):
        return _regressor(robot, x + s * d1[0] + t * d2[0], v0[0] + s * dv[0], a0[0])

    for qq in _draws(rng, q0.mid[0], q0.rad[0], 3):
        second = (
            Y_at(qq, h, h) - Y_at(qq, h, -h) - Y_at(qq, -h, h) + Y_at(qq, -h, -h)
        ) / (4 * h * h)  # fmt: skip
        slack = 1e-5 * (1 + np.abs(second))
        assert np.all(np.abs(second - Y.dot.dot.mid[0]) <= Y.dot.dot.rad[0] + slack)
        value = Y_at(qq, 0.0, 0.0)
        assert np.all(np.abs(value - Y.val.val.mid[0]) <= Y.val.val.rad[0])


def test_shared_values_equal_separate_jets_and_hold_pinocchio(robot):  # noqa: F811
    """Jets whose value is broadcast along the directions' axis (evaluated once, with several
    derivatives) give what each jet gives alone, and the slopes ``dM/dq_k`` hold Pinocchio's
    central differences over the box."""
    rng = np.random.default_rng(13)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    n, cells, h = robot.dof, 2, 1e-6
    q = Ball(rng.standard_normal((cells, n)), np.full((cells, n), 0.02))
    along = Jet(
        q.map(lambda x: np.broadcast_to(x[:, None, :], (cells, n, n))),
        Ball.point(np.broadcast_to(np.eye(n), (cells, n, n))),
    )
    shared = regressor.mass_matrices(along, pi[None])  # (cells, k, 1, n, n)
    for k in range(n):
        alone = regressor.mass_matrices(
            Jet(q, Ball.point(np.tile(np.eye(n)[k], (cells, 1)))), pi[None]
        )
        for part in ("val", "dot"):
            for which in ("mid", "rad"):
                got = getattr(getattr(shared, part), which)[:, k]
                assert np.array_equal(got, getattr(getattr(alone, part), which))
    armature = np.diag(robot.model.armature)
    eye = np.eye(n) * h
    for b in range(cells):
        for qq in _draws(rng, q.mid[b], q.rad[b], 3):
            assert np.all(
                np.abs(robot.M(qq) - armature - shared.val.mid[b, 0, 0]) <= shared.val.rad[b, 0, 0]
            )
            for k in range(n):
                slope = (robot.M(qq + eye[k]) - robot.M(qq - eye[k])) / (2 * h)
                slack = 1e-6 * (1 + np.abs(slope))
                assert np.all(
                    np.abs(slope - shared.dot.mid[b, k, 0]) <= shared.dot.rad[b, k, 0] + slack
                )


def test_hessian_algebra_equals_hyper_dual_numbers(robot):  # noqa: F811
    """``mass_matrix_curvatures`` (every pair at once, in the value/gradient/Hessian algebra)
    computes, term for term, the ``d^2 / ds dt`` part of ``mass_matrices`` at the hyper-dual
    ``q + s e_k + t e_j`` (the general jet-of-jets path): the same balls."""
    rng = np.random.default_rng(14)
    regressor = BallRegressor(robot)
    pi = parameters_of(robot)
    n = robot.dof
    q = Ball(rng.standard_normal((2, n)), np.full((2, n), 0.03))
    H = regressor.mass_matrix_curvatures(q, pi[None])
    eye = np.eye(n)
    for k, j in itertools.combinations_with_replacement(range(n), 2):
        e_k, e_j = (Ball.point(np.tile(eye[i], (2, 1))) for i in (k, j))
        hyper = Jet(Jet(q, e_k), Jet(e_j, Ball.point(np.zeros((2, n)))))
        second = regressor.mass_matrices(hyper, pi[None]).dot.dot
        assert np.array_equal(second.mid, H.mid[:, k, j]), (k, j)
        assert np.array_equal(second.rad, H.rad[:, k, j]), (k, j)
        assert np.array_equal(H.mid[:, j, k], H.mid[:, k, j])


def test_scaled_gravity_and_slotine_li_at_points_equal_pinocchio(robot):  # noqa: F811
    """``evaluate`` with gravity scaled and ``slotine_li`` (both polarized columns in one pass) at
    points: Pinocchio's regressor with that gravity, to rounding, the radius covering it."""
    rng = np.random.default_rng(15)
    regressor = BallRegressor(robot)
    n = robot.dof
    model = robot.model.copy()
    model.gravity.linear = -2.0 * robot.model.gravity.linear
    for _ in range(3):
        q, v, a = rng.standard_normal((3, n))
        Y = regressor.evaluate(Ball.point(q[None]), Ball.point(v[None]), Ball.point(a[None]), -2.0)
        data = model.createData()
        reference = pin.computeJointTorqueRegressor(model, data, robot.configuration(q), v, a)
        assert np.all(np.abs(Y.mid[0] - reference) <= Y.rad[0] + 1e-13 * (1 + np.abs(reference)))
        qd, qd_a, qdd_a = rng.standard_normal((3, n))
        SL = regressor.slotine_li(*(Ball.point(x[None]) for x in (q, qd, qd_a, qdd_a)))
        reference = (
            _regressor(robot, q, np.zeros(n), qdd_a)
            + (_regressor(robot, q, qd + qd_a, 0 * q) - _regressor(robot, q, qd - qd_a, 0 * q)) / 4
        )
        assert np.all(np.abs(SL.mid[0] - reference) <= SL.rad[0] + 1e-12 * (1 + np.abs(reference)))
        assert np.max(SL.rad) < 1e-10


def test_row_order_keeps_subtrees_contiguous():
    """Rows sorted by body give each joint's subtree a range of rows; a subtree that is not a
    range of joints falls back to every one-body row."""
    parent = np.array([-1, 0, 1, 0, 3])  # two branches of the root: 1-2 and 3-4
    chain = kernels.Chain(
        parent, np.ones(5, bool), np.zeros((5, 3)), np.zeros((5, 3, 9)), np.zeros((5, 3)),
        np.zeros((5, 3)), np.zeros(3),
    )  # fmt: skip
    mid = np.zeros((6, 50))
    mid[0, [3, 45]] = 1.0  # two bodies: shared
    mid[1, 41], mid[2, 12], mid[3, 25], mid[4, 11], mid[5, 0] = 1.0, 2.0, 1.0, 1.0, 1.0
    rows, shared, own_lo, own_hi, sub_lo, sub_hi = kernels._row_order(chain, mid, 0 * mid)
    assert shared == 1 and list(rows) == [0, 5, 2, 4, 3, 1]
    assert list(own_lo) == [1, 2, 4, 5, 5] and list(own_hi) == [2, 4, 5, 5, 6]
    assert list(sub_lo) == [1, 2, 4, 5, 5] and list(sub_hi) == [6, 5, 5, 6, 6]
    tangled = chain.__class__(np.array([-1, -1, 0, 1, 2]), *(getattr(chain, f) for f in (
        "revolute", "axis", "parts", "translation", "direction", "gravity")))  # fmt: skip
    *_, sub_lo, sub_hi = kernels._row_order(tangled, mid, 0 * mid)
    # Subtrees {0, 2, 4}, {1, 3}, {2, 4} are not ranges of joints; {3}, {4} are.
    assert list(sub_lo) == [1, 1, 1, 5, 5] and list(sub_hi) == [6, 6, 6, 5, 6]


@pytest.mark.parametrize("kind", ["first_order", "hyper_dual", "hessian"])
def test_product_tables_are_truncated_taylor_products(kind):
    """Each table multiplies value/derivative vectors as truncated Taylor series do: checked
    on random vectors against the product rule."""
    algebra = {
        "first_order": kernels.first_order(3),
        "hyper_dual": kernels.hyper_dual(),
        "hessian": kernels.hessian(3),
    }[kind]
    rng = np.random.default_rng(16)
    a, b = rng.standard_normal((2, algebra.components))
    c = np.zeros(algebra.components)
    for i in range(algebra.components):
        for e in range(algebra.ptr[i], algebra.ptr[i + 1]):
            c[algebra.to[e]] += a[i] * b[algebra.tj[e]]
    assert c[0] == pytest.approx(a[0] * b[0])
    if kind == "first_order":
        assert np.allclose(c[1:], a[0] * b[1:] + a[1:] * b[0])
    elif kind == "hyper_dual":  # (x0 + s x1 + t x2 + st x3)(...) with s^2 = t^2 = 0
        assert np.allclose(c[1:3], a[0] * b[1:3] + a[1:3] * b[0])
        assert c[3] == pytest.approx(a[0] * b[3] + a[1] * b[2] + a[2] * b[1] + a[3] * b[0])
    else:  # value, gradient, Hessian of a product
        pairs = kernels.pair_index(3)
        assert np.allclose(c[1:4], a[0] * b[1:4] + a[1:4] * b[0])
        for k, j in itertools.product(range(3), repeat=2):
            expected = (
                a[0] * b[pairs[k, j]] + a[1 + k] * b[1 + j] + a[1 + j] * b[1 + k]
                + a[pairs[k, j]] * b[0]
            )  # fmt: skip
            assert c[pairs[k, j]] == pytest.approx(expected)
