"""Boxes that describe rigid bodies (urpc.model.box_consistency): refused when no rigid body has
a negative mass or moment, or when the bound would overflow; accepted with a warning saying which
part is no rigid body when only part of the box is; the bound over such a box stays sound."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import yaml
from conftest import RR_DIR

from urpc.bounds import make_bound
from urpc.bounds.base import link_body_placement
from urpc.cli import main
from urpc.model.box_consistency import NonPhysicalBoxWarning, corner_check
from urpc.model.box_template import BoxTemplateSettings, box_template
from urpc.model.regressor import SlotineLiRegressor
from urpc.model.robot import load_robot
from urpc.model.uncertainty import load_uncertainty, parse_uncertainty

#: link2 of the RR arm: ixx = izz = 5/3, iyy = 5/12, so iyy <= ixx + izz fails above 10/3.
PARTLY_NON_PHYSICAL = "links: {link2: {iyy: [0.1, 4]}}\n"


@pytest.fixture(scope="module")
def rr():
    return load_robot("rr_planar")


def test_a_box_partly_outside_physics_is_accepted_with_a_warning_naming_the_part(rr):
    with pytest.warns(NonPhysicalBoxWarning) as record:
        box = parse_uncertainty(yaml.safe_load(PARTLY_NON_PHYSICAL), rr, source="box.yaml")
    message = str(record[0].message)
    assert "links.link2" in message and "'link2'" in message
    assert "triangle inequality fails where iyy > ixx + izz" in message
    assert "iyy reaches 4" in message and "3.33333" in message and "stays sound" in message
    assert "iyy > ixx + izz" in box.link_box("link2").non_physical


def test_cli_check_prints_one_warning_line_and_exits_0(tmp_path, capsys):
    path = tmp_path / "box.yaml"
    path.write_text(PARTLY_NON_PHYSICAL)
    assert main(["check", "rr_planar", "--uncertainty", str(path)]) == 0
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: "), err
    assert str(path) in lines[0] and "links.link2" in lines[0] and "triangle" in lines[0]
    assert "link2" in out


def test_off_diagonal_boxes_name_a_non_physical_corner(rr):
    text = "links: {link2: {ixy: [-1.5, 1.5]}}"
    with pytest.warns(NonPhysicalBoxWarning, match=r"of its 2 corners, e\.g\. ixy = -1\.5"):
        parse_uncertainty(yaml.safe_load(text), rr)


def test_barycentric_boxes_are_checked_at_their_corners(rr):
    # h_x = m c_x = 2.5 nominally; a CoM far out with the same I_O is no rigid body.
    text = "links: {link2: {barycentric: {h_x: [0, 10]}}}"
    with pytest.warns(NonPhysicalBoxWarning, match="pseudo-inertia is not positive semi"):
        box = parse_uncertainty(yaml.safe_load(text), rr)
    assert box.link_box("link2").non_physical


def test_the_bound_over_a_partly_non_physical_box_encloses_its_non_physical_corner(rr):
    with pytest.warns(NonPhysicalBoxWarning):
        box = parse_uncertainty(yaml.safe_load(PARTLY_NON_PHYSICAL), rr)
    link_box = box.link_box("link2")
    corner = link_box.nominal.copy()
    corner[link_box.fields.index("iyy")] = 4.0  # iyy > ixx + izz: no rigid body
    assert not corner_check(link_box).all_physical
    body, placement = link_body_placement(rr, "link2")
    delta = placement @ (
        link_box.standard_parameters(corner) - link_box.standard_parameters(link_box.nominal)
    )
    regressor = SlotineLiRegressor(rr)
    rng = np.random.default_rng(3)
    for method in ("vertex", "hull", "rigorous"):
        bound = make_bound(method, rr, box)
        for _ in range(20):
            state = [rng.normal(size=2) * s for s in (1.0, 3.0, 3.0, 10.0)]
            w = regressor(*state)[:, 10 * body : 10 * body + 10] @ delta
            lower, upper = bound.enclose(*state)
            assert np.all(lower <= w + 1e-9) and np.all(w <= upper + 1e-9), method


@pytest.mark.parametrize(
    ("name", "locked"),
    [("rr_planar", ()), ("ur10", ()), ("kinova", ()), ("z1", ()), ("so101", ()),
     ("panda", ("panda_finger_joint1", "panda_finger_joint2"))],
)  # fmt: skip
@pytest.mark.parametrize("inertia", [0.2, 0.9])
def test_urpc_init_boxes_stay_accepted_without_a_warning(name, locked, inertia):
    robot = load_robot(name, locked_joints=list(locked))
    settings = BoxTemplateSettings(
        inertia_relative=inertia, payload_link=robot.moving_link_names[-1], payload_mass=2.0
    )
    text = box_template(robot, settings, robot_source=name, locked_joints=locked)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        box = parse_uncertainty(yaml.safe_load(text), robot)
    assert all(link_box.non_physical is None for link_box in box.links)


@pytest.mark.parametrize("name", ["rr_planar", "ur5", "panda"])
def test_the_shipped_boxes_are_entirely_physical(name):
    # The payload moments of UR5 and Panda lie in [0.0025, 0.005] each: max <= 2 min keeps the
    # triangle inequality at every corner (with [0, 0.005], ixx = 0.005 > iyy + izz = 0).
    locked = ["panda_finger_joint1", "panda_finger_joint2"] if name == "panda" else []
    robot = load_robot(name, locked_joints=locked)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        box = load_uncertainty(name, robot)
    assert all(b.non_physical is None for b in box.links)


def test_an_explicit_empty_links_mapping_still_says_exact(rr, tmp_path):
    path = tmp_path / "box.yaml"
    path.write_text("links: {}\n")
    assert load_uncertainty(path, rr).n_uncertain == 0
    path.write_text("robot: rr_planar\nlinks: {}\n")
    assert load_uncertainty(path, rr).n_uncertain == 0


def test_a_box_naming_the_urdf_by_path_or_alias_is_for_that_robot(tmp_path):
    ur5 = load_robot("ur5")
    for declared in ("ur5", "ur5_robot", "/somewhere/ur5_robot.urdf"):
        assert parse_uncertainty({"robot": declared, "links": {}}, ur5).n_uncertain == 0
    rr = load_robot(RR_DIR / "rr_planar.urdf")
    assert parse_uncertainty({"robot": "rr_planar.urdf", "links": {}}, rr).n_uncertain == 0
