"""The ``rigorous`` bound: an interval Newton-Euler enclosure on Arb balls.

References, all independent of the code under test: Pinocchio's ``crba``,
``computeCoriolisMatrix`` and ``computeGeneralizedGravity`` on plants built at sampled and vertex
parameter points, the textbook RR model of ``conftest.rr_closed_form``, and the exact hull
``Y (pi - pi0)`` over a barycentric box from Pinocchio's joint-torque regressor.

Overestimation figures (width of the enclosure over the width of a dense sampled inner hull) are
printed by the tests (``pytest tests/test_rigorous.py -s``); ``python tests/test_rigorous.py``
runs the denser measurement reported in the docs.
"""

from __future__ import annotations

import sys
import time

import numpy as np
import pytest
from conftest import PANDA_FINGERS, RR_DIR, rr_closed_form
from flint import arb, ctx
from hypothesis import given
from hypothesis import strategies as st

from urpc.bounds import METHODS, RegressorBound, make_bound
from urpc.bounds.hull import HullBound
from urpc.bounds.rigorous import RigorousBound, interval_ball, lower_float, upper_float
from urpc.errors import InputError
from urpc.model.regressor import SlotineLiRegressor, link_regressor_map
from urpc.model.robot import load_robot
from urpc.model.uncertainty import ParameterBox, load_uncertainty, parse_uncertainty

#: Absolute slack [N m] granted to the *floating-point references* (Pinocchio, numpy), whose own
#: rounding is ~1e-13 here; the enclosure itself is never inflated.
REFERENCE_SLACK = 1e-9

# A tree with every supported joint type: unaligned revolute, unaligned prismatic, aligned
# continuous, unaligned continuous on a branch, rotated joint frames and inertial frames, and a
# massive link on a fixed joint (merged by Pinocchio into its parent body with a rotated placement).
TREE_URDF = """<?xml version="1.0"?>
<robot name="tree">
  <link name="base"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1" rpy="0.1 0.2 0.3"/><axis xyz="0.6 0.8 0"/>
    <limit lower="-3" upper="3" effort="100" velocity="5"/>
  </joint>
  <link name="l1">
    <inertial><origin xyz="0.1 0.02 -0.03" rpy="0.2 -0.1 0.4"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0.001" ixz="-0.002" iyy="0.03" iyz="0.003" izz="0.025"/></inertial>
  </link>
  <joint name="j2" type="prismatic">
    <parent link="l1"/><child link="l2"/>
    <origin xyz="0.2 0 0" rpy="0 0.5 0"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-0.5" upper="0.5" effort="100" velocity="1"/>
  </joint>
  <link name="l2">
    <inertial><origin xyz="0.05 0.1 0.02" rpy="0 0 0"/><mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.012" iyz="0" izz="0.008"/></inertial>
  </link>
  <joint name="j3" type="continuous">
    <parent link="l2"/><child link="l3"/>
    <origin xyz="0 0.1 0.3" rpy="0.3 0 0"/><axis xyz="0 0 1"/>
  </joint>
  <link name="l3">
    <inertial><origin xyz="0 0.05 0.1" rpy="0 0 0"/><mass value="1.0"/>
      <inertia ixx="0.005" ixy="0" ixz="0" iyy="0.006" iyz="0" izz="0.004"/></inertial>
  </link>
  <joint name="tool_joint" type="fixed">
    <parent link="l3"/><child link="tool"/>
    <origin xyz="0.1 0.05 0.02" rpy="0.4 0.5 0.6"/>
  </joint>
  <link name="tool">
    <inertial><origin xyz="0.01 0.02 0.03" rpy="0 0 0"/><mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.0015"/></inertial>
  </link>
  <joint name="j4" type="continuous">
    <parent link="l1"/><child link="l4"/>
    <origin xyz="0 -0.2 0.1" rpy="0 0 0.7"/><axis xyz="0.48 0.6 0.64"/>
  </joint>
  <link name="l4">
    <inertial><origin xyz="0.02 0 0.1" rpy="0 0 0"/><mass value="0.8"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.002"/></inertial>
  </link>
</robot>
"""


