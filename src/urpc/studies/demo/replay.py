"""The demos' 3D replays: each configuration in turn, modules colored by kind, the payload a sphere.

The reconfiguration demo plays its configurations one after the other on one clock; the tool
change plays the arm before the change, then after it (the payload sphere grows). See
:mod:`urpc.sim.replay` and ``docs/replay.md``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ...model.modular import TCP_LINK
from ...sim.replay import ReplayPart, Shape
from .configuration_run import ConfigurationRun
from .synthesis import SynthesizedArm
from .tool_change import ToolChangeRun

#: Colors (0xRRGGBB) of the module kinds, and of a payload.
KIND_COLORS = {"base": 0x4D4D4D, "actuator": 0x2B5C8A, "link": 0xA8B0B8, "tool": 0xE8731A}
PAYLOAD_COLOR = 0x2CA02C


def reconfigure_parts(runs: Sequence[ConfigurationRun]) -> list[ReplayPart]:
    """One part per configuration that did not diverge, one after the other."""
    parts, clock = [], 0.0
    for run in runs:
        if run.result is None:
            continue
        result = run.result
        t = result.t - result.t[0] + clock
        parts.append(_part(run.arm, t, result.q, result.q_desired))
        clock = float(t[-1]) + float(np.median(np.diff(result.t))) if len(t) > 1 else float(t[-1])
    return parts


def tool_change_parts(run: ToolChangeRun) -> list[ReplayPart]:
    """The arm before the change, then after it (its payload from its own box)."""
    result = run.result
    before = result.t < run.t_change - 1e-12
    parts = []
    for arm, rows in ((run.before, before), (run.after, ~before)):
        if np.any(rows):
            parts.append(_part(arm, result.t[rows], result.q[rows], result.q_desired[rows]))
    return parts


def _part(arm: SynthesizedArm, t: np.ndarray, q: np.ndarray, q_desired: np.ndarray) -> ReplayPart:
    colors = {
        part.link: KIND_COLORS[part.kind] for part in arm.assembly.parts if part.kind in KIND_COLORS
    }
    return ReplayPart(
        arm.robot,
        t,
        q,
        q_desired,
        label=f"{arm.name} ({arm.dof} joints)",
        colors=colors,
        extra=_payloads(arm),
        end_effector=TCP_LINK,
    )


def _payloads(arm: SynthesizedArm) -> list[tuple[str, Shape]]:
    """A sphere per payload at its nominal center of mass, its volume proportional to the mass."""
    import meshcat.geometry as mg

    shapes = []
    for payload in arm.box.payloads:
        box = arm.box.link_box(payload.name)
        values = np.asarray(box.nominal, dtype=float)
        mass = max(float(values[0]), 1e-3)
        com = values[1:4] if box.kind == "physical" else values[1:4] / mass  # barycentric: m c
        placement = pin.SE3(np.eye(3), com)
        sphere = mg.Sphere(0.05 * mass ** (1.0 / 3.0))
        shapes.append((payload.link, Shape(payload.name, 0, placement, sphere, PAYLOAD_COLOR)))
    return shapes
