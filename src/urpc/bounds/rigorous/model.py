"""The robot's model data as Arb balls: joints (placement, axis, kind) and their poses at an interval
angle, and link inertias moved exactly into their body frames."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from flint import arb

from ...errors import UrpcError
from ...model.robot import Robot
from ...model.uncertainty import LinkBox
from .balls import (
    SYM_INDEX,
    ZERO,
    Mat,
    Vec,
    add,
    dot,
    interval_ball,
    rotate,
    scale,
    to_mat,
    to_vec,
)


# ============================================================================ model data
@dataclass(frozen=True)
class Joint:
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
class Term:
    """One uncertain link as seen by its body: its 10 coordinates in the body frame, as balls over
    the box and as exact(ly enclosed) nominal values. ``physical``: ``m, c, I_C``; otherwise
    ``m, h, I_O`` (about the body origin)."""

    name: str
    physical: bool
    box: tuple[arb, ...]
    nominal: tuple[arb, ...]


def joints_of(robot: Robot) -> tuple[Joint, ...]:
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
            Joint(
                parent=model.parents[j] - 1,
                placement_rotation=to_mat(placement.rotation),
                placement_translation=to_vec(placement.translation),
                axis=to_vec(axis),
                revolute=revolute,
                aligned=aligned,
                aligned_sign=sign,
            )
        )
    return tuple(joints)


def to_balls(values: Sequence[float]) -> tuple[arb, ...]:
    return tuple(arb(float(v)) for v in values)


def barycentric_of_physical(p: Sequence[arb]) -> tuple[arb, ...]:
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


def placed_in_body(coordinates: Sequence[arb], physical: bool, R: Mat, p: Vec) -> tuple[arb, ...]:
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
    for a, b in SYM_INDEX:
        total = ZERO
        for (k, l), t in zip(SYM_INDEX, tensor, strict=True):
            coefficient = R[a][k] * R[b][l] if k == l else R[a][k] * R[b][l] + R[a][l] * R[b][k]
            total = total + coefficient * t
        rotated.append(total)
    if physical:
        com = tuple(p[a] + dot(R[a], first) for a in range(3))
        return (m, *com, *rotated)
    h = tuple(p[a] * m + dot(R[a], first) for a in range(3))
    p_squared = dot(p, p)
    inertia = []
    for (a, b), part in zip(SYM_INDEX, rotated, strict=True):
        delta = 1 if a == b else 0
        total = part + m * ((p_squared if delta else ZERO) - p[a] * p[b])
        for k in range(3):
            # u = R h: the coefficient of h_k in -(u_a p_b + p_a u_b) + 2 delta_ab (p . u).
            coefficient = -(R[a][k] * p[b] + p[a] * R[b][k])
            if delta:
                coefficient = coefficient + 2 * (p[0] * R[0][k] + p[1] * R[1][k] + p[2] * R[2][k])
            total = total + coefficient * first[k]
        inertia.append(total)
    return (m, *h, *inertia)


def link_box_balls(link_box: LinkBox) -> tuple[arb, ...]:
    """One ball per coordinate of a link box, each containing its whole interval."""
    return tuple(
        interval_ball(lo, hi) for lo, hi in zip(link_box.lower, link_box.upper, strict=True)
    )


def joint_pose(joint: Joint, angle: arb) -> tuple[Mat, Vec]:
    """Pose ``(R, t)`` of the body frame in the parent frame: placement times joint motion."""
    P = joint.placement_rotation
    if not joint.revolute:
        offset = scale(angle, joint.axis)
        return P, add(joint.placement_translation, rotate(P, offset))
    s, c = angle.sin_cos()
    if joint.aligned is not None:
        k = joint.aligned
        i, j = (k + 1) % 3, (k + 2) % 3
        if joint.aligned_sign < 0:
            s = -s
        # Rotation about e_k: columns e_k -> e_k, e_i -> c e_i + s e_j, e_j -> -s e_i + c e_j.
        rows = []
        for r in range(3):
            row = [ZERO] * 3
            row[k] = P[r][k]
            row[i] = c * P[r][i] + s * P[r][j]
            row[j] = c * P[r][j] - s * P[r][i]
            rows.append(tuple(row))
        return tuple(rows), joint.placement_translation  # type: ignore[return-value]
    # Rodrigues, as Pinocchio: c 1 + s S(a) + (1 - c) a a^T.
    a = joint.axis
    one_minus_c = 1 - c
    skew = ((ZERO, -a[2], a[1]), (a[2], ZERO, -a[0]), (-a[1], a[0], ZERO))
    J = tuple(
        tuple(
            (c if r == col else ZERO) + s * skew[r][col] + one_minus_c * a[r] * a[col]
            for col in range(3)
        )
        for r in range(3)
    )
    R = tuple(
        tuple(dot(P[r], (J[0][col], J[1][col], J[2][col])) for col in range(3)) for r in range(3)
    )
    return R, joint.placement_translation  # type: ignore[return-value]
