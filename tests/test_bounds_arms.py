"""Soundness on eight example-robot-data arms beyond the RR arm, the UR5 and the Panda (the
tightness table's arms and finger_edu): every link with mass uncertain (mass +-10-50 %, CoM
+-1-5 cm, inertia +-20 %) and a payload,
``w`` computed on a Pinocchio plant rebuilt at every sample (``box.plant``), at ordinary states and
at high rates (1e2-1e3 rad/s, where the rounding envelope of ``docs/bounds.md`` section 7 matters).
Zero violations, every fast method.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from test_bounds import assert_encloses, build, random_state, sampled_mismatch

from urpc.model.robot import load_robot

_SPEC = importlib.util.spec_from_file_location(
    "tightness_script", Path(__file__).resolve().parents[1] / "scripts" / "tightness.py"
)
tightness_script = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(tightness_script)
ARMS = tightness_script.ARMS  # the arms of the published tightness table
#: Arms beyond that table, so that the suite covers at least 8 arms besides RR, UR5 and Panda:
#: the TriFinger finger (3 joints, a fixed-base chain whose last link is a long fingertip).
EXTRA_ARMS = {"finger_edu": ()}
METHODS = ["hull", "vertex", "vertex-plain"]


def sample_points(box, rng, n_uniform: int, n_vertices: int):
    """Uniform draws and random vertices (random bits: these boxes have 40-72 coordinates)."""
    points = [box.sample(rng) for _ in range(n_uniform)]
    for bits in rng.integers(0, 2, size=(n_vertices, box.n_uncertain)):
        points.append(box.vertex(sum(int(b) << j for j, b in enumerate(bits))))
    return points


def high_rate_state(rng, dof):
    q = rng.uniform(-np.pi, np.pi, dof)
    qd = 10 ** rng.uniform(2, 3, dof) * rng.choice([-1.0, 1.0], dof)
    return q, qd, 1e-3 * rng.normal(size=dof), 1e-3 * rng.normal(size=dof)


SOUNDNESS_ARMS = {**{n: v for n, v in ARMS.items() if n not in ("ur5", "panda")}, **EXTRA_ARMS}


def test_the_suite_covers_eight_arms_beyond_rr_ur5_and_panda():
    assert len(SOUNDNESS_ARMS) >= 8


@pytest.mark.parametrize("name", sorted(SOUNDNESS_ARMS))
def test_every_sample_of_an_arm_box_is_enclosed(name):
    robot = load_robot(name, locked_joints=list(SOUNDNESS_ARMS[name]))
    rng = np.random.default_rng(sum(map(ord, name)))
    box = tightness_script.arm_box(robot, rng)
    points = sample_points(box, rng, 60, 60)
    states = [random_state(rng, robot.dof) for _ in range(3)]
    states += [random_state(rng, robot.dof, scale=15.0), high_rate_state(rng, robot.dof)]
    sampled = sampled_mismatch(robot, box, points, states)
    for method in METHODS:
        bound = build(method, robot, box)
        for state, w, magnitude in zip(states, sampled.w, sampled.magnitude, strict=True):
            lower, upper = bound.enclose(*state)
            assert_encloses(lower, upper, w, magnitude)