# ============================================================================ helpers
def random_state(rng: np.random.Generator, dof: int, scale: float = 2.0) -> tuple[np.ndarray, ...]:
    """``q, qd, qd_a, qdd_a`` with independent velocities (so ``C(q, qd) qd_a`` is tested, not
    just ``c(q, qd)``)."""
    return tuple(scale * rng.normal(size=dof) for _ in range(4))


def slotine_li_torque(robot, q, qd, qd_a, qdd_a) -> np.ndarray:
    """``M qdd_a + C qd_a + g`` from Pinocchio's crba, computeCoriolisMatrix, generalized gravity."""
    return robot.M(q) @ qdd_a + robot.C(q, qd) @ qd_a + robot.g(q)


def sampled_mismatch(plants, nominal, state) -> np.ndarray:
    """``w`` at each plant [N m], shape ``(len(plants), dof)``."""
    reference = slotine_li_torque(nominal, *state)
    return np.array([slotine_li_torque(plant, *state) - reference for plant in plants])


def box_points(box: ParameterBox, rng: np.random.Generator, n_random: int, n_vertices: int):
    """Random points and vertices of the box (all vertices when there are few)."""
    n_total = 2**box.n_uncertain
    if n_total <= n_vertices:
        vertices = [box.vertex(k) for k in range(n_total)]
    else:
        bits = rng.integers(0, 2, size=(n_vertices, box.n_uncertain))
        vertices = [box.vertex(sum(int(b) << k for k, b in enumerate(row))) for row in bits]
    return vertices + [box.sample(rng) for _ in range(n_random)]


def assert_inside(lower, upper, values, scale):
    slack = REFERENCE_SLACK * max(1.0, scale)
    below = values < lower - slack
    above = values > upper + slack
    assert not below.any() and not above.any(), (
        f"sampled w outside the enclosure: lower {lower}, upper {upper}, "
        f"sampled min {values.min(axis=0)}, max {values.max(axis=0)}"
    )


