"""The replay's scene as meshcat commands: each robot's shapes, the desired end-effector path, and
one animation that moves every joint with the recorded trajectory.

A replay shows one or more :class:`ReplayPart` in turn (a simulation, or each configuration of the
reconfiguration demo): part ``k`` is visible from its first sample time to the next part's. Scene
paths: ``/urpc/part<k>/<joint name>/<shape>`` (a joint node carries the placement ``oMi`` of that
joint, its shapes are fixed in it), ``/urpc/part<k>/end_effector`` (placement ``oMf`` of the
end-effector frame) and ``/urpc/part<k>/desired_path`` (a line through the desired end-effector
positions). Key frames are recorded samples themselves, never interpolated: frame ``i`` of a part
is the recorded sample nearest to ``i / fps`` seconds, with its exact time.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from ...errors import InputError
from ...model.robot import Robot
from .shapes import END_EFFECTOR_COLOR, Shape, end_effector_frame, robot_shapes

#: Root of the replay in the scene tree.
ROOT = "/urpc"
#: Color of the desired end-effector path.
DESIRED_COLOR = 0x2CA02C
#: Most points of one desired path.
PATH_POINTS = 2000


@dataclass(frozen=True, eq=False)
class ReplayPart:
    """One robot moving along a recorded trajectory.

    Attributes:
        robot: The robot (its kinematics and geometry).
        t: Sample times on the replay's clock [s], ``(K,)``, increasing.
        q: Joint positions [rad or m], ``(K, dof)``.
        q_desired: The reference [rad or m], ``(K, dof)``.
        label: Shown while the part plays.
        colors: URDF link name -> 0xRRGGBB, overriding the URDF's colors.
        extra: More shapes (e.g. a payload), as ``(frame name, Shape)``: the shape's placement is
            in that frame.
        end_effector: Frame of the end effector (default: :func:`end_effector_frame`).
    """

    robot: Robot
    t: np.ndarray
    q: np.ndarray
    q_desired: np.ndarray
    label: str = ""
    colors: Mapping[str, int] = field(default_factory=dict)
    extra: Sequence[tuple[str, Shape]] = ()
    end_effector: str | None = None

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        shape = (len(t), self.robot.dof)
        if t.ndim != 1 or len(t) == 0 or np.any(np.diff(t) < 0):
            raise InputError("a replay needs increasing sample times", field="t")
        for name in ("q", "q_desired"):
            if np.shape(getattr(self, name)) != shape:
                raise InputError(
                    f"{name} has shape {np.shape(getattr(self, name))}, expected {shape} for "
                    f"robot '{self.robot.name}'",
                    field=name,
                )


def frame_indices(t: np.ndarray, fps: float) -> np.ndarray:
    """Indices of the recorded samples shown as key frames: the sample nearest to each multiple
    of ``1 / fps`` from ``t[0]`` to ``t[-1]``, each once, the last sample always included."""
    grid = np.arange(t[0], t[-1] + 0.5 / fps, 1.0 / fps)
    right = np.clip(np.searchsorted(t, grid), 1, len(t) - 1) if len(t) > 1 else np.zeros(1, int)
    if len(t) > 1:
        left = right - 1
        right = np.where(np.abs(t[left] - grid) <= np.abs(t[right] - grid), left, right)
    return np.unique(np.append(right, len(t) - 1))


def placements(robot: Robot, q: np.ndarray, frame: int) -> tuple[list[pin.SE3], pin.SE3]:
    """Pinocchio's forward kinematics at joint positions ``q``: every joint's ``oMi`` and the
    placement ``oMf`` of ``frame``."""
    model = robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.configuration(np.asarray(q, dtype=float)))
    return [data.oMi[j].copy() for j in range(model.njoints)], data.oMf[frame].copy()


def scene_commands(parts: Sequence[ReplayPart], fps: float) -> tuple[list[Any], dict[str, Any]]:
    """The meshcat commands drawing ``parts`` (objects and static transforms, then one
    ``SetAnimation``), and what the page needs to know (duration, labels, camera)."""
    import meshcat.animation as ma
    import meshcat.commands as mc
    import meshcat.geometry as mg
    from meshcat.path import Path as ScenePath

    def path(text: str) -> ScenePath:
        return ScenePath(tuple(p for p in text.split("/") if p))

    commands: list[Any] = []
    animation = ma.Animation(default_framerate=fps)
    starts = [float(part.t[0]) for part in parts]
    end = max(float(part.t[-1]) for part in parts)
    points: list[np.ndarray] = []
    segments = []
    for k, part in enumerate(parts):
        base = f"{ROOT}/part{k}"
        model = part.robot.model
        ee = end_effector_frame(model, part.end_effector)
        nodes = [_node_name(model.names[j], j) for j in range(model.njoints)]
        for shape in robot_shapes(part.robot, part.colors):
            _add_shape(commands, mc, mg, path(f"{base}/{nodes[shape.joint]}/{shape.name}"), shape)
        for frame_name, shape in part.extra:
            frame = model.frames[model.getFrameId(frame_name)]
            fixed = Shape(
                shape.name, frame.parentJoint, frame.placement * shape.placement, shape.geometry,
                shape.color, shape.scale,
            )  # fmt: skip
            _add_shape(commands, mc, mg, path(f"{base}/{nodes[fixed.joint]}/{fixed.name}"), fixed)
        marker = mg.Sphere(0.012 * _reach(part.robot) + 0.005)
        commands.append(
            mc.SetObject(marker, mg.MeshPhongMaterial(color=END_EFFECTOR_COLOR), path(f"{base}/end_effector"))
        )  # fmt: skip
        desired = _desired_path(part, ee)
        points.append(desired)
        line = mg.Line(
            mg.PointsGeometry(desired.T.astype(np.float32)),
            mg.LineBasicMaterial(color=DESIRED_COLOR, linewidth=2),
        )
        commands.append(mc.SetObject(line, path=path(f"{base}/desired_path")))
        root = _Root(path(base))
        for sample in frame_indices(part.t, fps):
            joints, tool = placements(part.robot, part.q[sample], ee)
            frame = animation.at_frame(root, float(part.t[sample]) * fps)
            for j in range(1, model.njoints):
                frame[nodes[j]].set_transform(joints[j].homogeneous)
            frame["end_effector"].set_transform(tool.homogeneous)
            points.append(np.array([p.translation for p in [*joints, tool]]))
        if len(parts) > 1:  # each part is visible from its start to the next one's
            visible = [(0.0, k == 0)] + ([(starts[k] * fps, True)] if k > 0 else [])
            if k + 1 < len(parts):
                visible.append((starts[k + 1] * fps, False))
            for key, value in visible:
                animation.at_frame(root, key).set_property("visible", "boolean", value)
        segments.append({"start": starts[k], "label": part.label})
    # Every clip spans the whole replay, so that the time slider and the mixer agree.
    for clip in animation.clips.values():
        for track in clip.tracks.values():
            if track.frames[-1] < end * fps:
                track.set_property(end * fps, track.values[-1])
    commands.append(mc.SetAnimation(animation, play=True, repetitions=1))
    cloud = np.vstack(points)
    low, high = cloud.min(axis=0), cloud.max(axis=0)
    info = {
        "duration": end,
        "segments": segments,
        "center": ((low + high) / 2).tolist(),
        "radius": float(max(np.linalg.norm(high - low) / 2, 0.1)),
    }
    return commands, info


class _Root:
    """What ``Animation.at_frame`` needs of a visualizer: its scene path."""

    def __init__(self, path):
        self.path = path


def _add_shape(commands: list, mc, mg, where, shape: Shape) -> None:
    material = mg.MeshPhongMaterial(color=shape.color)
    commands.append(mc.SetObject(shape.geometry, material, where))
    commands.append(mc.SetTransform(shape.matrix(), where))


def _desired_path(part: ReplayPart, frame: int) -> np.ndarray:
    step = max(1, int(np.ceil(len(part.t) / PATH_POINTS)))
    rows = list(range(0, len(part.t), step))
    if rows[-1] != len(part.t) - 1:
        rows.append(len(part.t) - 1)
    return np.array([placements(part.robot, part.q_desired[i], frame)[1].translation for i in rows])


def _reach(robot: Robot) -> float:
    joints, _ = placements(robot, robot.angles(pin.neutral(robot.model)), 0)
    return max([float(np.linalg.norm(p.translation)) for p in joints] + [0.2])


def _node_name(name: str, index: int) -> str:
    cleaned = "".join(c if c.isalnum() or c in "_-." else "_" for c in name)
    return f"{index}_{cleaned}"
