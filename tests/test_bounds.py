"""Bound methods: soundness against dense sampling of the box, tightness.

The reference mismatch torque is computed independently of the bound methods, per parameter
sample: ``plant = box.plant(robot, point)`` and Pinocchio's ``crba`` / ``computeCoriolisMatrix`` /
``computeGeneralizedGravity`` on that plant, ``w = (M - M0) qdd_a + (C - C0) qd_a + g - g0`` (and,
for the RR arm, the textbook model of ``conftest.rr_closed_form``). Samples are uniform draws of
the box plus all its vertices (random vertices when there are more than 1024).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pytest
from conftest import rr_closed_form
from hypothesis import given, settings
from hypothesis import strategies as st

from urpc.bounds import METHODS, default_method, make_bound
from urpc.bounds.base import ROUNDING_ABSOLUTE
from urpc.bounds.vertex import VertexBound
from urpc.errors import InputError, UrpcError
from urpc.model.regressor import SlotineLiRegressor
from urpc.model.uncertainty import LinkBox, ParameterBox, parse_uncertainty

#: The registered methods, plus the vertex method with its plain curvature margin.
ALL_METHODS = [*sorted(METHODS), "vertex-plain"]
FAST_METHODS = ["hull", "vertex", "vertex-plain"]


def build(method: str, robot, box):
    if method == "vertex-plain":
        return VertexBound(robot, box, exact_com=False)
    return make_bound(method, robot, box)


WRIST = {"mass": "10%", "com_x": "+-0.02", "com_y": "+-0.02", "com_z": "+-0.02"}
WRIST |= {"ixx": "20%", "iyy": "20%", "izz": "20%"}
PAYLOAD = {"mass": [0, 3], "com_z": [0, 0.1]}
UR5_BOX = {
    "links": {
        "upper_arm_link": {"barycentric": {"m": "5%", "h_z": "+-0.05", "I_xx": "10%"}},
        "wrist_1_link": WRIST,
        "wrist_2_link": WRIST,
        "wrist_3_link": WRIST,
    },
    "payload": {"link": "tool0", **PAYLOAD},
}
PANDA_BOX = {
    "links": {
        "panda_link5": WRIST,
        "panda_link6": WRIST,
        "panda_link7": WRIST,
        "panda_hand": {"barycentric": {"m": "10%", "h_x": "+-0.01", "I_zz": "20%"}},
    },
    "payload": {"link": "panda_hand_tcp", **PAYLOAD},
}
#: A physical UR5 box with 8 uncertain coordinates (256 vertices, all enumerated).
UR5_PHYSICAL = {
    "links": {
        "forearm_link": {"mass": "10%", "com_z": "+-0.02"},
        "wrist_1_link": {"mass": "10%", "com_x": "+-0.02", "com_y": "+-0.02", "iyy": "20%"},
    },
    "payload": {"link": "tool0", **PAYLOAD},
}
#: A barycentric UR5 box with 8 uncertain coordinates.
UR5_BARYCENTRIC = {
    "links": {
        "forearm_link": {"barycentric": {"m": "10%", "h_z": "+-0.05", "I_yy": "20%"}},
        "wrist_2_link": {"barycentric": {"m": "10%", "h_x": "+-0.01", "h_y": "+-0.01"}},
        "wrist_3_link": {"barycentric": {"m": "10%", "I_zz": "30%", "h_z": "+-0.002"}},
    }
}


# ============================================================================== references
def sample_points(box: ParameterBox, rng: np.random.Generator, n_uniform: int, n_vertices: int):
    """Uniform draws plus every vertex (``2^n <= 1024``) or ``n_vertices`` random vertices."""
    points = [box.sample(rng) for _ in range(n_uniform)]
    n = box.n_uncertain
    if n <= 10:
        points += [box.vertex(k) for k in range(2**n)]
    else:
        points += [box.vertex(int(k)) for k in rng.integers(0, 2**n, size=n_vertices)]
    return points


def random_state(rng: np.random.Generator, dof: int, scale: float = 1.0):
    """``(q, qd, qd_a, qdd_a)`` [rad, rad/s, rad/s, rad/s^2] of magnitude ``scale``."""
    q = rng.uniform(-np.pi, np.pi, dof)
    qd, qd_a = scale * rng.normal(size=dof), scale * rng.normal(size=dof)
    return q, qd, qd_a, 5.0 * scale * rng.normal(size=dof)


@dataclass
class Sampled:
    """Mismatch torques ``w`` of every sample at every state (``states x samples x dof``) and
    the magnitude of the torques involved (for the rounding tolerance of the reference)."""

    states: list
    w: np.ndarray
    magnitude: np.ndarray


def sampled_mismatch(robot, box, points, states) -> Sampled:
    nominal = box.nominal_robot(robot)
    plants = [box.plant(robot, point) for point in points]
    w, magnitude = [], []
    for q, qd, qd_a, qdd_a in states:
        M0, C0, g0 = nominal.M(q), nominal.C(q, qd), nominal.g(q)
        w.append([(p.M(q) - M0) @ qdd_a + (p.C(q, qd) - C0) @ qd_a + p.g(q) - g0 for p in plants])
        magnitude.append(np.abs(M0 @ qdd_a) + np.abs(C0 @ qd_a) + np.abs(g0) + 1.0)
    return Sampled(states, np.array(w), np.array(magnitude))


def assert_encloses(lower, upper, w, magnitude):
    """Every sample inside ``[lower, upper]``, up to the reference's own rounding."""
    tolerance = 1e-12 * magnitude
    below = w < lower - tolerance
    above = w > upper + tolerance
    assert not below.any(), f"samples below the enclosure: {np.argwhere(below)[:5]}"
    assert not above.any(), f"samples above the enclosure: {np.argwhere(above)[:5]}"


