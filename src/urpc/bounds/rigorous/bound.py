"""The ``rigorous`` bound method: the interval Newton-Euler recursion of :mod:`urpc.bounds.rigorous`
over the parameter box, outward-rounded to doubles."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from flint import arb, ctx

from ...errors import InputError, did_you_mean
from ...model.joint_dynamics import STICTION_VELOCITY, JointBox
from ...model.point import ParameterPoint
from ...model.regressor import state_vector_error
from ...model.robot import Robot
from ...model.uncertainty import ParameterBox, physical_coordinates
from ..base import BoundMethod
from .balls import (
    HALF,
    PRECISION,
    ZERO,
    ZERO3,
    Mat,
    Motion,
    Vec,
    add,
    cross,
    dot,
    interval_ball,
    lower_float,
    rotate_back,
    scale,
    to_mat,
    to_vec,
    upper_float,
)
from .model import (
    Term,
    barycentric_of_physical,
    joint_pose,
    joints_of,
    link_box_balls,
    placed_in_body,
    to_balls,
)
from .spatial import act_force, act_inverse, add_force, body_force, subtract_force


class RigorousBound(BoundMethod):
    """Sound enclosure of ``w`` by an interval RNEA on Arb balls, outward-rounded to doubles.

    Independent of Pinocchio's algorithms and of the regressor; slower than the fast methods
    (milliseconds per call) and looser (interval dependency), but every result is a proven
    enclosure of the exact ``w`` of the model over the box.
    """

    name = "rigorous"

    def __init__(self, robot: Robot, box: ParameterBox):
        super().__init__(robot, box)
        self._kinds = {link_box.link: link_box.kind for link_box in box.links}
        with ctx.workprec(PRECISION):
            self._joints = joints_of(self.robot)
            self._gravity = to_vec(-np.asarray(self.robot.model.gravity.linear, dtype=float))
            self._link_frames = {
                link.name: (to_mat(link.placement.rotation), to_vec(link.placement.translation))
                for link in self.robot.links
                if link.joint_index > 0
            }
            self._nominal_bodies = self._body_parameters({})
            uncertain = {b.link: b for b in box.uncertain_links}
            self._terms: list[list[Term]] = [[] for _ in self._joints]
            for link in self.robot.links:
                if link.name in uncertain:
                    link_box = uncertain[link.name]
                    physical = link_box.kind == "physical"
                    R, p = self._link_frames[link.name]
                    nominal = physical_coordinates(link.inertia)
                    nominal_balls = to_balls(nominal)
                    if not physical:
                        nominal_balls = barycentric_of_physical(nominal_balls)
                    box_balls = link_box_balls(link_box)
                    self._terms[link.joint_index - 1].append(
                        Term(
                            link.name,
                            physical,
                            placed_in_body(box_balls, physical, R, p),
                            placed_in_body(nominal_balls, physical, R, p),
                        )
                    )

    # ------------------------------------------------------------------------- public API
    def enclose(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` [N m or N]: outward-rounded doubles around :meth:`enclose_balls`,
        plus ``[-beta_d, beta_d]`` when the disturbance bound is known (Theorem 1)."""
        balls = self.enclose_balls(q, qd, qd_a, qdd_a)
        lower = np.array([lower_float(b) for b in balls])
        upper = np.array([upper_float(b) for b in balls])
        if not (np.isfinite(lower).all() and np.isfinite(upper).all()):
            raise InputError(
                "the state is too large for double precision: the enclosure of the mismatch "
                f"torque overflows (|qd| = {np.max(np.abs(qd)):.3g}, "
                f"|qd_a| = {np.max(np.abs(qd_a)):.3g}, |qdd_a| = {np.max(np.abs(qdd_a)):.3g})",
                field="qd",
            )
        if self.disturbance_bound:
            lower, upper = self._add_disturbance(lower, upper)
            # One rounded-to-nearest subtraction/addition: one ulp outward covers it.
            lower, upper = np.nextafter(lower, -np.inf), np.nextafter(upper, np.inf)
        return lower, upper

    def enclose_balls(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> list[arb]:
        """Balls containing ``w_i`` [N m or N] for every parameter point of the box (``d = 0``),
        the joint terms included (:func:`joint_balls`)."""
        with ctx.workprec(PRECISION):
            poses, motions = self._forward(*self._state(q, qd, qd_a, qdd_a))
            forces: list[tuple[Vec, Vec] | None] = []
            for terms, motion in zip(self._terms, motions, strict=True):
                force = None
                for term in terms:
                    difference = subtract_force(
                        body_force(term.box, term.physical, *motion),
                        body_force(term.nominal, term.physical, *motion),
                    )
                    force = difference if force is None else add_force(force, difference)
                forces.append(force)
            torques = self._backward(forces, poses)
            if self.joints is not None:
                joint_terms = joint_balls(self.joints, qd, qd_a, qdd_a)
                torques = [t + j for t, j in zip(torques, joint_terms, strict=True)]
            return torques

    def torque_balls(
        self,
        q: np.ndarray,
        qd: np.ndarray,
        qd_a: np.ndarray,
        qdd_a: np.ndarray,
        point: ParameterPoint | Mapping[str, np.ndarray] | None = None,
    ) -> list[arb]:
        """Balls containing ``M(q) qdd_a + C(q, qd) qd_a + g(q)`` [N m or N] of the robot at a
        parameter point (a :class:`~urpc.model.point.ParameterPoint` or its older ``dict``: link
        name -> coordinates in the kind of that link's box, physical ``PHYSICAL_FIELDS`` for a
        link without a box; links not named stay nominal), as in :meth:`ParameterBox.plant`. The
        point version of the enclosure, for validation against Pinocchio.

        Raises:
            InputError: a vector of the wrong shape, an unknown link name in ``point``, or joint
                parameters in it (the rigid-body torque has none).
        """
        point = ParameterPoint({}) if point is None else ParameterPoint.coerce(point)
        if point.joints is not None:
            raise InputError(
                "torque_balls is the rigid-body torque: give a point without joint parameters",
                field="point",
            )
        with ctx.workprec(PRECISION):
            bodies = self._body_parameters(point.links) if point.links else self._nominal_bodies
            poses, motions = self._forward(*self._state(q, qd, qd_a, qdd_a))
            forces = [
                body_force(body, False, *motion)
                for body, motion in zip(bodies, motions, strict=True)
            ]
            return self._backward(forces, poses)

    def torque_and_enclosure(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """As :meth:`BoundMethod.torque_and_enclosure`, the nominal torque from Pinocchio (this
        method has no regressor)."""
        robot = self.robot
        nominal = robot.M(q) @ qdd_a + robot.C(q, qd) @ qd_a + robot.g(q)  # with armature
        lower, upper = self.enclose(q, qd, qd_a, qdd_a)
        if self.joints is not None:
            nominal += self.joints.nominal_torque(qd_a, qdd_a, armature=False)
        return nominal, lower, upper

    # ------------------------------------------------------------------------- internals
    def _state(self, *vectors: np.ndarray) -> list[list[arb]]:
        named = dict(zip(("q", "qd", "qd_a", "qdd_a"), vectors, strict=True))
        problem = state_vector_error(self.robot, **named)  # wrong shape, NaN or inf
        if problem is not None:
            raise problem
        return [[arb(float(x)) for x in np.asarray(v, dtype=float)] for v in vectors]

    def _body_parameters(self, point: Mapping[str, np.ndarray]) -> list[tuple[arb, ...]]:
        """Barycentric parameters (body frame) of every body, summed over its links, with the
        named links at ``point``.

        Raises:
            InputError: a name of ``point`` is not a moving link.
        """
        unknown = sorted(set(point) - set(self._link_frames))
        if unknown:
            raise InputError(
                f"unknown or fixed links {unknown} in the parameter point; "
                + did_you_mean(unknown[0], self._link_frames)
            )
        bodies = [[ZERO] * 10 for _ in range(self.robot.dof)]
        for link in self.robot.links:
            if link.joint_index == 0:
                continue
            if link.name in point:
                coordinates = to_balls(point[link.name])
                if self._kinds.get(link.name, "physical") == "physical":
                    coordinates = barycentric_of_physical(coordinates)
            else:
                coordinates = barycentric_of_physical(to_balls(physical_coordinates(link.inertia)))
            R, p = self._link_frames[link.name]
            placed = placed_in_body(coordinates, False, R, p)
            body = bodies[link.joint_index - 1]
            for k in range(10):
                body[k] = body[k] + placed[k]
        return [tuple(body) for body in bodies]

    def _forward(
        self, q: list[arb], qd: list[arb], qd_a: list[arb], qdd_a: list[arb]
    ) -> tuple[list[tuple[Mat, Vec]], list[tuple[Motion, Motion, Motion]]]:
        """Pose ``(R, t)`` of every body in its parent, and its velocities ``V`` (from ``qd``),
        ``W`` (from ``qd_a``) and symmetrized acceleration ``A``, in body frames."""
        poses: list[tuple[Mat, Vec]] = []
        motions: list[tuple[Motion, Motion, Motion]] = []
        for i, joint in enumerate(self._joints):
            R, t = joint_pose(joint, q[i])
            poses.append((R, t))
            axis = joint.axis
            if joint.parent < 0:
                V_lin, V_ang, W_lin, W_ang = ZERO3, ZERO3, ZERO3, ZERO3
                A_lin, A_ang = rotate_back(R, self._gravity), ZERO3
            else:
                (V_lin, V_ang), (W_lin, W_ang), (A_lin, A_ang) = (
                    act_inverse(R, t, motion) for motion in motions[joint.parent]
                )
            if joint.revolute:
                V_ang = add(V_ang, scale(qd[i], axis))
                W_ang = add(W_ang, scale(qd_a[i], axis))
                A_ang = add(A_ang, scale(qdd_a[i], axis))
                # (V x S qd_a_i + W x S qd_i) / 2 with S = (0, axis).
                A_lin = add(A_lin, _half_cross_sum(qd_a[i], V_lin, qd[i], W_lin, axis))
                A_ang = add(A_ang, _half_cross_sum(qd_a[i], V_ang, qd[i], W_ang, axis))
            else:
                V_lin = add(V_lin, scale(qd[i], axis))
                W_lin = add(W_lin, scale(qd_a[i], axis))
                A_lin = add(A_lin, scale(qdd_a[i], axis))
                # S = (axis, 0): V x S x = (omega x axis x, 0).
                A_lin = add(A_lin, _half_cross_sum(qd_a[i], V_ang, qd[i], W_ang, axis))
            motions.append(((V_lin, V_ang), (W_lin, W_ang), (A_lin, A_ang)))
        return poses, motions

    def _backward(
        self, forces: list[tuple[Vec, Vec] | None], poses: list[tuple[Mat, Vec]]
    ) -> list[arb]:
        """``tau_i = S_i^T F_i`` with ``F_i`` the force of body ``i`` plus its children's."""
        total = list(forces)
        tau = [ZERO] * len(self._joints)
        for i in reversed(range(len(self._joints))):
            force = total[i]
            if force is None:
                continue
            joint = self._joints[i]
            tau[i] = dot(joint.axis, force[1] if joint.revolute else force[0])
            if joint.parent >= 0:
                R, t = poses[i]
                moved = act_force(R, t, force)
                parent = total[joint.parent]
                total[joint.parent] = moved if parent is None else add_force(parent, moved)
        return tau


def _half_cross_sum(a: arb, V: Vec, b: arb, W: Vec, axis: Vec) -> Vec:
    """``(a V x axis + b W x axis) / 2``: a joint's term of the symmetrized acceleration."""
    return add(scale(HALF * a, cross(V, axis)), scale(HALF * b, cross(W, axis)))


def joint_balls(joints: JointBox, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray) -> list[arb]:
    """Balls containing the joint terms of ``w`` (:meth:`JointBox.enclose`, here in exact
    interval arithmetic): ``(Ia - Ia0) qdd_a + Dv qd - Dv0 qd_a`` over the box, plus the Coulomb
    friction the set-valued law (or the stiction band) allows at ``qd``, minus
    ``Fc0 sat(qd_a / v_s)``."""
    balls = []
    band = arb(STICTION_VELOCITY)
    for i in range(joints.dof):
        v, va, a = float(qd[i]), float(qd_a[i]), float(qdd_a[i])
        lower, upper, nominal = joints.lower[:, i], joints.upper[:, i], joints.nominal[:, i]
        ball = (interval_ball(lower[0], upper[0]) - arb(nominal[0])) * arb(a)
        ball += interval_ball(lower[1], upper[1]) * arb(v) - arb(nominal[1]) * arb(va)
        if v >= STICTION_VELOCITY:
            friction = interval_ball(lower[2], upper[2])
        elif v <= -STICTION_VELOCITY:
            friction = -interval_ball(lower[2], upper[2])
        else:
            friction = interval_ball(-upper[2], upper[2])
        if va >= STICTION_VELOCITY:
            shape = arb(1)
        elif va <= -STICTION_VELOCITY:
            shape = arb(-1)
        else:
            shape = arb(va) / band
        balls.append(ball + friction - arb(nominal[2]) * shape)
    return balls
