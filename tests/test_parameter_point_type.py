"""The typed parameter point (issue 18.9): what returns a point returns a read-only
``ParameterPoint``, what takes one still takes the older dict with the ``"<joints>"`` key, and the
two forms give the same plant, bit for bit."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import urpc
from urpc.errors import InputError
from urpc.model.point import JOINTS, ParameterPoint


@pytest.fixture(scope="module")
def ur5_drives():
    robot = urpc.load_robot("ur5")
    return robot, urpc.load_uncertainty("ur5/uncertainty_joint_friction", robot)


def _same_robot(a: urpc.Robot, b: urpc.Robot) -> bool:
    return a.model.saveToString() == b.model.saveToString() and np.array_equal(
        a.joint_parameters, b.joint_parameters
    )


def test_every_point_source_returns_a_typed_point(rr, rr_box, ur5_drives):
    robot, box = ur5_drives
    points = [
        rr_box.vertex(3),
        rr_box.sample(np.random.default_rng(0)),
        urpc.sample_rigid_point(rr_box, 0)[0],
        urpc.load_parameter_point("rr_planar", rr, rr_box),
        box.vertex(5),
        box.sample(np.random.default_rng(1)),
    ]
    assert all(type(p) is ParameterPoint for p in points)
    assert points[0].joints is None and points[4].joints.shape == (3, robot.dof)
    # The vertex picks, bit by bit, the ends of the uncertain coordinates (the box's rule).
    link = rr_box.link_box("link2")
    ends = np.flatnonzero(link.uncertain)
    expected = link.nominal.copy()
    upper = np.array([(3 >> bit) & 1 for bit in range(ends.size)], dtype=bool)
    expected[ends] = np.where(upper, link.upper[ends], link.lower[ends])
    np.testing.assert_array_equal(points[0].links["link2"], expected)


def test_a_point_is_read_only_and_replace_gives_a_checked_copy(rr_box):
    point = rr_box.vertex(0)
    with pytest.raises(ValueError):
        point.links["link2"][0] = 1.0
    with pytest.raises(TypeError):
        point.links["link3"] = np.zeros(10)  # type: ignore[index]
    with pytest.raises(dataclasses.FrozenInstanceError):
        point.joints = np.zeros((3, 2))  # type: ignore[misc]
    mine = np.arange(10.0)
    copy = ParameterPoint({"link2": mine})
    mine[0] = 99.0  # the point keeps its own copy
    assert copy.links["link2"][0] == 0.0
    heavier = dataclasses.replace(point, links={"link2": point.links["link2"] * 2})
    assert heavier.links["link2"][0] == 2 * point.links["link2"][0]
    with pytest.raises(InputError) as caught:
        dataclasses.replace(point, links={"link2": [1.0, 2.0]})
    assert caught.value.field == "point.link2"


def test_equality_hash_and_repr_follow_the_numbers(rr_box):
    a, b = rr_box.vertex(1), rr_box.vertex(1)
    assert a == b and hash(a) == hash(b) and len({a, b}) == 1
    assert a != rr_box.vertex(2) and a != ParameterPoint(a.links, np.zeros((3, 2)))
    assert a != a.as_dict()  # a dict is not a point (compare ParameterPoint.coerce(d))
    assert ParameterPoint({"link2": -0.0 * a.links["link2"]}) == ParameterPoint(
        {"link2": 0.0 * a.links["link2"]}
    )
    text = repr(a)
    assert text.startswith("ParameterPoint(links={'link2': [") and text.endswith("joints=None)")
    values = json.loads(text[text.index("[") : text.index("]") + 1])
    np.testing.assert_allclose(values, a.links["link2"], rtol=5e-6)  # 6 digits


def test_the_older_dict_form_gives_the_same_plant_bit_for_bit(rr, rr_box, ur5_drives):
    robot, box = ur5_drives
    q = np.random.default_rng(2).uniform(-1, 1, robot.dof)
    for b, r, point in (
        (rr_box, rr, rr_box.vertex(6)),
        (box, robot, box.sample(np.random.default_rng(3))),
    ):
        legacy = point.as_dict()
        assert set(legacy) == set(point.links) | ({JOINTS} if point.joints is not None else set())
        assert ParameterPoint.coerce(legacy) == point
        typed, old = b.plant(r, point), b.plant(r, legacy)
        assert _same_robot(typed, old)
        np.testing.assert_array_equal(typed.M(q[: r.dof]), old.M(q[: r.dof]))
    assert urpc.physically_consistent(box, point) == urpc.physically_consistent(box, legacy)
    assert rr_box.plant(rr, ParameterPoint({})).name == rr.name  # names nothing: nominal
    assert _same_robot(rr_box.plant(rr, ParameterPoint({})), rr_box.plant(rr))


def test_reading_a_point_as_a_dict_still_works_with_a_warning(ur5_drives):
    _, box = ur5_drives
    point = box.vertex(9)
    with pytest.warns(DeprecationWarning, match=r"point\.joints"):
        joints = point[JOINTS]
    np.testing.assert_array_equal(joints, point.joints)
    with pytest.warns(DeprecationWarning, match="ParameterPoint"):
        assert JOINTS in point and "payload" in point
    with pytest.warns(DeprecationWarning):
        assert dict(point.items()).keys() == point.as_dict().keys() == set(point.keys())
    with pytest.warns(DeprecationWarning, match=r"point\.get\('payload'\)"):
        np.testing.assert_array_equal(point.get("payload"), point.links["payload"])
    with pytest.warns(DeprecationWarning):
        assert point.get("nothing", 5) == 5 and len(list(point.values())) == len(point.links) + 1


def test_shape_errors_name_the_entry_as_before(rr, rr_box, ur5_drives):
    for bad in ({"link2": [1.0, 2.0]}, {"link2": [np.nan] * 10}):
        with pytest.raises(InputError) as caught:
            rr_box.plant(rr, bad)
        assert caught.value.field == "point.link2"
        assert "must be 10 finite numbers" in str(caught.value)
    robot, box = ur5_drives
    with pytest.raises(InputError) as caught:
        box.plant(robot, {JOINTS: np.zeros((3, 2))})
    assert caught.value.field == "point.<joints>" and "shape (3, 6)" in str(caught.value)
    with pytest.raises(InputError) as caught:
        box.plant(robot, ParameterPoint({}, np.zeros((3, 2))))  # the typed form, same check
    assert caught.value.field == "point.<joints>" and "shape (3, 6)" in str(caught.value)
    with pytest.raises(InputError) as caught:
        ParameterPoint({JOINTS: np.zeros(10)})
    assert caught.value.field == "links" and "joints=" in str(caught.value)
    with pytest.raises(InputError) as caught:
        rr_box.plant(rr, [1, 2, 3])  # type: ignore[arg-type]
    assert caught.value.field == "point" and "got list" in str(caught.value)


def test_for_box_checks_names_and_joints_against_the_box(rr_box, ur5_drives):
    robot, box = ur5_drives
    point = ParameterPoint.for_box(box, {"payload": box.link_box("payload").nominal})
    assert point.links.keys() == {"payload"}
    # A moving link the box does not bound is exact for the controller, but a valid name.
    exact = [n for n in robot.moving_link_names if n not in {b.link for b in box.links}]
    assert ParameterPoint.for_box(box, {exact[0]: np.ones(10)}).links.keys() == {exact[0]}
    with pytest.raises(InputError) as caught:
        ParameterPoint.for_box(rr_box, {"link9": np.zeros(10)})
    assert caught.value.field == "links.link9" and "link2" in str(caught.value)
    with pytest.raises(InputError) as caught:
        ParameterPoint.for_box(box, joints=np.zeros((3, 5)))
    assert caught.value.field == "point.<joints>" and "(3, 6)" in str(caught.value)


def test_a_campaign_run_on_a_box_with_drive_intervals_builds_its_plant():
    """The stored run keeps the drives row by row (flat); the worker used to pass that flat
    array to box.plant, which refused it for every run of such a campaign."""
    from urpc.studies.campaign.draws import draw_runs
    from urpc.studies.scenario import build, load_scenario

    setup = build(load_scenario("ur5/joint_friction").with_overrides(duration=0.05))
    specs, _ = draw_runs(setup, 2, 0)
    for spec in specs:
        point = spec.parameter_point
        assert len(spec.point[JOINTS]) == 18 and point.joints.shape == (3, 6)
        np.testing.assert_array_equal(point.joints.ravel(), spec.point[JOINTS])
        np.testing.assert_array_equal(setup.box.plant(point).joint_parameters, point.joints)
