"""The certificate's cost next to the control steps it certifies (``urpc bench certificate``,
``scripts/bench_certificate.py``; docs/performance.md, "What the certificate costs").

For each arm: the CPU time of :func:`urpc.certify` (implicit law, 1 kHz, ``epsilon = 1e-2``, a
2 s generic reference, the arm's box, ``d = 2``) and of 1000 control steps of the same controller,
measured in the same process, their ratio, the cells of the floor's enclosure and the outcome.
An arm is a shipped robot with its shipped box (``ur5``, ``panda`` with its fingers locked, ...)
or ``chainN``: a planar-and-twist serial arm of ``N`` revolute joints (alternating y and z axes,
0.1 m links, 1 kg each, every mass +-10 %), built as a URDF.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

#: The arms of the issue's figures: a 6-dof arm, a 7-dof arm and a 30-link chain.
CERTIFICATE_ARMS = ("ur5", "panda", "chain30")
PANDA_FINGERS = ("panda_finger_joint1", "panda_finger_joint2")


def chain_urdf(links: int) -> str:
    """The URDF of the ``links``-joint chain of the module docstring."""
    parts = ['<robot name="chain"><link name="base"/>']
    parent = "base"
    for k in range(links):
        axis = "0 1 0" if k % 2 == 0 else "0 0 1"
        parts.append(
            f'<joint name="j{k}" type="revolute"><parent link="{parent}"/><child link="l{k}"/>'
            f'<origin xyz="0 0 {0.1 if k else 0.0}"/><axis xyz="{axis}"/>'
            f'<limit lower="-2.5" upper="2.5" effort="200" velocity="3"/></joint>'
            f'<link name="l{k}"><inertial><origin xyz="0 0 0.05"/><mass value="1.0"/>'
            f'<inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.0005"/>'
            f"</inertial></link>"
        )
        parent = f"l{k}"
    parts.append("</robot>")
    return "".join(parts)


def benchmark_arm(name: str, folder: Path):
    """``(robot, box)`` of an arm of the module docstring (a chain's URDF written in
    ``folder``)."""
    import urpc

    if name.startswith("chain") and name[5:].isdigit():
        links = int(name[5:])
        path = folder / f"{name}.urdf"
        path.write_text(chain_urdf(links))
        robot = urpc.load_robot(path)
        box = urpc.parse_uncertainty(
            {"links": {f"l{k}": {"mass": "10%"} for k in range(links)}}, robot
        )
        return robot, box
    locked = PANDA_FINGERS if name == "panda" else ()
    robot = urpc.load_robot(name, locked_joints=locked)
    return robot, urpc.load_uncertainty(name, robot)


def certificate_cost(name: str, folder: Path) -> dict[str, Any]:
    """The figures of one arm (module docstring)."""
    import urpc

    robot, box = benchmark_arm(name, folder)
    controller = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3)
    trajectory = urpc.generic_trajectory(box.nominal_robot(robot))
    start = time.process_time()
    certificate = urpc.certify(controller, trajectory, duration=2.0, disturbance_bound=2.0)
    certify_time = time.process_time() - start
    state = controller.initial_state()
    q = trajectory.reference(0.0).q
    qd = np.zeros(robot.dof)
    start = time.process_time()
    for k in range(1000):
        reference = trajectory.reference(k * 1e-3)
        controller.output(k * 1e-3, q, qd, reference, state)
    step_time = time.process_time() - start
    return {
        "arm": name,
        "dof": robot.dof,
        "cells": int(certificate.figures.get("cells", 0)),
        "certify_s": certify_time,
        "steps_s": step_time,
        "ratio": certify_time / step_time,
        "certified": certificate.certified,
        "floor": certificate.epsilon_floor,
        "max_period_ms": certificate.max_sample_period * 1e3,
    }


def certificate_costs(
    arms=CERTIFICATE_ARMS, progress: Callable[[str], Any] | None = None
) -> list[dict[str, Any]]:
    """:func:`certificate_cost` of each arm, in order."""
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for name in arms:
            if progress is not None:
                progress(f"certificate of {name}")
            rows.append(certificate_cost(name, Path(folder)))
    return rows


def format_certificate_costs(rows: list[dict[str, Any]]) -> str:
    """A Markdown table of :func:`certificate_costs`' rows."""
    lines = [
        "| arm | dof | cells | certify [s CPU] | 1000 steps [s CPU] | ratio | certified at 1 kHz "
        "| floor [rad] | max period [ms] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['arm']} | {r['dof']} | {r['cells']} | {r['certify_s']:.1f} | "
            f"{r['steps_s']:.3f} | {r['ratio']:.0f} | {'yes' if r['certified'] else 'no'} | "
            f"{r['floor']:.3g} | {r['max_period_ms']:.3g} |"
        )
    return "\n".join(lines)
