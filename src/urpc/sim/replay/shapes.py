"""What a replay draws of a robot: its URDF visual geometry, or a skeleton made from its kinematics.

Each :class:`Shape` is a meshcat geometry fixed to one Pinocchio joint (``joint = 0``: the fixed
base), at a placement in that joint's frame. The URDF's visual geometry comes from Pinocchio
(``buildGeomFromUrdf``, reduced like the model when joints are locked): boxes, cylinders, spheres
and mesh files (DAE, STL, OBJ, embedded in the page). A URDF without visuals (``rr_planar``), or
whose mesh files cannot be found, is drawn as a skeleton: a cylinder along each joint axis and a
rod from each joint to the next joint or to a frame beyond the last one (the tool).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ...errors import InputError
from ...model.robot import Robot

#: Colors (0xRRGGBB) of the skeleton: rods, joints, the end-effector marker.
ROD_COLOR, JOINT_COLOR, END_EFFECTOR_COLOR = 0x4C72B0, 0x333333, 0xFF7F0E
#: The meshcat (three.js) cylinder runs along y; Pinocchio's (coal) along z.
_Y_TO_Z = pin.SE3(pin.utils.rotate("x", np.pi / 2), np.zeros(3))


class ReplayGeometryWarning(UserWarning):
    """The URDF's visual geometry could not be used entirely; the replay draws a skeleton."""


@dataclass(frozen=True)
class Shape:
    """One piece of geometry fixed to a joint.

    Attributes:
        name: Unique name (a scene path element).
        joint: Pinocchio joint index carrying it (0: the base).
        placement: Pose in that joint's frame (for a cylinder: its axis along z).
        geometry: The meshcat geometry (its own frame as three.js has it).
        color: 0xRRGGBB.
        scale: Per-axis scale of a mesh.
        link: The URDF link it belongs to ("" for a skeleton shape).
    """

    name: str
    joint: int
    placement: pin.SE3
    geometry: Any
    color: int
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    link: str = ""

    def matrix(self) -> np.ndarray:
        """The 4x4 transform of the meshcat object in the joint frame (scale included)."""
        placement = self.placement
        if type(self.geometry).__name__ == "Cylinder":
            placement = placement * _Y_TO_Z
        return placement.homogeneous @ np.diag([*self.scale, 1.0])


def end_effector_frame(model: pin.Model, name: str | None = None) -> int:
    """The frame id of the end effector: ``name``, or the last body frame carried by the last
    joint (``tool`` of rr_planar, ``tcp`` of a modular arm, ``tool0`` of the UR5)."""
    if name is not None:
        if not model.existFrame(name):
            names = [frame.name for frame in model.frames]
            raise InputError(f"no frame '{name}' in the model; valid: {', '.join(names)}")
        return model.getFrameId(name)
    last = model.njoints - 1
    bodies = [
        i
        for i, frame in enumerate(model.frames)
        if frame.parentJoint == last and frame.type == pin.FrameType.BODY
    ]
    if bodies:
        return bodies[-1]
    return next(i for i, frame in enumerate(model.frames) if frame.parentJoint == last)


def robot_shapes(robot: Robot, colors: Mapping[str, int] | None = None) -> list[Shape]:
    """The shapes of ``robot``: its URDF visuals, else its skeleton (with a
    :class:`ReplayGeometryWarning` when visuals exist but cannot be loaded).

    Args:
        robot: The robot (its URDF file must still exist for the visuals).
        colors: URDF link name -> 0xRRGGBB, overriding the URDF's colors.
    """
    try:
        shapes = visual_shapes(robot, colors or {})
    except (OSError, RuntimeError, ValueError) as exc:
        warnings.warn(
            ReplayGeometryWarning(
                f"{robot.name}: the URDF's visual geometry cannot be loaded ({_one_line(exc)}); "
                "the replay draws the arm's skeleton"
            ),
            stacklevel=2,
        )
        shapes = []
    return shapes or skeleton_shapes(robot)


