"""Enclosures of the rigid-body dynamics over boxes of states, and of their time derivatives.

The certificate (:mod:`urpc.control.cells`) needs ``M(q)``, ``Y_SL``, Coriolis matrices and
torques bounded over whole cells of time and the tube around the reference, not at points, and
the rates at which they change. This module evaluates the recursive Newton-Euler regressor
``Y(q, v, a)`` (``Y pi = M(q) a + c(q, v) + g(q)``; columns as Pinocchio's
``computeJointTorqueRegressor``: 10 standard parameters per joint body, ``m, m c, I`` about the
body frame) in **midpoint-radius ball arithmetic**, vectorized over a batch of boxes: every input
is a :class:`Ball` ``(mid, rad)`` of arrays and every output encloses the exact value for every
input point of its box. A :class:`Jet` carries a ball and a ball of its time derivative through the
same recursion (forward-mode differentiation), so that ``d/dt Y(q(t), v(t), a(t))`` is enclosed
over a box of states *and* of their rates.

The recursion runs as one compiled pass over the batch (:mod:`urpc.model.ball_kernels`): the
poses once per box, shared by the columns of a mass or Christoffel matrix, every column's forward
pass, body regressor and backward pass with the parameter rows carried together; exactly-zero
vectors (zero velocities, unit accelerations and parameter directions below their body) are
skipped, which is exact. Jets (and jets of jets) are elements of a truncated Taylor algebra;
several directions of one box share its value, and the second derivatives of ``M`` are
evaluated all at once (value, gradient and Hessian) with the very terms of the hyper-dual numbers.

Rounding (:mod:`urpc.model.ball_kernels` has the analysis): each ball of the recursion is a sum of
``N`` terms, balls or products of two balls, whose midpoint is the floating-point sum and whose
radius adds the terms' radii and ``(N + 2) u`` times the sum of the terms' magnitudes, the radius
inflated by ``1 + 2 (N + 4) u`` (``u = 2^-53``) so that rounding it cannot shrink it; ball sums
(a child's force added to its parent's, the polarizations) add ``2u |result|`` and are inflated by
``1 + 8u``. ``sin``/``cos`` of a ball ``[x - r, x + r]`` are ``cos x +- (|sin x| r + r^2 / 2)``
(Taylor with remainder) plus 2 ulps for the library's rounding. The model's constants (joint
placements, axes) are taken as exact: the enclosure is of the model as Pinocchio holds it.

Checked in ``tests/test_regressor_balls.py`` and ``tests/test_ball_kernels.py``: at zero radius the midpoint equals Pinocchio's
regressor, mass matrix and inverse dynamics to rounding and the radius covers the difference; over
random boxes the enclosures hold every Pinocchio evaluation at points drawn in the box, and the
enclosed derivatives hold finite differences of Pinocchio along random curves through the box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import UrpcError
from . import ball_kernels as kernels
from .ball_arithmetic import Ball, Jet, concatenate, intersect_symmetric, matvec, transposed
from .robot import Robot

__all__ = ["Ball", "BallRegressor", "Jet", "matvec", "parameters_of"]


# ============================================================================ the recursion
@dataclass(frozen=True)
class _Joint:
    parent: int  # joint index of the parent (-1: the base)
    revolute: bool
    axis: np.ndarray  # unit axis in the joint frame
    rotation: np.ndarray  # placement rotation in the parent frame
    translation: np.ndarray  # placement translation in the parent frame
    # Rodrigues split of a revolute joint's rotation: R(q) = A0 + cos q A1 + sin q A2.
    parts: tuple[np.ndarray, np.ndarray, np.ndarray] | None


class BallRegressor:
    """The Newton-Euler recursion of one robot's kinematics over boxes of states.

    Args:
        robot: A fixed-base chain of 1-dof revolute or prismatic joints (continuous joints are
            revolute in the angle coordinate, like :meth:`Robot.M`).

    Raises:
        UrpcError: a joint with more than one degree of freedom or a screw motion.
    """

    def __init__(self, robot: Robot):
        model = robot.model
        self.dof = robot.dof
        self.gravity = np.asarray(model.gravity.linear, dtype=float).copy()
        neutral = pin.neutral(model)
        joints = []
        for j in range(1, model.njoints):
            joint = model.joints[j]
            if joint.nv != 1 or joint.idx_v != j - 1:
                raise UrpcError(f"joint '{model.names[j]}' is not a 1-dof joint in chain order")
            data = joint.createData()
            joint.calc(data, neutral)
            subspace = np.asarray(data.S, dtype=float).reshape(6)
            revolute = robot.joint_kinds[j - 1] in ("revolute", "continuous")
            axis = subspace[3:] if revolute else subspace[:3]
            if np.any(subspace[:3] if revolute else subspace[3:]):
                raise UrpcError(f"joint '{model.names[j]}' has a screw motion subspace")
            placement = model.jointPlacements[j]
            P = np.asarray(placement.rotation, dtype=float)
            parts = None
            if revolute:
                outer = np.outer(axis, axis)
                S = np.array(
                    [[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]]
                )
                parts = (P @ outer, P @ (np.eye(3) - outer), P @ S)
            joints.append(
                _Joint(
                    model.parents[j] - 1,
                    revolute,
                    axis.copy(),
                    P.copy(),
                    np.asarray(placement.translation, dtype=float).copy(),
                    parts,
                )
            )
        self.joints = tuple(joints)
        self.chain = _chain(self.joints, self.gravity)

    # ------------------------------------------------------------------ the compiled pass
    def _run(self, q, columns, parameters, polarize: bool = False) -> Ball | Jet:
        """``Y(q, v_c, a_c) pi_p`` with gravity ``g_c g`` for each column ``(v_c, a_c, g_c)``
        and parameter row ``pi_p`` (a :class:`Ball` ``(P, 10 dof)``), over the batch of ``q``
        (balls, jets or jets of jets, ``batch + (dof,)``, the columns' broadcast to it):
        ``batch + (C, P, dof)``, one compiled pass (:mod:`urpc.model.ball_kernels`). With
        ``polarize``, the ``C / 2`` differences ``(tau_c - tau_{c + C / 2}) / 4`` instead (ball
        differences, then an exact scaling).

        Jets whose values agree along the last batch axis (directions of one box, as in
        ``Jet(broadcast value, directions)``) are evaluated as one value with ``D`` first
        derivatives: the value is computed once, the derivatives as they would be alone."""
        n = self.dof
        inputs = [q] + [x for v, a, _ in columns for x in (v, a)]
        shape = np.broadcast_shapes(*(_shape(x) for x in inputs))
        inputs = [_broadcast(x, shape) for x in inputs]
        depth = max(_depth(x) for x in inputs)
        batch = shape[:-1]
        shared = (
            depth == 1
            and len(batch) >= 1
            and batch[-1] > 1
            and all(_constant_along(x, -2) for x in inputs)
        )
        if shared:
            directions = batch[-1]
            algebra = kernels.first_order(directions)
            outer = batch[:-1]

            def arrays(x):
                x = Jet.of(x)
                parts = [x.val[..., 0, :]] + [x.dot[..., d, :] for d in range(directions)]
                return _stacked(parts, outer, n)

        else:
            algebra = (kernels.first_order(0), kernels.first_order(1), kernels.hyper_dual())[depth]
            outer = batch

            def arrays(x):
                return _stacked(_components(x, depth), outer, n)

        qa = arrays(inputs[0])
        va = [arrays(x) for x in inputs[1::2]]
        aa = [arrays(x) for x in inputs[2::2]]
        mid, rad = kernels.recursion(
            self.chain,
            algebra,
            qa,
            tuple(np.stack([x[i] for x in va], 1) for i in range(2)),
            tuple(np.stack([x[i] for x in aa], 1) for i in range(2)),
            np.array([g for _, _, g in columns], dtype=float),
            (parameters.mid, parameters.rad),
            polarize,
        )  # (B, C, P, n, K)
        shape_out = outer + mid.shape[1:4]
        parts = [
            Ball(mid[..., o].reshape(shape_out), rad[..., o].reshape(shape_out))
            for o in range(algebra.components)
        ]
        if not shared:
            return _assemble(parts, depth)
        # The value for every direction, and the derivatives along the directions' axis.
        value = parts[0].map(
            lambda x: np.ascontiguousarray(
                np.broadcast_to(x[..., None, :, :, :], outer + (directions,) + x.shape[-3:])
            )
        )
        dot = Ball(
            np.stack([p.mid for p in parts[1:]], len(outer)),
            np.stack([p.rad for p in parts[1:]], len(outer)),
        )
        return Jet(value, dot)

    def _columns(self, q, columns, parameters, polarize: bool = False) -> Ball | Jet:
        """:meth:`_run`, parameters as points or a :class:`Ball`."""
        if not isinstance(parameters, Ball):
            parameters = Ball.point(np.atleast_2d(np.asarray(parameters, dtype=float)))
        return self._run(q, columns, parameters, polarize)

    # ------------------------------------------------------------------ the methods
    def evaluate(self, q, v, a, gravity_scale: float = 1.0):
        """``Y(q, v, a)`` with gravity ``gravity_scale * g``: shape ``batch + (dof, 10 dof)``.

        ``q``, ``v``, ``a``: balls or jets of shape ``batch + (dof,)`` [rad, rad/s, rad/s^2]."""
        identity = Ball.point(np.eye(10 * self.dof))
        Y = self._run(q, [(v, a, gravity_scale)], identity)  # batch + (1, 10 dof, dof)
        return transposed(Y[..., 0, :, :])

    def torques(self, q, v, a, parameters, gravity_scale: float = 1.0):
        """``Y(q, v, a) pi`` for each row ``pi`` of ``parameters`` ``(P, 10 dof)`` (an array of
        points, or a :class:`Ball` of parameter intervals): the inverse dynamics of ``P`` models
        at once, shape ``batch + (P, dof)``. Cheaper than :meth:`evaluate` times ``pi``: forces
        are carried as 3-vectors, not as regressor blocks."""
        return self._columns(q, [(v, a, gravity_scale)], parameters)[..., 0, :, :]

    def slotine_li(self, q, qd, qd_a, qdd_a):
        """``Y_SL(q, qd, qd_a, qdd_a)`` (``M qdd_a + C(q, qd) qd_a + g``, Christoffel ``C``) over
        the boxes: ``(Y_{2g}(q, qd + qd_a, 2 qdd_a) - Y_{-2g}(q, qd - qd_a, -2 qdd_a)) / 4``,
        both in one pass (the poses shared)."""
        identity = Ball.point(np.eye(10 * self.dof))
        columns = [
            (qd + qd_a, qdd_a.scaled(2.0), 2.0),
            (qd - qd_a, qdd_a.scaled(-2.0), -2.0),
        ]
        Y = self._run(q, columns, identity, polarize=True)  # batch + (1, 10 dof, dof)
        return transposed(Y[..., 0, :, :])

    def mass_matrices(self, q, parameters):
        """``M(q)`` of each model (rows of ``parameters``, armature excluded) over the boxes of
        ``q``: ``batch + (P, dof, dof)``. Column ``j`` is ``Y(q, 0, e_j) pi`` without gravity
        (the poses shared by the columns, the zero velocities and the bodies before joint ``j``
        skipped); the two enclosures of each off-diagonal entry are intersected. With a jet
        ``q`` (``q`` and ``qd``) the derivative is ``dM/dt = C(q, qd) + C(q, qd)^T``,
        enclosed."""
        n = self.dof
        zero = Ball.point(np.zeros(n))
        eye = np.eye(n)
        columns = [(zero, Ball.point(eye[j]), 0.0) for j in range(n)]
        values = self._columns(q, columns, parameters)  # (..., j, P, i)
        return intersect_symmetric(values.map(lambda x: np.moveaxis(x, -3, -1)))

    def mass_matrix_curvatures(self, q: Ball, parameters):
        """``d^2 M / dq_k dq_j`` of each model (rows of ``parameters``, armature excluded) over the
        boxes of ``q``: ``batch + (k, j, P, dof, dof)``, symmetric in ``k, j``. Each pair ``k <= j``
        is the ``d^2 / ds dt`` part of :meth:`mass_matrices` at the hyper-dual ``q + s e_k + t
        e_j``; all pairs are evaluated in one pass as the second derivatives of ``M`` in the
        algebra of values, gradients and Hessians (:func:`~urpc.model.ball_kernels.hessian`),
        with the same terms in the same order, the value and the gradient computed once."""
        n = self.dof
        if not isinstance(parameters, Ball):
            parameters = Ball.point(np.atleast_2d(np.asarray(parameters, dtype=float)))
        batch = q.shape[:-1]
        algebra = kernels.hessian(n)
        K = algebra.components
        B = int(np.prod(batch, dtype=int))
        qm = np.zeros((B, n, K))
        qr = np.zeros((B, n, K))
        qm[:, :, 0] = np.reshape(q.mid, (B, n))
        qr[:, :, 0] = np.reshape(q.rad, (B, n))
        qm[:, np.arange(n), 1 + np.arange(n)] = 1.0
        columns = np.zeros((B, n, n, K))
        accelerations = np.zeros((B, n, n, K))
        accelerations[:, np.arange(n), np.arange(n), 0] = 1.0
        mid, rad = kernels.recursion(
            self.chain, algebra, (qm, qr), (columns, columns), (accelerations, columns),
            np.zeros(n), (parameters.mid, parameters.rad),
        )  # fmt: skip  # (B, j, P, i, K)
        pairs = kernels.pair_index(n)
        first, second = np.triu_indices(n)
        index = pairs[first, second]
        # (B, pairs, P, i, j): the two enclosures of each off-diagonal entry intersected.
        values = intersect_symmetric(
            Ball(
                np.moveaxis(mid[..., index], (-1, 1), (1, -1)),
                np.moveaxis(rad[..., index], (-1, 1), (1, -1)),
            )
        )
        P = mid.shape[2]
        full = (B, n, n, P, n, n)
        out_mid, out_rad = np.zeros(full), np.zeros(full)
        for source, out in ((values.mid, out_mid), (values.rad, out_rad)):
            out[:, first, second] = source
            out[:, second, first] = source
        shape = batch + full[1:]
        return Ball(out_mid.reshape(shape), out_rad.reshape(shape))

    def coriolis_matrices(self, q, qd, parameters):
        """The Christoffel ``C(q, qd)`` of each model over the boxes: ``batch + (P, dof, dof)``,
        column ``j`` by polarization ``(c(q, qd + e_j) - c(q, qd - e_j)) / 4``, ``c(q, x) =
        Y(q, x, 0) pi`` without gravity (all ``2 dof`` evaluations in one pass)."""
        n = self.dof
        zero = Ball.point(np.zeros(n))
        eye = np.eye(n)
        columns = [(qd + Ball.point(eye[j]), zero, 0.0) for j in range(n)]
        columns += [(qd - Ball.point(eye[j]), zero, 0.0) for j in range(n)]
        values = self._columns(q, columns, parameters, polarize=True)  # (..., j, P, i)
        return values.map(lambda x: np.moveaxis(x, -3, -1))

    def coriolis_slopes(self, q: Ball, qd: np.ndarray, parameters) -> Ball:
        """The derivatives ``d C(q, qd) / d q_l`` of :meth:`coriolis_matrices` along every
        coordinate ``l`` over the boxes ``q`` (``batch + (n,)``) at the point velocities ``qd``
        (one per box): ``batch + (l, P, dof, dof)``, in one pass of first-order jets along the
        ``dof`` coordinates (the value computed once, shared by the derivatives); the columns
        ``qd +- e_j`` are formed in ball arithmetic, as :meth:`coriolis_matrices` forms them."""
        n = self.dof
        batch = q.shape[:-1]
        B = int(np.prod(batch, dtype=int))
        if not isinstance(parameters, Ball):
            parameters = Ball.point(np.atleast_2d(np.asarray(parameters, dtype=float)))
        v = Ball.point(np.reshape(np.asarray(qd, dtype=float), (B, 1, n)))
        unit = Ball.point(np.eye(n)[None])
        columns = concatenate([v + unit, v - unit], 1)  # (B, 2n, n)
        vm, vr = (np.zeros((B, 2 * n, n, n + 1)) for _ in range(2))
        vm[..., 0], vr[..., 0] = columns.mid, columns.rad
        zeros = np.zeros_like(vm)
        mid, rad = kernels.recursion(
            self.chain, kernels.first_order(n), _along_coordinates(q), (vm, vr), (zeros, zeros),
            np.zeros(2 * n), (parameters.mid, parameters.rad), polarize=True,
        )  # fmt: skip  # (B, j, P, i, 1 + l)
        shape = batch + (n, parameters.mid.shape[0], n, n)
        return Ball(*(np.moveaxis(x[..., 1:], (-1, 1), (1, -1)).reshape(shape) for x in (mid, rad)))

    def christoffel_matrices(self, q: Ball, parameters) -> Ball:
        """``C(q; e_k)`` for every unit velocity ``e_k`` and each model over the boxes of ``q``:
        ``batch + (k, P, dof, dof)``. Column ``i`` of ``C(q; e_k)`` is column ``k`` of
        ``C(q; e_i)`` (the Christoffel symbols are symmetric in their last two indices), so only
        the ``dof (dof + 1) / 2`` pairs ``k <= i`` are evaluated, each by polarization
        ``(c(q, e_k + e_i) - c(q, e_k - e_i)) / 4``, instead of ``dof^2`` (all in one pass, unit
        parameter rows carried as regressor columns). Their derivatives along ``q``:
        :meth:`christoffel_slopes`."""
        n = self.dof
        batch = q.shape[:-1]
        outm, outr, rows, models = self._christoffel_pass(
            _stacked([q], batch, n), kernels.first_order(0), parameters
        )
        first, second = np.triu_indices(n)
        shape = batch + (n, models, n, n)
        return Ball(
            kernels.pair_scatter(outm, first, second, rows, models).reshape(shape),
            kernels.pair_scatter(outr, first, second, rows, models).reshape(shape),
        )

    def christoffel_slopes(self, q: Ball, parameters) -> Ball:
        """The derivatives ``d C(q; e_k) / d q_l`` of :meth:`christoffel_matrices` along every
        coordinate ``l`` over the boxes ``q`` (``batch + (n,)``): ``batch + (l, k, P, dof,
        dof)``, in one pass of first-order jets along the ``dof`` coordinates (the value
        computed once, shared by the derivatives)."""
        n = self.dof
        batch = q.shape[:-1]
        outm, outr, rows, models = self._christoffel_pass(
            _along_coordinates(q), kernels.first_order(n), parameters
        )
        first, second = np.triu_indices(n)
        shape = batch + (n, n, models, n, n)
        slopes = [
            np.stack(
                [
                    kernels.pair_scatter(
                        np.ascontiguousarray(out[:, :, :, 1 + l : 2 + l]), first, second, rows,
                        models,
                    )
                    for l in range(n)
                ],
                1,
            ).reshape(shape)
            for out in (outm, outr)
        ]  # fmt: skip
        return Ball(*slopes)

    def _christoffel_pass(self, q: tuple[np.ndarray, np.ndarray], algebra, parameters):
        """The kernel's raw polarized columns ``(c(q, e_k + e_i) - c(q, e_k - e_i)) / 4`` of
        every pair ``k <= i`` (``q``: (mid, rad) of shape (B, n, K) in ``algebra``): ``(mid,
        rad, rows, P)``, (B, pairs, n, K, P') each, the rows the kernel holds and the number of
        models."""
        n = self.dof
        if not isinstance(parameters, Ball):
            parameters = Ball.point(np.atleast_2d(np.asarray(parameters, dtype=float)))
        first, second = np.triu_indices(n)
        eye = np.eye(n)
        velocities = np.concatenate([eye[first] + eye[second], eye[first] - eye[second]])
        B, C, K = q[0].shape[0], len(velocities), algebra.components
        vm = np.zeros((B, C, n, K))
        vm[:, :, :, 0] = velocities
        zeros = np.zeros_like(vm)
        outm, outr, rows = kernels.recursion(
            self.chain, algebra, q, (vm, zeros), (zeros, zeros), np.zeros(C),
            (parameters.mid, parameters.rad), polarize=True, raw=True,
        )  # fmt: skip
        return outm, outr, rows, parameters.mid.shape[0]


def parameters_of(robot: Robot) -> np.ndarray:
    """The standard parameters ``pi`` of a model's joint bodies (Pinocchio order), ``(10 dof,)``."""
    model = robot.model
    return np.concatenate(
        [np.asarray(model.inertias[j].toDynamicParameters()) for j in range(1, model.njoints)]
    )


# ============================================================================ helpers
def _along_coordinates(q: Ball) -> tuple[np.ndarray, np.ndarray]:
    """(mid, rad), shape (B, n, 1 + n), of the boxes ``q`` (``batch + (n,)``) as first-order
    jets along each coordinate (component ``1 + l`` the unit derivative along ``q_l``)."""
    n = q.mid.shape[-1]
    B = int(np.prod(q.mid.shape[:-1], dtype=int))
    qm, qr = np.zeros((B, n, n + 1)), np.zeros((B, n, n + 1))
    qm[:, :, 0] = np.reshape(q.mid, (B, n))
    qr[:, :, 0] = np.reshape(q.rad, (B, n))
    qm[:, np.arange(n), 1 + np.arange(n)] = 1.0
    return qm, qr


def _chain(joints: tuple[_Joint, ...], gravity: np.ndarray) -> kernels.Chain:
    parts = np.zeros((len(joints), 3, 9))
    direction = np.zeros((len(joints), 3))
    for k, joint in enumerate(joints):
        if joint.revolute:
            parts[k] = np.stack([A.reshape(9) for A in joint.parts])
        else:
            parts[k, 0] = joint.rotation.reshape(9)
            direction[k] = joint.rotation @ joint.axis
    return kernels.Chain(
        np.array([j.parent for j in joints], dtype=np.int64),
        np.array([j.revolute for j in joints], dtype=np.bool_),
        np.array([j.axis for j in joints], dtype=float).reshape(len(joints), 3),
        parts,
        np.array([j.translation for j in joints], dtype=float).reshape(len(joints), 3),
        direction,
        np.asarray(gravity, dtype=float),
    )


def _depth(x) -> int:
    """0 for a ball, 1 for a jet, 2 for a jet of jets."""
    return 1 + max(_depth(x.val), _depth(x.dot)) if isinstance(x, Jet) else 0


def _shape(x) -> tuple[int, ...]:
    return _shape(x.val) if isinstance(x, Jet) else x.mid.shape


def _broadcast(x, shape):
    return x.map(lambda a: np.broadcast_to(a, shape))


def _constant_along(x, axis: int) -> bool:
    """Whether a jet's value is the same at every index of ``axis``."""
    value = Jet.of(x).val
    return all(
        np.array_equal(a, np.broadcast_to(np.take(a, [0], axis), a.shape))
        for a in (value.mid, value.rad)
    )


def _components(x, depth: int) -> list[Ball]:
    """The balls of a ball, jet or jet of jets as an element of depth ``depth`` (``val`` parts
    first, as :class:`Jet` promotes a ball: zero derivatives)."""
    if depth == 0:
        return [x]
    x = Jet.of(x)
    return _components(x.val, depth - 1) + _components(x.dot, depth - 1)


def _assemble(parts: list[Ball], depth: int):
    if depth == 0:
        return parts[0]
    half = len(parts) // 2
    return Jet(_assemble(parts[:half], depth - 1), _assemble(parts[half:], depth - 1))


def _stacked(parts: list[Ball], outer: tuple[int, ...], n: int):
    """(mid, rad) of shape (B, n, K) of the components over the flattened batch ``outer``."""
    B = int(np.prod(outer, dtype=int))
    return tuple(
        np.stack([np.reshape(getattr(p, which), (B, n)) for p in parts], -1)
        for which in ("mid", "rad")
    )
