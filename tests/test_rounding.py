"""Rounding at high joint rates: every method against an arbitrary-precision reference.

At ``|qd|`` of 1e2-1e3 rad/s with a small ``qd_a``, the two regressor calls carry terms of size
``|qd|^2`` whose difference is of size ``|qd| |qd_a|``: the rounding error of ``Y_SL`` follows the
terms before the subtraction (``docs/bounds.md`` section 7). The reference here is exact: ``w`` is
computed by the interval Newton-Euler recursion on Arb balls (``RigorousBound.torque_balls``, no
floating-point arithmetic on the result) at parameter points, and for a box of masses only (``w``
is linear in each mass and separable over the links) its exact range is the sum over the links of
the larger (smaller) of the two mass ends, so an enclosure that misses it by 1e-13 N m is caught
(before the envelope, ``hull`` and ``vertex`` missed it by up to 2.2e-11 N m on these arms).
"""

from __future__ import annotations

import numpy as np
import pytest
from flint import arb

from urpc.bounds import make_bound
from urpc.bounds.rigorous import RigorousBound
from urpc.bounds.vertex import VertexBound
from urpc.model.regressor import SlotineLiRegressor
from urpc.model.robot import load_robot
from urpc.model.uncertainty import parse_uncertainty

METHODS = ["hull", "vertex", "vertex-plain", "rigorous"]
LOCKED = {"panda": ["panda_finger_joint1", "panda_finger_joint2"]}


def build(method, robot, box):
    if method == "vertex-plain":
        return VertexBound(robot, box, exact_com=False)
    return make_bound(method, robot, box)


def heavy_links(robot) -> list[str]:
    return [name for name in robot.moving_link_names if robot.link(name).inertia.mass > 0]


def high_rate_states(rng, dof: int, count: int):
    """``(q, qd, qd_a, qdd_a)``: every rate between 1e2 and 1e3 rad/s, ``qd_a`` and ``qdd_a`` of
    1e-6 to 1e-1 (a controller near its reference at a high speed)."""
    for k in range(count):
        small = (1e-6, 1e-3, 1e-1, 0.0)[k % 4]
        q = rng.uniform(-np.pi, np.pi, dof)
        qd = 10 ** rng.uniform(2, 3, dof) * rng.choice([-1.0, 1.0], dof)
        yield q, qd, small * rng.normal(size=dof), small * rng.normal(size=dof)


def exact_mass_range(oracle: RigorousBound, box, state) -> tuple[list[arb], list[arb]]:
    """Balls of the exact ``min_i`` and ``max_i`` of ``w`` over a box of masses only (barycentric
    ``m``: ``w`` is linear in it, and the hull methods are exact on such a box)."""
    nominal = oracle.torque_balls(*state)
    dof = len(nominal)
    lowest, highest = [arb(0)] * dof, [arb(0)] * dof
    for link_box in box.uncertain_links:
        ends = []
        for point in (link_box.lower, link_box.upper):
            torque = oracle.torque_balls(*state, {link_box.link: point})
            ends.append([t - t0 for t, t0 in zip(torque, nominal, strict=True)])
        for i in range(dof):
            a, b = ends[0][i], ends[1][i]
            a_first = a.mid() > b.mid()
            highest[i] += a if a_first else b
            lowest[i] += b if a_first else a
    return lowest, highest


@pytest.mark.parametrize("name", ["ur10", "panda", "xarm7", "z1"])
def test_every_method_encloses_the_exact_range_at_high_rates(name):
    robot = load_robot(name, locked_joints=LOCKED.get(name, ()))
    document = {"links": {n: {"barycentric": {"m": "50%"}} for n in heavy_links(robot)}}
    box = parse_uncertainty(document, robot)
    oracle = RigorousBound(robot, box)
    bounds = {method: build(method, robot, box) for method in METHODS}
    rng = np.random.default_rng(5)
    for state in high_rate_states(rng, robot.dof, 24):
        lowest, highest = exact_mass_range(oracle, box, state)
        for method, bound in bounds.items():
            lower, upper = bound.enclose(*state)
            for i in range(robot.dof):
                # Definitely outside (Arb comparisons are False when the balls overlap).
                assert not arb(float(upper[i])) < highest[i], (method, i, upper[i], highest[i])
                assert not arb(float(lower[i])) > lowest[i], (method, i, lower[i], lowest[i])


@pytest.mark.parametrize("name", ["ur5", "xarm7"])
def test_samples_of_a_physical_box_at_high_rates(name):
    """Mass, CoM and inertia uncertain, a payload; ``w`` at random vertices and draws, each in Arb
    (the reference's radius is below 1e-12 of its size)."""
    robot = load_robot(name)
    links = heavy_links(robot)
    entry = {"mass": "20%", **{f"com_{a}": "+-0.02" for a in "xyz"}, "ixx": "20%", "izz": "20%"}
    document = {
        "links": {n: entry for n in links[-3:]},
        "payload": {"link": links[-1], "mass": [0, 3], "com_z": [0, 0.1]},
    }
    box = parse_uncertainty(document, robot)
    oracle = RigorousBound(robot, box)
    rng = np.random.default_rng(6)
    points = [box.sample(rng) for _ in range(4)]
    points += [box.vertex(int(k)) for k in rng.integers(0, 2**40, 8)]
    bounds = {method: build(method, robot, box) for method in METHODS}
    for state in high_rate_states(rng, robot.dof, 4):
        nominal = oracle.torque_balls(*state)
        samples = []
        for point in points:
            torque = oracle.torque_balls(*state, point)
            samples.append([t - t0 for t, t0 in zip(torque, nominal, strict=True)])
        for method, bound in bounds.items():
            lower, upper = bound.enclose(*state)
            for w in samples:
                for i in range(robot.dof):
                    assert not w[i] < arb(float(lower[i])), (method, i, lower[i], w[i])
                    assert not w[i] > arb(float(upper[i])), (method, i, upper[i], w[i])


def test_envelope_follows_the_terms_before_the_subtraction():
    """``E`` grows with ``(|qd| + |qd_a|)^2``, not with the result ``|qd| |qd_a|``."""
    robot = load_robot("ur5")
    regressor = SlotineLiRegressor(robot)
    zero = np.zeros(robot.dof)
    slow = regressor.state_envelope(zero, np.full(robot.dof, 1.0), zero, zero)
    fast = regressor.state_envelope(zero, np.full(robot.dof, 1e3), zero, zero)
    gravity = regressor.state_envelope(zero, zero, zero, zero)
    assert fast - gravity == pytest.approx(1e6 * (slow - gravity), rel=1e-12)