def visual_shapes(robot: Robot, colors: Mapping[str, int]) -> list[Shape]:
    """The URDF's visual geometry (empty when the URDF has none)."""
    import meshcat.geometry as mg

    urdf = Path(robot.urdf_path)
    full = pin.buildModelFromUrdf(str(urdf))
    # package://NAME/... is resolved against every folder above the URDF (example-robot-data's
    # share/ folder, a ROS workspace).
    packages = [str(folder) for folder in urdf.resolve().parents]
    geometry = pin.buildGeomFromUrdf(
        full, str(urdf), pin.GeometryType.VISUAL, package_dirs=packages
    )
    if robot.locked_joints:
        ids = [full.getJointId(name) for name in robot.locked_joints]
        reference = pin.neutral(full)
        for name, value in robot.locked_joints.items():
            joint = full.joints[full.getJointId(name)]
            if joint.nq == 2:
                reference[joint.idx_q : joint.idx_q + 2] = np.cos(value), np.sin(value)
            else:
                reference[joint.idx_q] = value
        full, geometry = pin.buildReducedModel(full, geometry, ids, reference)
    shapes = []
    for k, item in enumerate(geometry.geometryObjects):
        joint = robot.model.getJointId(full.names[item.parentJoint]) if item.parentJoint else 0
        link = full.frames[item.parentFrame].name
        color = colors.get(link, _rgb(item.meshColor))
        solid = item.geometry
        kind = type(solid).__name__
        if kind == "Box":
            shape = mg.Box(list(2.0 * np.asarray(solid.halfSide)))
        elif kind in ("Cylinder", "Capsule"):
            shape = mg.Cylinder(2.0 * float(solid.halfLength), float(solid.radius))
        elif kind == "Sphere":
            shape = mg.Sphere(float(solid.radius))
        elif item.meshPath and Path(item.meshPath).suffix.lower() in _MESH_LOADERS:
            loader = _MESH_LOADERS[Path(item.meshPath).suffix.lower()]
            shape = getattr(mg, loader).from_file(item.meshPath)
        else:
            raise ValueError(f"'{item.name}' is a {kind}, which the replay cannot draw")
        shapes.append(
            Shape(
                f"visual{k}",
                joint,
                item.placement.copy(),
                shape,
                color,
                tuple(float(s) for s in item.meshScale),
                link,
            )
        )
    return shapes


_MESH_LOADERS = {".dae": "DaeMeshGeometry", ".stl": "StlMeshGeometry", ".obj": "ObjMeshGeometry"}


def skeleton_shapes(robot: Robot) -> list[Shape]:
    """A cylinder along each joint axis and a rod from each joint to its children (and to the
    frames beyond the last joints), sized from the arm's reach."""
    import meshcat.geometry as mg

    model = robot.model
    data = model.createData()
    neutral = pin.neutral(model)
    pin.computeJointJacobians(model, data, neutral)
    pin.framesForwardKinematics(model, data, neutral)
    ends = _rod_ends(model, data)
    reach = max([np.linalg.norm(v) for _, v in ends] + [0.1])
    radius = 0.03 * reach
    shapes: list[Shape] = []
    for j in range(1, model.njoints):
        jacobian = pin.getJointJacobian(model, data, j, pin.ReferenceFrame.LOCAL)
        column = jacobian[:, model.joints[j].idx_v]
        axis = column[3:] if np.linalg.norm(column[3:]) > 0.5 else column[:3]
        shapes.append(
            Shape(
                f"joint{j}",
                j,
                pin.SE3(_rotation_to(axis), np.zeros(3)),
                mg.Cylinder(4.0 * radius, 1.6 * radius),
                JOINT_COLOR,
            )
        )
    for k, (j, vector) in enumerate(ends):
        length = float(np.linalg.norm(vector))
        if length < 1e-9:
            continue
        placement = pin.SE3(_rotation_to(vector), 0.5 * vector)
        shapes.append(Shape(f"rod{k}", j, placement, mg.Cylinder(length, radius), ROD_COLOR))
    return shapes


def _rod_ends(model: pin.Model, data: pin.Data) -> list[tuple[int, np.ndarray]]:
    """``(joint, vector in its frame)`` to each child joint, and to each frame of a joint without
    children (its farthest one: the tool)."""
    ends = []
    parents = set()
    for j in range(1, model.njoints):
        parent = model.parents[j]
        parents.add(parent)
        ends.append((parent, np.asarray(model.jointPlacements[j].translation).copy()))
    for j in range(model.njoints):
        if j in parents:
            continue
        offsets = [
            np.asarray(frame.placement.translation)
            for frame in model.frames
            if frame.parentJoint == j
        ]
        if offsets:
            ends.append((j, max(offsets, key=np.linalg.norm).copy()))
    return ends


def _rotation_to(vector: np.ndarray) -> np.ndarray:
    """A rotation taking z to the direction of ``vector``."""
    z = np.asarray(vector, dtype=float) / np.linalg.norm(vector)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _rgb(rgba: np.ndarray) -> int:
    r, g, b = (int(round(255 * float(np.clip(c, 0.0, 1.0)))) for c in np.asarray(rgba)[:3])
    return (r << 16) | (g << 8) | b


def _one_line(exc: Exception) -> str:
    return " ".join(str(exc).split())
