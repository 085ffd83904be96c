"""Every parameter that enters the plant is checked against the box (issue 21.1): a joint drive
outside the box is warned and recorded as outside; a point with values the box has no place for
(joints without a joints: section, links the box does not list) is refused, naming them."""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest
from conftest import RR_DIR

import urpc
from urpc.__main__ import main
from urpc.errors import InputError
from urpc.model.uncertainty import outside_box
from urpc.studies.scenario import build, load_scenario
from urpc.studies.scenario.setup import OutsideBoxWarning

DRIVE_BOX = (RR_DIR / "uncertainty.yaml").read_text() + "\njoints: {joint1: {friction: [0, 1]}}\n"


def _files(tmp_path, box: str, point: str):
    (tmp_path / "box.yaml").write_text(box)
    (tmp_path / "point.yaml").write_text(point)
    return tmp_path / "box.yaml", tmp_path / "point.yaml"


def test_a_drive_outside_the_box_is_warned_and_recorded_outside(tmp_path, capsys):
    box, point = _files(tmp_path, DRIVE_BOX, "joints: {joint1: {friction: 5}}\n")
    argv = ["simulate", "--robot", "rr_planar", "-u", box, "--true-params", point]
    code = main([str(a) for a in [*argv, "--duration", "0.05", "--json"]])
    out, err = capsys.readouterr()
    assert code == 0, err
    summary = json.loads(out)["true_parameters"]
    assert summary["inside_box"] is False
    assert summary["outside_box"] == {"joint1.friction": pytest.approx(4.0)}
    assert "outside the box" in err and "joint1.friction" in err


def test_setup_records_the_drive_outside(tmp_path):
    robot = urpc.load_robot("rr_planar")
    box_path, point_path = _files(tmp_path, DRIVE_BOX, "joints: {joint1: {friction: 5}}\n")
    box = urpc.load_uncertainty(box_path, robot)
    point = urpc.load_parameter_point(point_path, robot, box)
    assert outside_box(box, point) == ["joint1.friction"]
    scenario = load_scenario("rr_planar/s3_ic1").with_overrides(duration=0.05)
    scenario = scenario.with_overrides(uncertainty=str(box_path), true_parameters=str(point_path))
    with pytest.warns(OutsideBoxWarning, match="joint1.friction"):
        setup = build(scenario)
    assert not setup.inside_box and set(setup.outside_box) == {"joint1.friction"}


def test_drives_for_a_box_without_joints_are_refused_naming_them(tmp_path):
    robot = urpc.load_robot("rr_planar")
    point = "joints: {joint1: {friction: 0.5, damping: 0.1}}\n"
    box_path, point_path = _files(tmp_path, (RR_DIR / "uncertainty.yaml").read_text(), point)
    box = urpc.load_uncertainty(box_path, robot)
    with pytest.raises(InputError) as info:
        urpc.load_parameter_point(point_path, robot, box)
    for word in ("point.yaml", "joints.joint1.friction", "joints.joint1.damping", "no 'joints:'"):
        assert word in str(info.value)


def test_a_link_the_box_does_not_list_is_exact_and_recorded_outside(tmp_path):
    robot = urpc.load_robot("rr_planar")
    box_path, point_path = _files(
        tmp_path, (RR_DIR / "uncertainty.yaml").read_text(), "links: {link1: {mass: 11}}\n"
    )
    scenario = load_scenario("rr_planar/s3_ic1").with_overrides(
        uncertainty=str(box_path), true_parameters=str(point_path)
    )
    with pytest.warns(OutsideBoxWarning, match="link1.mass"):
        setup = build(scenario)
    assert setup.outside_box == {"link1.mass": pytest.approx(1.0)}
    box = urpc.load_uncertainty(box_path, robot)
    same = tmp_path / "same.yaml"
    same.write_text("links: {link1: {mass: 10}}\n")  # its nominal: inside
    assert outside_box(box, urpc.load_parameter_point(same, robot, box), robot) == []


def test_the_shipped_points_are_inside_their_boxes():
    for name in ("rr_planar/s3_ic1", "ur5/heavy_payload", "panda/heavy_payload"):
        with warnings.catch_warnings():
            warnings.simplefilter("error", OutsideBoxWarning)
            assert build(load_scenario(name)).inside_box, name


def test_random_vertices_are_distinct_and_exhaust_the_box():
    """Every vertex once, in a seeded order, and on a box of more coordinates than an int64
    holds the indices still reach the last coordinates."""
    robot = urpc.load_robot("ur5")
    box = urpc.load_uncertainty("ur5", robot)
    drawn = list(box.random_vertices(np.random.default_rng(0)))
    assert sorted(drawn) == list(range(2**box.n_uncertain))
    assert drawn == list(box.random_vertices(np.random.default_rng(0)))
    wide = dataclasses.replace(box, links=box.links * 8)  # 80 coordinates
    first = [next(iter(wide.random_vertices(np.random.default_rng(k)))) for k in range(20)]
    assert max(first) >= 2**70 and len(set(first)) == 20