def width_ratios(lower, upper, w) -> np.ndarray:
    """``width(enclosure) / width(sampled hull)`` per joint; ``nan`` where the sampled width is
    negligible (a joint the box cannot move)."""
    sampled = w.max(axis=0) - w.min(axis=0)
    ratio = (upper - lower) / np.where(sampled > 0, sampled, 1.0)
    return np.where(sampled > 1e-6 * max(sampled.max(), 1e-300), ratio, np.nan)


# ============================================================================== fixtures
CASES = {
    "rr": dict(n_uniform=200, n_vertices=0, n_states=8),
    "ur5": dict(n_uniform=150, n_vertices=150, n_states=6),
    "panda": dict(n_uniform=150, n_vertices=150, n_states=6),
}


@pytest.fixture(scope="module")
def boxes(rr, rr_box, ur5, panda):
    return {
        "rr": (rr, rr_box),
        "ur5": (ur5, parse_uncertainty(UR5_BOX, ur5)),
        "panda": (panda, parse_uncertainty(PANDA_BOX, panda)),
    }


_SAMPLED: dict[str, Sampled] = {}


def sampled_case(boxes, case: str) -> Sampled:
    if case not in _SAMPLED:
        robot, box = boxes[case]
        settings_ = CASES[case]
        rng = np.random.default_rng(sum(map(ord, case)))
        points = sample_points(box, rng, settings_["n_uniform"], settings_["n_vertices"])
        n = settings_["n_states"]
        states = [random_state(rng, robot.dof) for _ in range(n - 2)]
        states += [random_state(rng, robot.dof, scale=15.0) for _ in range(2)]
        _SAMPLED[case] = sampled_mismatch(robot, box, points, states)
    return _SAMPLED[case]


# ============================================================================== soundness
@pytest.mark.parametrize("method", ALL_METHODS)
@pytest.mark.parametrize("case", list(CASES))
def test_every_sample_lies_in_the_enclosure(boxes, case, method):
    robot, box = boxes[case]
    sampled = sampled_case(boxes, case)
    bound = build(method, robot, box)
    for state, w, magnitude in zip(sampled.states, sampled.w, sampled.magnitude, strict=True):
        lower, upper = bound.enclose(*state)
        assert np.all(lower <= upper)
        assert_encloses(lower, upper, w, magnitude)
        np.testing.assert_allclose(bound.rho(*state), np.maximum(-lower, upper), rtol=1e-12)


