"""A side view of an assembled modular arm, from Pinocchio's forward kinematics."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin
from matplotlib.axes import Axes

from ...model.modular import TCP_LINK
from ...model.robot import Robot
from ...trajectories import home_configuration
from .synthesis import SynthesizedArm

_KIND_COLORS = {"link": "0.45", "tool": "tab:orange", "actuator": "0.2", "base": "0.3"}


def draw_arm(
    axes: Axes, arm: SynthesizedArm, q: np.ndarray | None = None, *, show_home: bool = True
) -> None:
    """A side view of an assembly at ``q`` [rad] (default: home, the middle of the joint limits),
    with the home pose as a light outline when ``show_home`` and ``q`` differs from it.

    Flange and module-frame positions come from Pinocchio's forward kinematics. The view looks
    along the first horizontal joint axis at ``q`` (the shoulder pitch of an anthropomorphic
    arm). Links and tools are lines from input to output flange, joints circles (large ones for
    large actuators), the TCP a cross and the payload a square at its nominal center of mass.
    """
    robot = arm.robot
    home = home_configuration(robot)
    q = home if q is None else np.asarray(q, dtype=float)
    horizontal, vertical = _side_view(robot, robot.configuration(q))

    def project(point: np.ndarray) -> tuple[float, float]:
        return float(point @ horizontal), float(point @ vertical)

    if show_home and not np.allclose(q, home):
        segments, joints, _ = _skeleton(arm, home, project)
        for _, _, points in segments:
            axes.plot(*zip(*points, strict=True), color="0.85", lw=3.0, solid_capstyle="butt")
        for _, (x, y) in joints:
            axes.plot(x, y, "o", ms=6, mfc="white", mec="0.75", mew=1.0)
    segments, joints, tcp = _skeleton(arm, q, project)
    for kind, _, points in segments:
        width = {"base": 9.0, "actuator": 6.0, "tool": 4.0}.get(kind, 3.0)
        axes.plot(
            *zip(*points, strict=True),
            color=_KIND_COLORS.get(kind, "0.45"),
            lw=width,
            solid_capstyle="butt",
        )
    for module, (x, y) in joints:
        size = 11 if arm.assembly.library[module].joint.effort >= 100 else 8
        axes.plot(x, y, "o", ms=size, mfc="white", mec="k", mew=1.5, zorder=3)
    x, y = project(tcp.translation)
    axes.plot(x, y, "x", ms=7, color="tab:orange", mew=2, zorder=4)
    for payload in arm.box.payloads:
        values = arm.box.link_box(payload.name).nominal
        px, py = project(tcp.act(np.asarray(values[1:4], dtype=float)))
        axes.plot(px, py, "s", ms=6 + 3 * float(values[0]), color="tab:green", zorder=4)
        axes.annotate(
            f"{values[0]:g} kg", (px, py), xytext=(9, 4), textcoords="offset points", fontsize=8
        )
    tool = next((p.module for p in arm.assembly.parts if p.kind == "tool"), None)
    if tool is not None:
        axes.annotate(tool, (x, y), xytext=(9, -12), textcoords="offset points", fontsize=8)
    axes.axhline(0.0, color="0.6", lw=1.0)
    axes.set_aspect("equal", adjustable="datalim")
    axes.margins(0.2)
    axes.set_xlabel("[m]")
    axes.tick_params(labelsize=8)


def _skeleton(
    arm: SynthesizedArm, q: np.ndarray, project: Callable[[np.ndarray], tuple[float, float]]
) -> tuple[list, list, pin.SE3]:
    """Projected ``(kind, module, flange points)`` per module, ``(module, point)`` per joint, and
    the TCP placement, at ``q``."""
    model = arm.robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, arm.robot.configuration(q))
    segments, joints = [], []
    for part in arm.assembly.parts:
        if part.kind == "payload":
            continue
        module = arm.assembly.library[part.module]
        frame = data.oMf[model.getFrameId(part.link)]
        points = [
            (frame * connector.placement).translation
            for connector in (module.proximal, module.distal)
            if connector is not None
        ]
        if part.kind == "base":
            points.insert(0, frame.translation)
        segments.append((part.kind, part.module, [project(p) for p in points]))
        if part.kind == "actuator":
            joints.append((part.module, project(frame.translation)))
    return segments, joints, data.oMf[model.getFrameId(TCP_LINK)].copy()


def _side_view(robot: Robot, configuration: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (horizontal, vertical) of the drawing plane: the plane normal to the first
    horizontal joint axis (world frame), or the world x-z plane."""
    model = robot.model
    data = model.createData()
    vertical = np.array([0.0, 0.0, 1.0])
    pin.computeJointJacobians(model, data, configuration)
    for joint in range(1, model.njoints):
        column = model.joints[joint].idx_v
        jacobian = pin.getJointJacobian(model, data, joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        axis = jacobian[3:, column]
        if np.linalg.norm(axis) > 0.5 and abs(axis @ vertical) < 0.5:
            horizontal = np.cross(axis, vertical)
            return horizontal / np.linalg.norm(horizontal), vertical
    return np.array([1.0, 0.0, 0.0]), vertical
