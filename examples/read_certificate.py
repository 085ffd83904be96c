"""Is ``epsilon`` guaranteed at this sample period, and down to which epsilon? Read the
certificate of a synthesized controller: its verdict, the floor, the largest period, and every
condition of the argument with its value and limit.

    python examples/read_certificate.py
"""

from __future__ import annotations

from _settings import duration

import urpc

robot = urpc.load_robot("rr_planar")
box = urpc.load_uncertainty("rr_planar", robot)
controller = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3)  # implicit law
certificate = urpc.certify(
    controller, urpc.PaperTrajectory(), duration=duration(10.0), disturbance_bound=10.0
)

print(certificate.summary())
print(f"certified:          {certificate.certified}")
print(
    f"epsilon floor:      {certificate.epsilon_floor:.3g} rad at T = {controller.sample_period} s"
)
print(f"max sample period:  {certificate.max_sample_period:.3g} s for epsilon = 1e-2 rad")
for condition in certificate.conditions:
    mark = "holds " if condition.holds else "FAILS "
    print(f"  {mark} {condition.name}: {condition.value:.4g} vs {condition.limit:.4g}")
