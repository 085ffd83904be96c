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

Rounding: each elementary operation returns the floating-point result of the midpoints and adds
to the radius a bound of its rounding error (``2u |result|`` for a sum or product, ``(k + 2) u``
times the sum of the magnitudes for a ``k``-term dot product, ``u = 2^-53``), and the radius
itself is computed with its terms inflated by ``1 + 8u`` (so that rounding the radius down cannot
shrink it). ``sin``/``cos`` of a ball ``[x - r, x + r]`` are ``cos x +- (|sin x| r + r^2 / 2)``
(Taylor with remainder) plus 2 ulps for the library's rounding. The model's constants (joint
placements, axes) are taken as exact: the enclosure is of the model as Pinocchio holds it.

Checked in ``tests/test_regressor_balls.py``: at zero radius the midpoint equals Pinocchio's
regressor, mass matrix and inverse dynamics to rounding and the radius covers the difference; over
random boxes the enclosures hold every Pinocchio evaluation at points drawn in the box, and the
enclosed derivatives hold finite differences of Pinocchio along random curves through the box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import UrpcError
from .ball_arithmetic import (
    Ball,
    Jet,
    concatenate,
    cos_sin,
    cross,
    intersect_symmetric,
    matmul,
    matvec,
    skew,
    stack,
    transposed,
    zeros,
)
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

    def _constant(self, value: np.ndarray, batch: tuple[int, ...]) -> Ball:
        return Ball.point(np.broadcast_to(value, batch + value.shape))

    def _placements(self, q) -> list[tuple]:
        """Per joint, the pose ``(R, p)`` of its frame in the parent's, over the batch."""
        batch = q.shape[:-1]
        poses = []
        for k, joint in enumerate(self.joints):
            angle = q[..., k]
            if joint.revolute:
                A0, A1, A2 = (self._constant(A, batch) for A in joint.parts)
                c, s = cos_sin(angle.map(lambda a: a[..., None, None]))
                R = A0 + c * A1 + s * A2
                p = self._constant(joint.translation, batch)
            else:
                R = self._constant(joint.rotation, batch)
                direction = self._constant(joint.rotation @ joint.axis, batch)
                p = self._constant(joint.translation, batch) + direction * angle.map(
                    lambda a: a[..., None]
                )
            poses.append((R, p))
        return poses

    def _forward(self, q, v, a, gravity_scale: float):
        """Poses, spatial velocities and accelerations (gravity as a base acceleration)."""
        batch = q.shape[:-1]
        poses = self._placements(q)
        zero3 = zeros(batch + (3,))
        gravity = self._constant(-gravity_scale * self.gravity, batch)
        velocities, accelerations = [], []
        for k, joint in enumerate(self.joints):
            R, p = poses[k]
            if joint.parent < 0:
                vl, vw, al, aw = zero3, zero3, gravity, zero3
            else:
                vl, vw = velocities[joint.parent]
                al, aw = accelerations[joint.parent]
            # actInv: x' = R^T x (angular), l' = R^T (l - p x w) (linear).
            Rt = transposed(R)
            vw_, vl_ = matvec(Rt, vw), matvec(Rt, vl - cross(p, vw))
            aw_, al_ = matvec(Rt, aw), matvec(Rt, al - cross(p, aw))
            axis = self._constant(joint.axis, batch)
            own = axis * v[..., k : k + 1]  # S qd, in the joint's own frame
            if joint.revolute:
                vw_ = vw_ + own
                # a += v x (S qd): angular part w x own, linear part l x own.
                aw_ = aw_ + axis * a[..., k : k + 1] + cross(vw_, own)
                al_ = al_ + cross(vl_, own)
            else:
                vl_ = vl_ + own
                al_ = al_ + axis * a[..., k : k + 1] + cross(vw_, own)
            velocities.append((vl_, vw_))
            accelerations.append((al_, aw_))
        return poses, velocities, accelerations

    def _backward(self, poses, force: list):
        """Joint torques ``S_k^T f_k`` of per-joint blocks of force rows ``(..., rows, 3)``
        carried to the root: ``(..., rows, dof)``."""
        torques = [None] * self.dof
        for k in reversed(range(self.dof)):
            joint = self.joints[k]
            f, m = force[k]
            batch = f.shape[:-2]
            axis = self._constant(joint.axis, batch)
            torques[k] = matvec(m if joint.revolute else f, axis)
            if joint.parent >= 0:
                R, p = poses[k]
                # Rows are force vectors: f' = f R^T, m' = m R^T + (p x f') = m R^T - f' S(p).
                Rt = transposed(R)
                f_up = matmul(f, Rt)
                m_up = matmul(m, Rt) - matmul(f_up, skew(p))
                pf, pm = force[joint.parent]
                force[joint.parent] = (pf + f_up, pm + m_up)
        return stack(torques, -1)

    def evaluate(self, q, v, a, gravity_scale: float = 1.0):
        """``Y(q, v, a)`` with gravity ``gravity_scale * g``: shape ``batch + (dof, 10 dof)``.

        ``q``, ``v``, ``a``: balls or jets of shape ``batch + (dof,)`` [rad, rad/s, rad/s^2]."""
        n = self.dof
        poses, velocities, accelerations = self._forward(q, v, a, gravity_scale)
        force = []
        for k in range(n):
            lin, ang = _body_regressor(*velocities[k], *accelerations[k])  # (..., 10, 3)
            batch = lin.shape[:-2]
            before, after = zeros(batch + (10 * k, 3)), zeros(batch + (10 * (n - k - 1), 3))
            force.append(
                (concatenate([before, lin, after], -2), concatenate([before, ang, after], -2))
            )
        return transposed(self._backward(poses, force))

    def torques(self, q, v, a, parameters, gravity_scale: float = 1.0):
        """``Y(q, v, a) pi`` for each row ``pi`` of ``parameters`` ``(P, 10 dof)`` (an array of
        points, or a :class:`Ball` of parameter intervals): the inverse dynamics of ``P`` models
        at once, shape ``batch + (P, dof)``. Cheaper than :meth:`evaluate` times ``pi``: forces
        are carried as 3-vectors, not as regressor blocks."""
        if not isinstance(parameters, Ball):
            parameters = Ball.point(np.atleast_2d(np.asarray(parameters, dtype=float)))
        poses, velocities, accelerations = self._forward(q, v, a, gravity_scale)
        force = []
        for k in range(self.dof):
            lin, ang = _body_regressor(*velocities[k], *accelerations[k])  # (..., 10, 3)
            pi = parameters[:, 10 * k : 10 * k + 10]  # (P, 10)
            force.append((matmul(pi, lin), matmul(pi, ang)))  # (..., P, 3)
        return self._backward(poses, force)

    def slotine_li(self, q, qd, qd_a, qdd_a):
        """``Y_SL(q, qd, qd_a, qdd_a)`` (``M qdd_a + C(q, qd) qd_a + g``, Christoffel ``C``) over
        the boxes: ``(Y_{2g}(q, qd + qd_a, 2 qdd_a) - Y_{-2g}(q, qd - qd_a, -2 qdd_a)) / 4``."""
        plus = self.evaluate(q, qd + qd_a, qdd_a.scaled(2.0), gravity_scale=2.0)
        minus = self.evaluate(q, qd - qd_a, qdd_a.scaled(-2.0), gravity_scale=-2.0)
        return (plus - minus).scaled(0.25)

    def mass_matrices(self, q, parameters):
        """``M(q)`` of each model (rows of ``parameters``, armature excluded) over the boxes of
        ``q``: ``batch + (P, dof, dof)``. Column ``j`` is ``Y(q, 0, e_j) pi`` without gravity; the
        two enclosures of each off-diagonal entry are intersected. With a jet ``q`` (``q`` and
        ``qd``) the derivative is ``dM/dt = C(q, qd) + C(q, qd)^T``, enclosed."""
        n = self.dof
        batch = q.shape[:-1]
        qq = q.map(lambda x: np.broadcast_to(x[..., None, :], batch + (n, n)))
        zero = zeros(batch + (n, n))
        unit = Ball.point(np.broadcast_to(np.eye(n), batch + (n, n)))
        columns = self.torques(qq, zero, unit, parameters, gravity_scale=0.0)  # (..., j, P, i)
        return intersect_symmetric(columns.map(lambda x: np.moveaxis(x, -3, -1)))

    def mass_matrix_curvatures(self, q: Ball, parameters):
        """``d^2 M / dq_k dq_j`` of each model (rows of ``parameters``, armature excluded) over the
        boxes of ``q``: ``batch + (k, j, P, dof, dof)``, symmetric in ``k, j``. Each pair ``k <= j``
        is one evaluation of :meth:`mass_matrices` at the hyper-dual ``q + s e_k + t e_j`` (a jet
        of jets), whose ``d^2 / ds dt`` part is the second derivative."""
        n = self.dof
        batch = q.shape[:-1]
        first, second = np.triu_indices(n)
        pairs = len(first)
        shape = batch + (pairs, n)

        def point(x):
            return Ball.point(np.broadcast_to(x, shape))

        boxes = q.map(lambda x: np.broadcast_to(x[..., None, :], shape))
        eye = np.eye(n)
        hyper = Jet(Jet(boxes, point(eye[first])), Jet(point(eye[second]), point(0.0)))
        values = self.mass_matrices(hyper, parameters).dot.dot  # batch + (pairs, P, n, n)
        full = batch + (n, n) + values.mid.shape[len(batch) + 1 :]
        mid, rad = np.zeros(full), np.zeros(full)
        for source, out in ((values.mid, mid), (values.rad, rad)):
            out[..., first, second, :, :, :] = source
            out[..., second, first, :, :, :] = source
        return Ball(mid, rad)

    def coriolis_matrices(self, q, qd, parameters):
        """The Christoffel ``C(q, qd)`` of each model over the boxes: ``batch + (P, dof, dof)``,
        column ``j`` by polarization ``(c(q, qd + e_j) - c(q, qd - e_j)) / 4``, ``c(q, x) =
        Y(q, x, 0) pi`` without gravity."""
        n = self.dof
        batch = q.shape[:-1]
        qq = q.map(lambda x: np.broadcast_to(x[..., None, :], batch + (n, n)))
        unit = Ball.point(np.broadcast_to(np.eye(n), batch + (n, n)))
        rates = qd.map(lambda x: np.broadcast_to(x[..., None, :], batch + (n, n)))
        zero = zeros(batch + (n, n))
        plus = self.torques(qq, rates + unit, zero, parameters, gravity_scale=0.0)
        minus = self.torques(qq, rates - unit, zero, parameters, gravity_scale=0.0)
        return (plus - minus).scaled(0.25).map(lambda x: np.moveaxis(x, -3, -1))

    def christoffel_matrices(self, q, parameters):
        """``C(q; e_k)`` for every unit velocity ``e_k`` and each model over the boxes of ``q``:
        ``batch + (k, P, dof, dof)``. Column ``i`` of ``C(q; e_k)`` is column ``k`` of
        ``C(q; e_i)`` (the Christoffel symbols are symmetric in their last two indices), so only
        the ``dof (dof + 1) / 2`` pairs ``k <= i`` are evaluated, each by polarization
        ``(c(q, e_k + e_i) - c(q, e_k - e_i)) / 4``, instead of ``dof^2``."""
        n = self.dof
        batch = q.shape[:-1]
        first, second = np.triu_indices(n)
        pairs = len(first)
        eye = np.eye(n)
        qq = q.map(lambda x: np.broadcast_to(x[..., None, :], batch + (pairs, n)))
        zero = zeros(batch + (pairs, n))

        def velocities(v):
            return Ball.point(np.broadcast_to(v, batch + (pairs, n)))

        plus = self.torques(qq, velocities(eye[first] + eye[second]), zero, parameters, 0.0)
        minus = self.torques(qq, velocities(eye[first] - eye[second]), zero, parameters, 0.0)
        columns = (plus - minus).scaled(0.25)  # batch + (pairs, P, rows)
        models = columns.mid.shape[-2]
        shape = batch + (n, models, n, n)
        mid, rad = np.zeros(shape), np.zeros(shape)
        for values, out in ((columns.mid, mid), (columns.rad, rad)):
            out[..., first, :, :, second] = np.moveaxis(values, -3, 0)
            out[..., second, :, :, first] = np.moveaxis(values, -3, 0)
        return Ball(mid, rad)


