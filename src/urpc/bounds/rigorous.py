"""``rigorous``: an interval Newton-Euler enclosure of ``w`` with outward rounding (Arb balls).

This is the test oracle and the "paper-faithful" mode: the paper evaluated the dynamics over the
parameter box with INTLAB; here the recursive Newton-Euler algorithm (RNEA) is evaluated on
python-flint ``arb`` balls, whose every operation returns a ball that contains the exact result.
It is independent of the fast path: no Pinocchio algorithm, no regressor, no floating-point
arithmetic on the result. Only the model's *data* come from Pinocchio (joint placements, joint
axes, parents, gravity) and from the URDF links (placements, inertias), converted to balls exactly.

The mismatch torque of the paper's eq. (7) over the box ``D``::

    w(D) = tau(q, qd, qd_a, qdd_a; D) - tau(q, qd, qd_a, qdd_a; D0)
    tau  = M(q, D) qdd_a + C(q, qd, D) qd_a + g(q, D)

``C(q, v) w`` is the symmetric bilinear form that polarizes ``c(q, x) = C(q, x) x``, so one RNEA
pass with two velocity sets ``V`` (from ``qd``) and ``W`` (from ``qd_a``) computes ``tau`` when
every quadratic velocity product ``B(x, x)`` of the RNEA is replaced by ``(B(V, W) + B(W, V)) / 2``
(for any bilinear ``B``, ``(B(v+w, v+w) - B(v-w, v-w)) / 4 = (B(v, w) + B(w, v)) / 2``)::

    V_i = X_i V_p + S_i qd_i,   W_i = X_i W_p + S_i qd_a_i,   A_0 = -gravity
    A_i = X_i A_p + S_i qdd_a_i + (V_i x S_i qd_a_i + W_i x S_i qd_i) / 2
    f_i = I_i A_i + (V_i x* I_i W_i + W_i x* I_i V_i) / 2
    tau_i = S_i^T F_i,   F_i = f_i + sum over children k of X_k^* F_k

(Pinocchio's conventions: spatial vectors are ``(linear, angular)``, expressed in the body frame.)
``tau`` is linear in the inertias, so ``w`` is the same recursion with ``f_i`` replaced by
``f_i(box) - f_i(nominal)`` summed over the uncertain links of body ``i`` (exact links cancel
exactly). The interval parameters enter as given by the user: a physical box as mass, center of
mass and inertia about the center of mass (``f_lin = m (a - c x alpha)``,
``f_ang = I_C alpha + c x f_lin``), a barycentric box as ``m, h = m c, I_O``.

Interval evaluation overestimates (each parameter occurs several times in ``f_i``, and rotating an
interval force box wraps it); ``python tests/test_rigorous.py`` measures by how much against a
dense sampled inner hull and against the fast ``hull`` method.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from flint import arb, ctx

from ..errors import InputError, UrpcError, did_you_mean
from ..model.robot import Robot
from ..model.uncertainty import LinkBox, ParameterBox, physical_coordinates
from .base import BoundMethod

#: Working precision of the Arb balls [bits]. Inputs are doubles (exact at any precision); 64 bits
#: keep the midpoints' rounding well below the double resolution of the result.
PRECISION = 64

Vec = tuple[arb, arb, arb]
Motion = tuple[Vec, Vec]  # (linear, angular)
Mat = tuple[Vec, Vec, Vec]  # rows

_ZERO = arb(0)
_HALF = arb(0.5)
_ZERO3: Vec = (_ZERO, _ZERO, _ZERO)
#: Symmetric 3x3 tensor components in Pinocchio's order: xx, xy, yy, xz, yz, zz.
_SYM_INDEX = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))


# ============================================================================ conversions
def interval_ball(lower: float, upper: float) -> arb:
    """An Arb ball containing the whole interval ``[lower, upper]`` (both ends exactly)."""
    lo, hi = arb(float(lower)), arb(float(upper))
    if lower == upper:
        return lo
    if not lower < upper:
        raise InputError(f"empty interval [{lower}, {upper}]")
    return lo.union(hi)


def lower_float(ball: arb) -> float:
    """The largest double ``x`` with ``x <= ball`` as checked exactly (outward rounding down)."""
    if not ball.is_finite():
        return -np.inf
    bound = ball.lower()  # an exact ball (zero radius) below every point of ``ball``
    x = float(bound)
    while arb(x) > bound:
        x = float(np.nextafter(x, -np.inf))
    return x


def upper_float(ball: arb) -> float:
    """The smallest double ``x`` with ``x >= ball`` as checked exactly (outward rounding up)."""
    if not ball.is_finite():
        return np.inf
    bound = ball.upper()
    x = float(bound)
    while arb(x) < bound:
        x = float(np.nextafter(x, np.inf))
    return x


def _vec(values: Sequence[float]) -> Vec:
    return (arb(float(values[0])), arb(float(values[1])), arb(float(values[2])))


def _mat(matrix: np.ndarray) -> Mat:
    return tuple(_vec(row) for row in np.asarray(matrix, dtype=float))  # type: ignore[return-value]


# ============================================================================ 3-vector algebra
def _add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _scale(s: arb, a: Vec) -> Vec:
    return (s * a[0], s * a[1], s * a[2])


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a: Vec, b: Vec) -> arb:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _rotate(R: Mat, v: Vec) -> Vec:
    return (_dot(R[0], v), _dot(R[1], v), _dot(R[2], v))


def _rotate_back(R: Mat, v: Vec) -> Vec:
    """``R^T v``."""
    return (
        R[0][0] * v[0] + R[1][0] * v[1] + R[2][0] * v[2],
        R[0][1] * v[0] + R[1][1] * v[1] + R[2][1] * v[2],
        R[0][2] * v[0] + R[1][2] * v[1] + R[2][2] * v[2],
    )


def _sym_times(I: Sequence[arb], v: Vec) -> Vec:
    """Symmetric tensor (components xx, xy, yy, xz, yz, zz) times a vector."""
    xx, xy, yy, xz, yz, zz = I
    return (
        xx * v[0] + xy * v[1] + xz * v[2],
        xy * v[0] + yy * v[1] + yz * v[2],
        xz * v[0] + yz * v[1] + zz * v[2],
    )


# ============================================================================ model data
@dataclass(frozen=True)
class _Joint:
    """One 1-dof joint: ``parent`` body index (-1: the base), the constant placement of the joint
    frame in the parent frame, its axis (joint frame) and whether it turns or slides."""

    parent: int
    placement_rotation: Mat
    placement_translation: Vec
    axis: Vec
    revolute: bool
    aligned: int | None  # k when the axis is exactly +e_k or -e_k
    aligned_sign: int


@dataclass(frozen=True)
class _Term:
    """One uncertain link as seen by its body: its 10 coordinates in the body frame, as balls over
    the box and as exact(ly enclosed) nominal values. ``physical``: ``m, c, I_C``; otherwise
    ``m, h, I_O`` (about the body origin)."""

    name: str
    physical: bool
    box: tuple[arb, ...]
    nominal: tuple[arb, ...]


def _joints(robot: Robot) -> tuple[_Joint, ...]:
    model = robot.model
    neutral = pin.neutral(model)
    joints = []
    for j in range(1, model.njoints):
        shortname = model.joints[j].shortname()
        kind = robot.joint_kinds[j - 1]
        if model.joints[j].idx_v != j - 1:
            raise UrpcError(f"joint '{model.names[j]}' is not the {j}-th velocity coordinate")
        # The motion subspace S = (linear, angular) of a 1-dof joint is constant: the axis.
        joint_data = model.joints[j].createData()
        model.joints[j].calc(joint_data, neutral)
        subspace = np.asarray(joint_data.S, dtype=float).reshape(6)
        revolute = kind in ("revolute", "continuous")
        axis = subspace[3:] if revolute else subspace[:3]
        if np.any(subspace[:3] if revolute else subspace[3:]):
            raise UrpcError(f"joint '{model.names[j]}' ({shortname}) has a screw motion subspace")
        nonzero = np.flatnonzero(axis)
        aligned = int(nonzero[0]) if len(nonzero) == 1 and abs(axis[nonzero[0]]) == 1.0 else None
        sign = int(np.sign(axis[aligned])) if aligned is not None else 1
        placement = model.jointPlacements[j]
        joints.append(
            _Joint(
                parent=model.parents[j] - 1,
                placement_rotation=_mat(placement.rotation),
                placement_translation=_vec(placement.translation),
                axis=_vec(axis),
                revolute=revolute,
                aligned=aligned,
                aligned_sign=sign,
            )
        )
    return tuple(joints)


def _balls(values: Sequence[float]) -> tuple[arb, ...]:
    return tuple(arb(float(v)) for v in values)


def _barycentric_of_physical(p: Sequence[arb]) -> tuple[arb, ...]:
    """``m, h = m c, I_O = I_C + m S(c)^T S(c)`` of physical coordinates (balls)."""
    m, cx, cy, cz, ixx, ixy, iyy, ixz, iyz, izz = p
    return (
        m,
        m * cx,
        m * cy,
        m * cz,
        ixx + m * (cy * cy + cz * cz),
        ixy - m * cx * cy,
        iyy + m * (cx * cx + cz * cz),
        ixz - m * cx * cz,
        iyz - m * cy * cz,
        izz + m * (cx * cx + cy * cy),
    )


def _placed(coordinates: Sequence[arb], physical: bool, R: Mat, p: Vec) -> tuple[arb, ...]:
    """Coordinates of a link's inertia moved from its link frame to its body frame (``R, p``: the
    link frame's pose in the body frame).

    Every output coordinate is evaluated as one linear form of the input coordinates (coefficients
    from ``R, p`` only), so each interval coordinate occurs once per output: no dependency loss.

    physical:     ``c' = p + R c``, ``I_C' = R I_C R^T``;
    barycentric:  ``h' = m p + R h``, ``I_O' = R I_O R^T + m (|p|^2 1 - p p^T)
                  - (u p^T + p u^T) + 2 (p . u) 1`` with ``u = R h``.
    """
    m = coordinates[0]
    first = coordinates[1:4]
    tensor = coordinates[4:10]
    # R T R^T, entry (a, b), as a linear form of the 6 components of T.
    rotated = []
    for a, b in _SYM_INDEX:
        total = _ZERO
        for (k, l), t in zip(_SYM_INDEX, tensor, strict=True):
            coefficient = R[a][k] * R[b][l] if k == l else R[a][k] * R[b][l] + R[a][l] * R[b][k]
            total = total + coefficient * t
        rotated.append(total)
    if physical:
        com = tuple(p[a] + _dot(R[a], first) for a in range(3))
        return (m, *com, *rotated)
    h = tuple(p[a] * m + _dot(R[a], first) for a in range(3))
    p_squared = _dot(p, p)
    inertia = []
    for (a, b), part in zip(_SYM_INDEX, rotated, strict=True):
        delta = 1 if a == b else 0
        total = part + m * ((p_squared if delta else _ZERO) - p[a] * p[b])
        for k in range(3):
            # u = R h: the coefficient of h_k in -(u_a p_b + p_a u_b) + 2 delta_ab (p . u).
            coefficient = -(R[a][k] * p[b] + p[a] * R[b][k])
            if delta:
                coefficient = coefficient + 2 * (p[0] * R[0][k] + p[1] * R[1][k] + p[2] * R[2][k])
            total = total + coefficient * first[k]
        inertia.append(total)
    return (m, *h, *inertia)


def _box_balls(link_box: LinkBox) -> tuple[arb, ...]:
    """One ball per coordinate of a link box, each containing its whole interval."""
    return tuple(
        interval_ball(lo, hi) for lo, hi in zip(link_box.lower, link_box.upper, strict=True)
    )


# ============================================================================ the bound
class RigorousBound(BoundMethod):
    """Sound enclosure of ``w`` by an interval RNEA on Arb balls, outward-rounded to doubles.

    Independent of Pinocchio's algorithms and of the regressor; slower than the fast methods
    (milliseconds per call) and looser (interval dependency), but every result is a proven
    enclosure of the exact ``w`` of the model over the box.

    Raises:
        UrpcError: from :meth:`enclose_regressor` (this method does not use the regressor).
    """

    name = "rigorous"
    uses_regressor = False

    def __init__(self, robot: Robot, box: ParameterBox):
        super().__init__(robot, box)
        self._kinds = {link_box.link: link_box.kind for link_box in box.links}
        with ctx.workprec(PRECISION):
            self._joints = _joints(self.robot)
            self._gravity = _vec(-np.asarray(self.robot.model.gravity.linear, dtype=float))
            self._link_frames = {
                link.name: (_mat(link.placement.rotation), _vec(link.placement.translation))
                for link in self.robot.links
                if link.joint_index > 0
            }
            self._nominal_bodies = self._body_parameters({})
            uncertain = {b.link: b for b in box.uncertain_links}
            self._terms: list[list[_Term]] = [[] for _ in self._joints]
            for link in self.robot.links:
                if link.name in uncertain:
                    link_box = uncertain[link.name]
                    physical = link_box.kind == "physical"
                    R, p = self._link_frames[link.name]
                    nominal = physical_coordinates(link.inertia)
                    nominal_balls = _balls(nominal)
                    if not physical:
                        nominal_balls = _barycentric_of_physical(nominal_balls)
                    box_balls = _box_balls(link_box)
                    self._terms[link.joint_index - 1].append(
                        _Term(
                            link.name,
                            physical,
                            _placed(box_balls, physical, R, p),
                            _placed(nominal_balls, physical, R, p),
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
        if self.disturbance_bound:
            lower, upper = self._add_disturbance(lower, upper)
            # One rounded-to-nearest subtraction/addition: one ulp outward covers it.
            lower, upper = np.nextafter(lower, -np.inf), np.nextafter(upper, np.inf)
        return lower, upper

    def enclose_balls(
        self, q: np.ndarray, qd: np.ndarray, qd_a: np.ndarray, qdd_a: np.ndarray
    ) -> list[arb]:
        """Balls containing ``w_i`` [N m or N] for every parameter point of the box (``d = 0``)."""
        with ctx.workprec(PRECISION):
            poses, motions = self._forward(*self._state(q, qd, qd_a, qdd_a))
            forces: list[tuple[Vec, Vec] | None] = []
            for terms, motion in zip(self._terms, motions, strict=True):
                force = None
                for term in terms:
                    difference = _subtract(
                        _body_force(term.box, term.physical, *motion),
                        _body_force(term.nominal, term.physical, *motion),
                    )
                    force = difference if force is None else _add_force(force, difference)
                forces.append(force)
            return self._backward(forces, poses)

    def torque_balls(
        self,
        q: np.ndarray,
        qd: np.ndarray,
        qd_a: np.ndarray,
        qdd_a: np.ndarray,
        point: Mapping[str, np.ndarray] | None = None,
    ) -> list[arb]:
        """Balls containing ``M(q) qdd_a + C(q, qd) qd_a + g(q)`` [N m or N] of the robot at a
        parameter point (link name -> coordinates in the kind of that link's box, physical
        ``PHYSICAL_FIELDS`` for a link without a box; links not named stay nominal), as in
        :meth:`ParameterBox.plant`. The point version of the enclosure, for validation against
        Pinocchio.

        Raises:
            InputError: a vector of the wrong shape, an unknown link name in ``point``.
        """
        with ctx.workprec(PRECISION):
            bodies = self._nominal_bodies if not point else self._body_parameters(point)
            poses, motions = self._forward(*self._state(q, qd, qd_a, qdd_a))
            forces = [
                _body_force(body, False, *motion)
                for body, motion in zip(bodies, motions, strict=True)
            ]
            return self._backward(forces, poses)

    def enclose_regressor(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        raise UrpcError(
            "the 'rigorous' bound evaluates the Newton-Euler recursion on intervals and does not "
            "use the regressor; call enclose(q, qd, qd_a, qdd_a) instead"
        )

    # ------------------------------------------------------------------------- internals
    def _state(self, *vectors: np.ndarray) -> list[list[arb]]:
        balls = []
        for name, vector in zip(("q", "qd", "qd_a", "qdd_a"), vectors, strict=True):
            array = np.asarray(vector, dtype=float)
            if array.shape != (self.robot.dof,):
                raise InputError(f"{name} has shape {array.shape}, expected ({self.robot.dof},)")
            balls.append([arb(float(x)) for x in array])
        return balls

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
        bodies = [[_ZERO] * 10 for _ in range(self.robot.dof)]
        for link in self.robot.links:
            if link.joint_index == 0:
                continue
            if link.name in point:
                coordinates = _balls(point[link.name])
                if self._kinds.get(link.name, "physical") == "physical":
                    coordinates = _barycentric_of_physical(coordinates)
            else:
                coordinates = _barycentric_of_physical(_balls(physical_coordinates(link.inertia)))
            R, p = self._link_frames[link.name]
            placed = _placed(coordinates, False, R, p)
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
            R, t = _joint_pose(joint, q[i])
            poses.append((R, t))
            axis = joint.axis
            if joint.parent < 0:
                V_lin, V_ang, W_lin, W_ang = _ZERO3, _ZERO3, _ZERO3, _ZERO3
                A_lin, A_ang = _rotate_back(R, self._gravity), _ZERO3
            else:
                (V_lin, V_ang), (W_lin, W_ang), (A_lin, A_ang) = (
                    _act_inverse(R, t, motion) for motion in motions[joint.parent]
                )
            if joint.revolute:
                V_ang = _add(V_ang, _scale(qd[i], axis))
                W_ang = _add(W_ang, _scale(qd_a[i], axis))
                A_ang = _add(A_ang, _scale(qdd_a[i], axis))
                # (V x S qd_a_i + W x S qd_i) / 2 with S = (0, axis).
                A_lin = _add(
                    A_lin,
                    _add(
                        _scale(_HALF * qd_a[i], _cross(V_lin, axis)),
                        _scale(_HALF * qd[i], _cross(W_lin, axis)),
                    ),
                )
                A_ang = _add(
                    A_ang,
                    _add(
                        _scale(_HALF * qd_a[i], _cross(V_ang, axis)),
                        _scale(_HALF * qd[i], _cross(W_ang, axis)),
                    ),
                )
            else:
                V_lin = _add(V_lin, _scale(qd[i], axis))
                W_lin = _add(W_lin, _scale(qd_a[i], axis))
                A_lin = _add(A_lin, _scale(qdd_a[i], axis))
                # S = (axis, 0): V x S x = (omega x axis x, 0).
                A_lin = _add(
                    A_lin,
                    _add(
                        _scale(_HALF * qd_a[i], _cross(V_ang, axis)),
                        _scale(_HALF * qd[i], _cross(W_ang, axis)),
                    ),
                )
            motions.append(((V_lin, V_ang), (W_lin, W_ang), (A_lin, A_ang)))
        return poses, motions

    def _backward(
        self, forces: list[tuple[Vec, Vec] | None], poses: list[tuple[Mat, Vec]]
    ) -> list[arb]:
        """``tau_i = S_i^T F_i`` with ``F_i`` the force of body ``i`` plus its children's."""
        total = list(forces)
        tau = [_ZERO] * len(self._joints)
        for i in reversed(range(len(self._joints))):
            force = total[i]
            if force is None:
                continue
            joint = self._joints[i]
            tau[i] = _dot(joint.axis, force[1] if joint.revolute else force[0])
            if joint.parent >= 0:
                R, t = poses[i]
                moved = _act_force(R, t, force)
                parent = total[joint.parent]
                total[joint.parent] = moved if parent is None else _add_force(parent, moved)
        return tau


