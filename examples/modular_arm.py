"""A modular arm: compose shipped modules (base first) into one URDF and one uncertainty box,
synthesize its controller and simulate it. Swap a module, assemble again, synthesize again.

    python examples/modular_arm.py
"""

from __future__ import annotations

import tempfile

import numpy as np
from _settings import duration

import urpc

MODULES = ["base", "actuator_large", "elbow_large", "link_500", "elbow_small", "link_300"]

with tempfile.TemporaryDirectory() as folder:
    for tool in ("tool_gripper", "tool_vacuum"):
        assembly = urpc.assemble([*MODULES, tool], name=f"arm_{tool}", out_dir=folder)
        robot, box = assembly.load()
        controller = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3)
        trajectory = urpc.generic_trajectory(robot)
        plant = box.plant(robot, box.sample(np.random.default_rng(0)))
        result = urpc.simulate(plant, controller, trajectory, duration=duration(3.0))
        m = result.metrics
        print(
            f"{assembly.name}: {robot.dof} joints, met {m['met']}, "
            f"final error {m['final_error']:.3g} rad, torque peak {m['torque_peak']:.3g} N m"
        )