def parameters_of(robot: Robot) -> np.ndarray:
    """The standard parameters ``pi`` of a model's joint bodies (Pinocchio order), ``(10 dof,)``."""
    model = robot.model
    return np.concatenate(
        [np.asarray(model.inertias[j].toDynamicParameters()) for j in range(1, model.njoints)]
    )


def _body_regressor(vl, vw, al, aw):
    """The body regressor ``Phi(v, a)``: the force ``f = I a + v x* (I v)`` as a linear map of
    ``pi = (m, h, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz)`` (``h = m c``, ``I`` about the origin);
    returns its linear and angular parts as ``(..., 10, 3)`` (parameter, component)::

        f_lin = m (a_l + w x v_l) + (S(a_w) + S(w)^2) h
        f_ang = -S(a_l - v_l x w) h + (L(a_w) + S(w) L(w)) iota,    I x = L(x) iota
    """
    batch = vl.shape[:-1]
    Sw = skew(vw)
    mass_lin = (al + cross(vw, vl)).map(lambda x: x[..., None])  # (..., 3, 1)
    h_lin = skew(aw) + matmul(Sw, Sw)
    h_ang = -skew(al - cross(vl, vw))
    i_ang = _inertia_map(aw) + matmul(Sw, _inertia_map(vw))  # (..., 3, 6)
    lin = concatenate([mass_lin, h_lin, zeros(batch + (3, 6))], -1)
    ang = concatenate([zeros(batch + (3, 1)), h_ang, i_ang], -1)
    return transposed(lin), transposed(ang)


def _inertia_map(x):
    """``L(x)`` with ``I x = L(x) iota`` for ``iota = (xx, xy, yy, xz, yz, zz)``: (..., 3, 6)."""
    if isinstance(x, Jet):
        return Jet(_inertia_map(x.val), _inertia_map(x.dot))

    def build(v):
        a, b, c = v[..., 0], v[..., 1], v[..., 2]
        out = np.zeros(v.shape[:-1] + (3, 6))
        out[..., 0, 0], out[..., 0, 1], out[..., 0, 3] = a, b, c
        out[..., 1, 1], out[..., 1, 2], out[..., 1, 4] = a, b, c
        out[..., 2, 3], out[..., 2, 4], out[..., 2, 5] = a, b, c
        return out

    return Ball(build(x.mid), build(x.rad))