@pytest.mark.parametrize("method", ALL_METHODS)
def test_rr_enclosure_contains_the_textbook_model(rr, rr_box, method):
    """The paper's arm, with the reference ``w`` from the closed-form model (no Pinocchio)."""
    rng = np.random.default_rng(7)
    link2 = rr_box.link_box("link2")  # coordinates: mass, com_x = lc2, iyy = I2
    nominal = link2.nominal
    points = [p.links["link2"] for p in sample_points(rr_box, rng, 300, 0)]
    bound = build(method, rr, rr_box)
    for scale in (1.0, 1.0, 1.0, 20.0):
        q, qd, qd_a, qdd_a = random_state(rng, 2, scale)
        M0, C0, g0 = rr_closed_form(q, qd, nominal[0], nominal[1], nominal[6])
        w = []
        for p in points:
            M, C, g = rr_closed_form(q, qd, p[0], p[1], p[6])
            w.append((M - M0) @ qdd_a + (C - C0) @ qd_a + g - g0)
        magnitude = np.abs(M0 @ qdd_a) + np.abs(C0 @ qd_a) + np.abs(g0) + 1.0
        assert_encloses(*bound.enclose(q, qd, qd_a, qdd_a), np.array(w), magnitude)


LINKS = ["shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_3_link"]


@settings(max_examples=12, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    links=st.lists(st.sampled_from(LINKS), min_size=1, max_size=2, unique=True),
    barycentric=st.booleans(),
    mass=st.floats(0.0, 0.5),
    com=st.floats(0.0, 0.05),
    inertia=st.floats(0.0, 0.5),
    payload=st.booleans(),
)
def test_random_small_boxes_are_enclosed(
    ur5, seed, links, barycentric, mass, com, inertia, payload
):
    def percent(x: float) -> str:
        return f"{100 * x}%"

    entries = {}
    for k, name in enumerate(links):
        if barycentric and k == 0:
            entry = {"m": percent(mass), "h_y": f"+-{com}", "I_yy": percent(inertia)}
            entries[name] = {"barycentric": entry}
        else:
            entries[name] = {
                "mass": percent(mass),
                **{f"com_{a}": f"+-{com}" for a in "xyz"},
                **{f"i{a}{a}": percent(inertia) for a in "xyz"},
            }
    document = {"links": entries}
    if payload:
        document["payload"] = {"link": "wrist_3_link", "mass": [0, 2.0], "com_x": [-com, com]}
    box = parse_uncertainty(document, ur5)
    rng = np.random.default_rng(seed)
    points = sample_points(box, rng, 30, 30)
    states = [random_state(rng, ur5.dof, scale) for scale in (1.0, 10.0)]
    sampled = sampled_mismatch(ur5, box, points, states)
    for method in ALL_METHODS:
        bound = build(method, ur5, box)
        for state, w, magnitude in zip(states, sampled.w, sampled.magnitude, strict=True):
            assert_encloses(*bound.enclose(*state), w, magnitude)


