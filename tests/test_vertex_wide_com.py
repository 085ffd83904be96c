"""``vertex`` on wide CoM boxes, where the extrema of ``w`` over the box lie inside the CoM box:
sound against Pinocchio plants rebuilt at every sample (uniform draws, random vertices and dense
CoM grids per link), and tight against a dense sampled hull (the ratio bound fails with the
per-axis curvature margin that ``vertex`` used before the exact CoM maximum: 1.05 on the UR3 and
1.25 on the SO-100 there)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from test_bounds import assert_encloses, random_state, sampled_mismatch

from urpc.bounds import make_bound
from urpc.model.robot import load_robot
from urpc.model.uncertainty import parse_uncertainty
from urpc.studies.benchmark.tightness import tightness


def wide_box(robot, com_half_width: float, links: list[str]):
    """Mass +-30 %, CoM +-``com_half_width`` [m] on each axis and inertia +-20 % on ``links``,
    and a 0-2 kg payload on the last one with its CoM in a 10 cm cube."""
    entries = {
        name: {
            "mass": "30%",
            **{f"com_{a}": f"+-{com_half_width}" for a in "xyz"},
            **{f"i{a}{a}": "20%" for a in "xyz"},
        }
        for name in links
    }
    payload = {"link": links[-1], "mass": [0, 2], **{f"com_{a}": [-0.05, 0.05] for a in "xyz"}}
    return parse_uncertainty({"links": entries, "payload": payload}, robot)


def com_grid_points(box, n: int):
    """Per uncertain link: both mass ends times an ``n^3`` CoM grid, the rest nominal."""
    points = []
    for link in box.uncertain_links:
        axes = [np.linspace(link.lower[k], link.upper[k], n) for k in (1, 2, 3)]
        for mass, *com in itertools.product([link.lower[0], link.upper[0]], *axes):
            values = link.nominal.copy()
            values[0], values[1:4] = mass, com
            points.append({link.link: values})
    return points


CASES = {
    "ur3": ["wrist_2_link", "wrist_3_link"],
    "so100": ["wrist", "gripper"],
    "panda": ["panda_link6", "panda_link7"],
}
LOCKED = {"panda": ["panda_finger_joint1", "panda_finger_joint2"]}


@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("com_half_width", [0.05, 0.3])
def test_vertex_encloses_wide_com_boxes(name, com_half_width):
    robot = load_robot(name, locked_joints=LOCKED.get(name, []))
    box = wide_box(robot, com_half_width, CASES[name])
    rng = np.random.default_rng(41)
    points = [box.sample(rng) for _ in range(60)]
    for bits in rng.integers(0, 2, size=(60, box.n_uncertain)):
        points.append(box.vertex(sum(int(b) << j for j, b in enumerate(bits))))
    points += com_grid_points(box, 7)
    states = [random_state(rng, robot.dof) for _ in range(3)]
    states += [(np.zeros(robot.dof), *random_state(rng, robot.dof)[1:])]  # q = 0
    sampled = sampled_mismatch(robot, box, points, states)
    bound = make_bound("vertex", robot, box)
    for state, w, magnitude in zip(states, sampled.w, sampled.magnitude, strict=True):
        assert_encloses(*bound.enclose(*state), w, magnitude)


@pytest.mark.parametrize("name", ["ur3", "so100"])
def test_vertex_is_tight_on_a_wide_com_box(name):
    """Two wrist links with their CoM +-5 cm and a payload whose CoM spans a 10 cm cube: the
    enclosure's width is within 2 % of a sampled inner hull of Pinocchio plants (a 9-point CoM
    grid per axis, assembled per joint) at every state and joint."""
    robot = load_robot(name)
    box = wide_box(robot, 0.05, CASES[name])
    result = tightness(robot, box, ["vertex"], n_states=8, n_uniform=50, n_vertices=50, com_grid=9)
    assert result["vertex"].worst >= 1.0 - 1e-9  # sound (the hull is an inner approximation)
    assert result["vertex"].worst <= 1.02, result["vertex"].ratios