def width_ratios(lower, upper, samples) -> np.ndarray:
    """``width(enclosure) / width(sampled hull)`` per joint (joints the box cannot move: nan)."""
    sampled = samples.max(axis=0) - samples.min(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(sampled > 1e-9, (upper - lower) / sampled, np.nan)


def measure(robot, box, rng, n_states, n_random, n_vertices, label) -> np.ndarray:
    """Soundness against sampled plants, and the overestimation ratios of ``rigorous`` (returned)
    and, for comparison, of the fast ``hull`` method (printed), over random states."""
    bound = RigorousBound(robot, box)
    hull = HullBound(robot, box)
    nominal = box.nominal_robot(robot)
    plants = [box.plant(robot, point) for point in box_points(box, rng, n_random, n_vertices)]
    ratios, hull_ratios = [], []
    for _ in range(n_states):
        state = random_state(rng, robot.dof)
        lower, upper = bound.enclose(*state)
        samples = sampled_mismatch(plants, nominal, state)
        assert_inside(lower, upper, samples, np.abs(slotine_li_torque(nominal, *state)).max())
        ratios.append(width_ratios(lower, upper, samples))
        hull_ratios.append(width_ratios(*hull.enclose(*state), samples))
    ratios, hull_ratios = np.array(ratios), np.array(hull_ratios)
    finite = np.isfinite(ratios)
    print(
        f"\n{label}: width / width(sampled hull), {n_states} states x {robot.dof} joints, "
        f"{len(plants)} plants:\n"
        f"  rigorous: median {np.median(ratios[finite]):.3f}, worst {ratios[finite].max():.3f}, "
        f"best {ratios[finite].min():.4f}\n"
        f"  hull:     median {np.median(hull_ratios[finite]):.3f}, "
        f"worst {hull_ratios[finite].max():.3f}\n"
        f"  rigorous / hull: median {np.median((ratios / hull_ratios)[finite]):.3f}, "
        f"worst {(ratios / hull_ratios)[finite].max():.3f}"
    )
    return ratios[finite]


def uniform_physical_box(robot, mass="10%", com="+-0.01", inertia="20%") -> dict:
    """Every moving link with mass: relative mass, absolute CoM offsets, relative diagonal inertia."""
    links = {}
    for link in robot.links:
        if link.joint_index > 0 and link.inertia.mass > 0:
            links[link.name] = {
                "mass": mass,
                **{f"com_{axis}": com for axis in "xyz"},
                **{f"i{axis}{axis}": inertia for axis in "xyz"},
            }
    return {"links": links}


@pytest.fixture(scope="module")
def tree(tmp_path_factory):
    path = tmp_path_factory.mktemp("tree") / "tree.urdf"
    path.write_text(TREE_URDF)
    return load_robot(path)


# ============================================================================ point version
@pytest.mark.parametrize("name", ["rr", "ur5", "panda", "tree"])
def test_point_version_contains_pinocchio(name, request):
    robot = request.getfixturevalue(name)
    bound = RigorousBound(robot, ParameterBox(links=()))
    rng = np.random.default_rng(10)
    for _ in range(8):
        state = random_state(rng, robot.dof)
        reference = slotine_li_torque(robot, *state)
        balls = bound.torque_balls(*state)
        lower = np.array([lower_float(b) for b in balls])
        upper = np.array([upper_float(b) for b in balls])
        assert np.all(upper - lower < 1e-11)  # a point evaluation stays a point
        assert_inside(lower, upper, reference[None, :], np.abs(reference).max())


def test_point_version_at_a_parameter_point_matches_the_textbook_rr_arm(rr, rr_box):
    bound = RigorousBound(rr, rr_box)
    rng = np.random.default_rng(11)
    for _ in range(10):
        q, qd, qd_a, qdd_a = random_state(rng, 2)
        m2, lc2, I2 = rng.uniform(5, 10), rng.uniform(0.5, 0.525), rng.uniform(5 / 12, 20 / 12)
        values = rr_box.link_box("link2").nominal.copy()
        values[[0, 1, 6]] = m2, lc2, I2  # mass, com_x, iyy
        M, C, g = rr_closed_form(q, qd, m2, lc2, I2)
        reference = M @ qdd_a + C @ qd_a + g
        balls = bound.torque_balls(q, qd, qd_a, qdd_a, point={"link2": values})
        lower = np.array([lower_float(b) for b in balls])
        upper = np.array([upper_float(b) for b in balls])
        assert_inside(lower, upper, reference[None, :], np.abs(reference).max())


def test_tree_point_at_sampled_parameters_matches_pinocchio_plant(tree):
    box = parse_uncertainty(
        {
            "links": {
                "tool": {"mass": "50%", "com_y": "+-0.05"},
                "l4": {"barycentric": {"h_z": "30%"}},
            }
        },
        tree,
    )
    bound = RigorousBound(tree, box)
    rng = np.random.default_rng(12)
    for _ in range(5):
        point = box.sample(rng)
        state = random_state(rng, tree.dof)
        reference = slotine_li_torque(box.plant(tree, point), *state)
        balls = bound.torque_balls(*state, point=point)
        lower = np.array([lower_float(b) for b in balls])
        upper = np.array([upper_float(b) for b in balls])
        assert_inside(lower, upper, reference[None, :], np.abs(reference).max())


# ============================================================================ soundness
def test_rr_table_one_box_is_enclosed(rr, rr_box, rr_true_point):
    rng = np.random.default_rng(20)
    ratios = measure(rr, rr_box, rng, n_states=15, n_random=40, n_vertices=8, label="rr_planar")
    assert ratios.min() >= 1 - 1e-9
    # The paper's true plant (a vertex), against the textbook model, not Pinocchio.
    bound = RigorousBound(rr, rr_box)
    true = rr_true_point.links["link2"]
    for _ in range(10):
        q, qd, qd_a, qdd_a = random_state(rng, 2)
        M, C, g = rr_closed_form(q, qd, true[0], true[1], true[6])
        M0, C0, g0 = rr_closed_form(q, qd, 5.0, 0.5, 5 / 12)
        w = (M - M0) @ qdd_a + (C - C0) @ qd_a + (g - g0)
        lower, upper = bound.enclose(q, qd, qd_a, qdd_a)
        assert_inside(lower, upper, w[None, :], np.abs(M @ qdd_a + g).max())


def test_ur5_small_box_with_payload_is_enclosed(ur5):
    document = {
        "links": {
            "forearm_link": {"mass": "10%", "com_x": "+-0.01", "com_z": "+-0.02", "iyy": "20%"},
            "wrist_1_link": {"barycentric": {"m": "20%", "h_y": "+-0.01", "I_zz": "30%"}},
        },
        # tool0 sits on joint 6 with a rotated placement: exercises moving a physical box.
        "payload": {"link": "tool0", "mass": [0, 2], "com_x": [0, 0.05], "com_z": [0, 0.1]},
    }
    box = parse_uncertainty(document, ur5)
    ratios = measure(ur5, box, np.random.default_rng(21), 8, 30, 30, label="ur5 small box")
    assert ratios.min() >= 1 - 1e-9


def test_tree_with_every_joint_type_is_enclosed(tree):
    document = {
        "links": {
            "l2": {"mass": "20%", "com_x": "+-0.02", "ixx": "30%", "ixy": "+-0.001"},
            "tool": {"mass": "50%", "com_y": "+-0.05", "izz": "40%"},
            "l4": {"barycentric": {"m": "10%", "h_z": "30%", "I_xy": "+-0.001"}},
        }
    }
    box = parse_uncertainty(document, tree)
    ratios = measure(
        tree, box, np.random.default_rng(22), 8, 30, 30, label="tree (all joint types)"
    )
    assert ratios.min() >= 1 - 1e-9


def test_contains_the_exact_hull_on_a_barycentric_box(panda):
    # Over a barycentric box w = Y (pi - pi0) is linear, so [Y (pi_c - pi0) -+ |Y| pi_r] is exact.
    names = ["panda_link3", "panda_link5", "panda_link7", "panda_hand"]
    fields = {"m": "20%", "h_x": "+-0.02", "h_z": "+-0.02", "I_xx": "30%", "I_zz": "30%"}
    box = parse_uncertainty({"links": {n: {"barycentric": fields} for n in names}}, panda)
    bound = RigorousBound(panda, box)
    regressor = SlotineLiRegressor(panda)
    link_map = link_regressor_map(panda, names)
    lower_pi = np.concatenate([box.link_box(n).lower for n in names])
    upper_pi = np.concatenate([box.link_box(n).upper for n in names])
    nominal_pi = np.concatenate([panda.link(n).parameters for n in names])
    rng = np.random.default_rng(23)
    ratios = []
    for _ in range(10):
        state = random_state(rng, panda.dof)
        Y = regressor(*state) @ link_map
        center = Y @ ((lower_pi + upper_pi) / 2 - nominal_pi)
        radius = np.abs(Y) @ ((upper_pi - lower_pi) / 2)
        slack = REFERENCE_SLACK * max(1.0, (np.abs(Y) @ np.abs(upper_pi)).max())
        lower, upper = bound.enclose(*state)
        assert np.all(lower <= center - radius + slack)
        assert np.all(upper >= center + radius - slack)
        ratios.append((upper - lower) / (2 * radius))
    ratios = np.array(ratios)
    print(
        f"\npanda barycentric: width(rigorous) / width(exact hull): median {np.median(ratios):.3f}, "
        f"worst {ratios.max():.3f}"
    )
    assert ratios.min() >= 1 - 1e-9


# ============================================================================ rounding and API
@given(
    st.floats(-1e12, 1e12, allow_nan=False, allow_subnormal=True),
    st.floats(0, 1e6, allow_nan=False, allow_subnormal=True),
)
def test_interval_ball_holds_both_ends_and_floats_round_outward(lower, width):
    upper = lower + width
    ball = interval_ball(lower, upper)
    assert ball.contains(arb(lower)) and ball.contains(arb(upper))
    lo, hi = lower_float(ball), upper_float(ball)
    # Exact comparisons of exact balls: the doubles enclose the ball...
    assert arb(lo) <= ball.lower() and arb(hi) >= ball.upper()
    # ...and are the tightest doubles that do.
    assert not arb(float(np.nextafter(lo, np.inf))) <= ball.lower()
    assert not arb(float(np.nextafter(hi, -np.inf))) >= ball.upper()
    assert lo <= lower and hi >= upper


@pytest.mark.parametrize("precision", [53, 200])
def test_rounding_of_an_inexact_ball_is_outward(precision):
    # At 200 bits the ball's ends are not doubles, so the conversion itself must round outward.
    with ctx.workprec(precision):
        third = arb(1) / 3  # a ball of positive radius (1/3 is not a dyadic number)
        for ball in (third, -third, third * 1e300, -third * 1e-300):
            lo, hi = lower_float(ball), upper_float(ball)
            assert arb(lo) <= ball.lower() and arb(hi) >= ball.upper()
            assert lo < hi
    assert lower_float(arb("nan")) == -np.inf and upper_float(arb("nan")) == np.inf


def test_enclose_is_outward_rounding_of_the_balls(rr, rr_box):
    bound = RigorousBound(rr, rr_box)
    state = random_state(np.random.default_rng(30), 2)
    balls = bound.enclose_balls(*state)
    lower, upper = bound.enclose(*state)
    for ball, lo, hi in zip(balls, lower, upper, strict=True):
        assert arb(lo) <= ball.lower() and arb(hi) >= ball.upper()
    assert lower.dtype == float and upper.dtype == float


def test_known_disturbance_bound_widens_by_the_bound(rr):
    box = load_uncertainty(RR_DIR / "uncertainty.yaml", rr)
    disturbed = ParameterBox(links=box.links, disturbance_bound=10.0)
    state = random_state(np.random.default_rng(31), 2)
    lower, upper = RigorousBound(rr, box).enclose(*state)
    lower_d, upper_d = RigorousBound(rr, disturbed).enclose(*state)
    assert np.all(lower_d <= lower - 10.0) and np.all(upper_d >= upper + 10.0)
    np.testing.assert_allclose(lower_d, lower - 10.0, rtol=1e-14)
    np.testing.assert_allclose(upper_d, upper + 10.0, rtol=1e-14)


def test_is_a_registered_method_without_regressor(rr, rr_box):
    assert METHODS["rigorous"] is RigorousBound
    bound = make_bound("rigorous", rr, rr_box)
    assert isinstance(bound, RigorousBound) and not bound.uses_regressor
    # It is no regressor bound, and inherits no regressor method it would have to refuse.
    assert not isinstance(bound, RegressorBound) and not hasattr(bound, "enclose_regressor")
    state = random_state(np.random.default_rng(32), 2)
    lower, upper = bound.enclose(*state)
    np.testing.assert_array_equal(bound.rho(*state), np.maximum(np.abs(lower), np.abs(upper)))


def test_bad_input_is_reported(rr, rr_box):
    bound = RigorousBound(rr, rr_box)
    with pytest.raises(InputError, match=r"qd_a has shape \(3,\)"):
        bound.enclose(np.zeros(2), np.zeros(2), np.zeros(3), np.zeros(2))
    with pytest.raises(InputError, match="link3"):
        bound.torque_balls(
            *random_state(np.random.default_rng(33), 2), point={"link3": np.ones(10)}
        )


def test_exact_box_gives_a_zero_width_enclosure_at_zero(ur5):
    # No uncertain link: w = 0 exactly, at any state.
    bound = RigorousBound(ur5, ParameterBox(links=()))
    lower, upper = bound.enclose(*random_state(np.random.default_rng(34), 6))
    np.testing.assert_array_equal(lower, 0.0)
    np.testing.assert_array_equal(upper, 0.0)


# ============================================================================ measurement
def main() -> None:
    """Denser overestimation measurement and timing (the figures of the docs)."""
    rng = np.random.default_rng(0)
    rr = load_robot("rr_planar")
    ur5 = load_robot("ur5")
    panda = load_robot("panda", locked_joints=PANDA_FINGERS)
    cases = [
        ("rr_planar, Table I", rr, load_uncertainty(RR_DIR / "uncertainty.yaml", rr)),
        ("ur5, every link", ur5, parse_uncertainty(uniform_physical_box(ur5), ur5)),
        ("panda, every link", panda, parse_uncertainty(uniform_physical_box(panda), panda)),
    ]
    for label, robot, box in cases:
        measure(robot, box, rng, n_states=50, n_random=500, n_vertices=500, label=label)
        bound = RigorousBound(robot, box)
        state = random_state(rng, robot.dof)
        n_calls = 200
        start = time.perf_counter()
        for _ in range(n_calls):
            bound.enclose(*state)
        elapsed = (time.perf_counter() - start) / n_calls
        print(f"{label}: {1e3 * elapsed:.3f} ms per enclose call")


if __name__ == "__main__":
    sys.exit(main())
