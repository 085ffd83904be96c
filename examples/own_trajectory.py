"""Your own reference: subclass ``urpc.Trajectory`` (give ``dof`` and ``evaluate``), or build a
``urpc.SinusoidTrajectory`` from a home pose, amplitudes and frequencies.

    python examples/own_trajectory.py
"""

from __future__ import annotations

import numpy as np
from _settings import duration

import urpc


class Circle(urpc.Trajectory):
    """Joints 1 and 2 trace a circle of ``radius`` [rad] around ``center`` at ``frequency`` [Hz],
    starting at rest: ``q(t) = center + radius s(t) (cos w t, sin w t)`` with the smooth ramp
    ``s(t) = 1 - exp(-t^2)`` (so ``q, qd`` are continuous at ``t = 0``)."""

    dof = 2
    kind = "circle"

    def __init__(self, center=(0.0, 0.5), radius=0.2, frequency=0.25):
        self.center, self.radius, self.omega = np.asarray(center), radius, 2 * np.pi * frequency

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)[..., None]
        w = self.omega
        s, sd, sdd = 1 - np.exp(-(t**2)), 2 * t * np.exp(-(t**2)), (2 - 4 * t**2) * np.exp(-(t**2))
        c = np.concatenate((np.cos(w * t), np.sin(w * t)), axis=-1)
        cd = w * np.concatenate((-np.sin(w * t), np.cos(w * t)), axis=-1)
        cdd = -(w**2) * c
        q = self.center + self.radius * s * c
        qd = self.radius * (sd * c + s * cd)
        qdd = self.radius * (sdd * c + 2 * sd * cd + s * cdd)
        return q, qd, qdd


robot = urpc.load_robot("rr_planar")
box = urpc.load_uncertainty("rr_planar", robot)
plant = box.plant(robot, urpc.load_parameter_point("rr_planar", robot, box))
controller = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3)

for trajectory in (
    Circle(),
    urpc.SinusoidTrajectory(home=[0.0, 0.5], amplitude=[0.3, 0.2], frequency=[0.2, 0.4]),
):
    result = urpc.simulate(plant, controller, trajectory, duration=duration(4.0))
    m = result.metrics
    print(f"{type(trajectory).__name__}: met {m['met']}, final error {m['final_error']:.3g} rad")