# ============================================================================ spatial algebra
def _joint_pose(joint: _Joint, angle: arb) -> tuple[Mat, Vec]:
    """Pose ``(R, t)`` of the body frame in the parent frame: placement times joint motion."""
    P = joint.placement_rotation
    if not joint.revolute:
        offset = _scale(angle, joint.axis)
        return P, _add(joint.placement_translation, _rotate(P, offset))
    s, c = angle.sin_cos()
    if joint.aligned is not None:
        k = joint.aligned
        i, j = (k + 1) % 3, (k + 2) % 3
        if joint.aligned_sign < 0:
            s = -s
        # Rotation about e_k: columns e_k -> e_k, e_i -> c e_i + s e_j, e_j -> -s e_i + c e_j.
        rows = []
        for r in range(3):
            row = [_ZERO] * 3
            row[k] = P[r][k]
            row[i] = c * P[r][i] + s * P[r][j]
            row[j] = c * P[r][j] - s * P[r][i]
            rows.append(tuple(row))
        return tuple(rows), joint.placement_translation  # type: ignore[return-value]
    # Rodrigues, as Pinocchio: c 1 + s S(a) + (1 - c) a a^T.
    a = joint.axis
    one_minus_c = 1 - c
    skew = ((_ZERO, -a[2], a[1]), (a[2], _ZERO, -a[0]), (-a[1], a[0], _ZERO))
    J = tuple(
        tuple(
            (c if r == col else _ZERO) + s * skew[r][col] + one_minus_c * a[r] * a[col]
            for col in range(3)
        )
        for r in range(3)
    )
    R = tuple(
        tuple(_dot(P[r], (J[0][col], J[1][col], J[2][col])) for col in range(3)) for r in range(3)
    )
    return R, joint.placement_translation  # type: ignore[return-value]