@pytest.mark.parametrize("method", ALL_METHODS)
def test_a_known_disturbance_adds_exactly_its_bound(ur5, method):
    beta = 7.5
    unknown = parse_uncertainty(UR5_PHYSICAL, ur5)
    known = parse_uncertainty({**UR5_PHYSICAL, "disturbance": beta}, ur5)
    state = random_state(np.random.default_rng(8), ur5.dof)
    lower, upper = build(method, ur5, unknown).enclose(*state)
    bound = build(method, ur5, known)
    known_lower, known_upper = bound.enclose(*state)
    np.testing.assert_allclose(known_lower, lower - beta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(known_upper, upper + beta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(bound.rho(*state), np.maximum(-lower, upper) + beta, atol=1e-12)


@pytest.mark.parametrize("method", FAST_METHODS)
def test_enclose_regressor_agrees_with_enclose(boxes, method):
    robot, box = boxes["panda"]
    bound = build(method, robot, box)
    state = random_state(np.random.default_rng(9), robot.dof)
    regressor = SlotineLiRegressor(box.nominal_robot(robot))
    Y = regressor(*state)
    with pytest.raises(UrpcError, match="rounding envelope"):  # a foreign Y: state unknown
        bound.enclose_regressor(Y)
    enclosed = bound.enclose_regressor(Y, envelope=regressor.envelope)
    for got, expected in zip(enclosed, bound.enclose(*state), strict=True):
        np.testing.assert_allclose(got, expected, rtol=1e-13, atol=1e-13)
    # The bound's own regressor: its last call's envelope is used.
    own = bound.regressor(*state)
    for got, expected in zip(bound.enclose_regressor(own), enclosed, strict=True):
        np.testing.assert_allclose(got, expected, rtol=1e-13, atol=1e-13)


# ============================================================================== tightness
def rr_and_ur5_physical(rr, rr_box, ur5):
    return [("rr", rr, rr_box), ("ur5", ur5, parse_uncertainty(UR5_PHYSICAL, ur5))]


def test_vertex_is_tight_on_physical_boxes(rr, rr_box, ur5):
    """``width(vertex) / width(sampled hull) <= 1.05`` (the sampled hull includes every vertex,
    so it is an inner approximation of the exact range)."""
    for label, robot, box in rr_and_ur5_physical(rr, rr_box, ur5):
        rng = np.random.default_rng(10)
        points = sample_points(box, rng, 200, 0)
        assert box.n_uncertain <= 10  # all vertices are in the sample
        states = [random_state(rng, robot.dof) for _ in range(6)]
        sampled = sampled_mismatch(robot, box, points, states)
        bound = make_bound("vertex", robot, box)
        ratios = np.concatenate(
            [width_ratios(*bound.enclose(*s), w) for s, w in zip(states, sampled.w, strict=True)]
        )
        ratios = ratios[np.isfinite(ratios)]
        assert ratios.size >= len(states) * (robot.dof - 1), label
        assert ratios.min() >= 1.0 - 1e-9, label  # sound
        assert ratios.max() <= 1.05, (label, ratios.max())


#: A barycentric Panda box on the hand, which sits off its body frame (rotated, offset).
PANDA_BARYCENTRIC = {
    "links": {
        "panda_hand": {"barycentric": {"m": "10%", "h_x": "+-0.01", "h_y": "+-0.01"}},
        "panda_link7": {"barycentric": {"m": "10%", "I_xy": "+-0.002", "I_zz": "20%"}},
    }
}


@pytest.mark.parametrize(
    ("name", "document"), [("ur5", UR5_BARYCENTRIC), ("panda", PANDA_BARYCENTRIC)]
)
def test_hull_and_vertex_are_exact_on_barycentric_boxes(request, name, document):
    """``w`` is linear over a barycentric box, so its vertices realize the exact range."""
    robot = request.getfixturevalue(name)
    box = parse_uncertainty(document, robot)
    assert box.n_uncertain <= 10
    rng = np.random.default_rng(11)
    points = sample_points(box, rng, 0, 0)
    states = [random_state(rng, robot.dof) for _ in range(4)]
    sampled = sampled_mismatch(robot, box, points, states)
    hull, vertex = build("hull", robot, box), build("vertex", robot, box)
    for state, w in zip(states, sampled.w, strict=True):
        ratios = width_ratios(*hull.enclose(*state), w)
        ratios = ratios[np.isfinite(ratios)]
        assert ratios.size >= robot.dof - 2
        assert np.all(np.abs(ratios - 1.0) < 1e-6), ratios
        for a, b in zip(hull.enclose(*state), vertex.enclose(*state), strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-10)


def test_vertex_is_exact_when_only_masses_are_uncertain(ur5):
    """Linear in each mass: the vertices realize the range (ratio 1 up to the rounding margin)."""
    document = {"links": {name: {"mass": "20%"} for name in LINKS}}
    box = parse_uncertainty(document, ur5)
    rng = np.random.default_rng(12)
    states = [random_state(rng, ur5.dof) for _ in range(3)]
    sampled = sampled_mismatch(ur5, box, sample_points(box, rng, 0, 0), states)
    bound = make_bound("vertex", ur5, box)
    for state, w in zip(states, sampled.w, strict=True):
        ratios = width_ratios(*bound.enclose(*state), w)
        ratios = ratios[np.isfinite(ratios)]
        assert np.all(np.abs(ratios - 1.0) < 1e-6), ratios


#: A wide CoM box on one UR5 wrist link (exact inertia about the CoM): ``G`` is a quadratic in the
#: CoM whose extrema often lie inside the box, where no vertex sees them.
WIDE_COM = {"links": {"wrist_2_link": {"mass": [1.0, 2.0], **{f"com_{a}": "+-0.3" for a in "xyz"}}}}


@pytest.mark.parametrize("exact_com", [True, False])
def test_vertex_margin_covers_interior_extrema(ur5, exact_com):
    """Through the whole method (regressor, compiled kernel): on a dense CoM grid at both mass
    ends, every ``w`` lies in the enclosure, and at some states the grid's extreme beats every
    vertex, so the curvature margin (not the vertices) is what keeps the bound sound."""
    box = parse_uncertainty(WIDE_COM, ur5)
    (link,) = box.links
    grid = np.linspace(-0.3, 0.3, 7)
    points, corner = [], []
    for mass, *offset in itertools.product([1.0, 2.0], grid, grid, grid):
        values = link.nominal.copy()
        values[0], values[1:4] = mass, link.nominal[1:4] + np.array(offset)
        points.append({link.link: values})
        corner.append(all(abs(abs(o) - 0.3) < 1e-12 for o in offset))
    rng = np.random.default_rng(21)
    states = [random_state(rng, ur5.dof) for _ in range(8)]
    sampled = sampled_mismatch(ur5, box, points, states)
    bound = VertexBound(ur5, box, exact_com=exact_com)
    corner = np.array(corner)
    interior_wins = 0
    for state, w, magnitude in zip(states, sampled.w, sampled.magnitude, strict=True):
        lower, upper = bound.enclose(*state)
        assert_encloses(lower, upper, w, magnitude)
        span = w.max(axis=0) - w.min(axis=0) + 1e-300
        interior_wins += np.sum(w.max(axis=0) > w[corner].max(axis=0) + 1e-3 * span)
        interior_wins += np.sum(w.min(axis=0) < w[corner].min(axis=0) - 1e-3 * span)
    assert interior_wins > 0  # without the margin, the vertices alone would not be sound here


# ============================================================================== misc
def test_vertex_is_registered_and_the_default_for_physical_boxes(rr_box, ur5):
    assert "vertex" in METHODS
    assert default_method(rr_box) == "vertex"
    assert default_method(parse_uncertainty(UR5_BARYCENTRIC, ur5)) == "hull"


@pytest.mark.parametrize("method", FAST_METHODS)
def test_a_box_without_uncertain_links_encloses_zero(ur5, method):
    box = parse_uncertainty({"links": {"wrist_1_link": {"mass": "0%"}}}, ur5)
    bound = build(method, ur5, box)
    lower, upper = bound.enclose(*random_state(np.random.default_rng(15), ur5.dof))
    np.testing.assert_allclose(lower, -ROUNDING_ABSOLUTE, rtol=0, atol=1e-15)
    np.testing.assert_allclose(upper, ROUNDING_ABSOLUTE, rtol=0, atol=1e-15)


def test_vertex_rejects_a_negative_mass(ur5):
    nominal = ur5.link("wrist_1_link").parameters
    coordinates = np.array([1.219, 0, 0, 0, 0.1, 0, 0.1, 0, 0, 0.1])
    lower, upper = coordinates.copy(), coordinates.copy()
    lower[0] = -1.0
    box = ParameterBox(links=(LinkBox("wrist_1_link", "physical", coordinates, lower, upper),))
    assert nominal[0] == pytest.approx(1.219)
    with pytest.raises(InputError, match="non-negative"):
        make_bound("vertex", ur5, box)
