"""Your own arm from a URDF: an uncertainty box, a controller at 1 kHz, a simulation.

Replace ``URDF`` with your robot's file and the ``links`` section with what you do not know about
it (here: the last link's mass within 10 % and its center of mass within 1 cm; the
disturbance bound is unknown). ``urpc init ROBOT --out box.yaml`` writes a starting box file.

    python examples/own_arm_from_urdf.py
"""

from __future__ import annotations

import numpy as np
from _settings import duration

import urpc
from urpc.model.catalog import resolve_robot

#: Any fixed-base serial chain's URDF file; this one ships with urpc (the paper's planar RR arm),
#: found where pip installed it (editable or not).
URDF = resolve_robot("rr_planar").urdf

robot = urpc.load_robot(str(URDF))
box = urpc.parse_uncertainty(
    {
        "links": {
            "link2": {
                "mass": "10%",  # +- 10 % of the URDF's value
                "com_x": "+-0.01",  # [m], center of mass in the link frame
            }
        },
        "disturbance": "unknown",  # Theorem 2: the gains adapt to any bounded disturbance
    },
    robot,
)
controller = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3)  # owns its 1 kHz
trajectory = urpc.generic_trajectory(robot)  # inside the joint limits
plant = box.plant(robot, box.sample(np.random.default_rng(1)))  # a "true" arm inside the box
result = urpc.simulate(plant, controller, trajectory, duration=duration(4.0), disturbance_bound=5.0)

metrics = result.metrics
print(f"{robot.name}: {robot.dof} joints, {controller!r}")
print(f"met ||e|| < {result.epsilon:g} rad: {metrics['met']}, entry {metrics['entry_time']} s")
print(f"final error {metrics['final_error']:.3g} rad, torque peak {metrics['torque_peak']:.3g} N m")
print(f"final gains: phi = {metrics['phi']:.4g}, kappa = {metrics['kappa']:.4g}")