def _act_inverse(R: Mat, t: Vec, motion: Motion) -> Motion:
    """A motion of the parent frame seen in the child frame: ``(R^T (v - t x w), R^T w)``."""
    linear, angular = motion
    return _rotate_back(R, _sub(linear, _cross(t, angular))), _rotate_back(R, angular)


def _act_force(R: Mat, t: Vec, force: tuple[Vec, Vec]) -> tuple[Vec, Vec]:
    """A force of the child frame seen in the parent frame: ``(R f, R n + t x R f)``."""
    linear = _rotate(R, force[0])
    return linear, _add(_rotate(R, force[1]), _cross(t, linear))


def _add_force(a: tuple[Vec, Vec], b: tuple[Vec, Vec]) -> tuple[Vec, Vec]:
    return _add(a[0], b[0]), _add(a[1], b[1])


def _subtract(a: tuple[Vec, Vec], b: tuple[Vec, Vec]) -> tuple[Vec, Vec]:
    return _sub(a[0], b[0]), _sub(a[1], b[1])


def _inertia_times(parameters: Sequence[arb], physical: bool, motion: Motion) -> tuple[Vec, Vec]:
    """Spatial inertia times a motion ``(x, alpha)``.

    physical ``(m, c, I_C)``: ``(m (x - c x alpha), I_C alpha + c x f_lin)``;
    barycentric ``(m, h, I_O)``: ``(m x - h x alpha, I_O alpha + h x x)``.
    """
    linear, angular = motion
    m, first, tensor = parameters[0], parameters[1:4], parameters[4:10]
    if physical:
        f_lin = _scale(m, _sub(linear, _cross(first, angular)))
        return f_lin, _add(_sym_times(tensor, angular), _cross(first, f_lin))
    return (
        _sub(_scale(m, linear), _cross(first, angular)),
        _add(_sym_times(tensor, angular), _cross(first, linear)),
    )


def _cross_force(motion: Motion, force: tuple[Vec, Vec]) -> tuple[Vec, Vec]:
    """``(v, omega) x* (f, n) = (omega x f, omega x n + v x f)``."""
    v, omega = motion
    return _cross(omega, force[0]), _add(_cross(omega, force[1]), _cross(v, force[0]))


def _body_force(
    parameters: Sequence[arb], physical: bool, V: Motion, W: Motion, A: Motion
) -> tuple[Vec, Vec]:
    """``I A + (V x* I W + W x* I V) / 2`` (the symmetrized Newton-Euler force)."""
    inertial = _inertia_times(parameters, physical, A)
    bias = _add_force(
        _cross_force(V, _inertia_times(parameters, physical, W)),
        _cross_force(W, _inertia_times(parameters, physical, V)),
    )
    return _add(inertial[0], _scale(_HALF, bias[0])), _add(inertial[1], _scale(_HALF, bias[1]))
