"""The certificate's cost next to the control steps it certifies (issue 19's figures).

    python scripts/bench_certificate.py            # UR5, Panda, a 30-link chain
    python scripts/bench_certificate.py --quick    # UR5 and a 10-link chain only
    python scripts/bench_certificate.py --arms chain4,chain8,chain12   # the growth with n

For each arm: the CPU time of ``urpc.certify`` (implicit law, 1 kHz, ``epsilon = 1e-2``, a 2 s
generic reference, the arm's box) and of 1000 control steps of the same controller, measured side
by side in one process, and their ratio; the number of cells, and the outcome. The chain is a
planar-and-twist serial arm of revolute joints (alternating y and z axes, 0.1 m links, 1 kg each,
every mass +-10 %), built here as a URDF.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

import urpc


def chain_urdf(links: int) -> str:
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


def arm(name: str, folder: Path):
    if name.startswith("chain"):
        links = int(name[5:])
        path = folder / f"{name}.urdf"
        path.write_text(chain_urdf(links))
        robot = urpc.load_robot(path)
        box = urpc.parse_uncertainty(
            {"links": {f"l{k}": {"mass": "10%"} for k in range(links)}}, robot
        )
        return robot, box
    locked = ["panda_finger_joint1", "panda_finger_joint2"] if name == "panda" else ()
    robot = urpc.load_robot(name, locked_joints=locked)
    return robot, urpc.load_uncertainty(name, robot)


def measure(name: str, folder: Path) -> dict:
    robot, box = arm(name, folder)
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
        "outcome": certificate.summary().split(":")[0],
        "floor": certificate.epsilon_floor,
        "max_period_ms": certificate.max_sample_period * 1e3,
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="UR5 and a 10-link chain")
    parser.add_argument(
        "--arms", help="comma-separated arms instead (ur5, panda, chainN for an N-link chain)"
    )
    args = parser.parse_args(argv)
    arms = ["ur5", "chain10"] if args.quick else ["ur5", "panda", "chain30"]
    if args.arms:
        arms = [name.strip() for name in args.arms.split(",") if name.strip()]
    print("| arm | dof | cells | certify [s CPU] | 1000 steps [s CPU] | ratio | outcome | "
          "floor [rad] | max period [ms] |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for name in arms:
            r = measure(name, Path(folder))
            print(
                f"| {r['arm']} | {r['dof']} | {r['cells']} | {r['certify_s']:.1f} | "
                f"{r['steps_s']:.3f} | {r['ratio']:.0f} | {r['outcome']} | {r['floor']:.3g} | "
                f"{r['max_period_ms']:.3g} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
