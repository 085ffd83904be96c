"""The uncertainty file format: every accepted form, and one clear error per kind of bad input."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import yaml
from conftest import RR_DIR

from urpc.__main__ import main
from urpc.errors import InputError
from urpc.model.robot import load_robot
from urpc.model.uncertainty import (
    BARYCENTRIC_FIELDS,
    PHYSICAL_FIELDS,
    load_parameter_point,
    load_uncertainty,
    outside_box,
    parse_uncertainty,
    physical_coordinates,
)


def test_table_one_box(rr_box):
    (link2,) = rr_box.links
    assert link2.link == "link2" and link2.kind == "physical"
    expected = {"mass": (5, 10), "com_x": (0.5, 0.525), "iyy": (5 / 12, 20 / 12)}
    for k, name in enumerate(PHYSICAL_FIELDS):
        lo, hi = expected.get(name, (link2.nominal[k], link2.nominal[k]))
        assert link2.lower[k] == pytest.approx(lo, abs=1e-15)
        assert link2.upper[k] == pytest.approx(hi, abs=1e-15)
    assert rr_box.disturbance_bound is None and rr_box.n_uncertain == 3


def test_true_plant_is_a_vertex_of_the_box(rr, rr_box, rr_true_point):
    assert outside_box(rr_box, rr_true_point) == []
    vertices = [rr_box.vertex(k).links["link2"] for k in range(2**rr_box.n_uncertain)]
    assert any(np.allclose(v, rr_true_point.links["link2"]) for v in vertices)
    plant = rr_box.plant(rr, rr_true_point)
    assert plant.link("link2").inertia.mass == 10


def _box(robot, document):
    return parse_uncertainty(document, robot, source="test.yaml")


def test_relative_and_offset_forms(rr):
    box = _box(
        rr,
        {
            "disturbance": 10,
            "links": {
                "link2": {
                    "mass": "10%",
                    "com_x": "+-0.05",
                    "iyy": ["0%", "+100%"],
                    "izz": ["-0.1", "+0.2"],
                    "ixx": "20/12",
                }
            },
        },
    )
    b = box.link_box("link2")
    get = {name: (b.lower[k], b.upper[k]) for k, name in enumerate(PHYSICAL_FIELDS)}
    assert get["mass"] == pytest.approx((4.5, 5.5))
    assert get["com_x"] == pytest.approx((0.45, 0.55))
    assert get["iyy"] == pytest.approx((5 / 12, 10 / 12))
    assert get["izz"] == pytest.approx((20 / 12 - 0.1, 20 / 12 + 0.2))
    assert get["ixx"] == pytest.approx((20 / 12, 20 / 12))
    assert box.disturbance_bound == 10.0


def test_barycentric_box_and_payload(ur5):
    box = _box(
        ur5,
        {
            "links": {"forearm_link": {"barycentric": {"m": "10%", "h_z": "+-0.05"}}},
            "payload": {"link": "wrist_3_link", "mass": [0, 3], "com_z": [0, 0.1]},
        },
    )
    forearm = box.link_box("forearm_link")
    assert forearm.kind == "barycentric" and forearm.fields == BARYCENTRIC_FIELDS
    assert forearm.upper[0] == pytest.approx(1.1 * ur5.link("forearm_link").inertia.mass)
    payload = box.link_box("payload")
    assert payload.nominal[0] == pytest.approx(1.5) and payload.nominal[3] == pytest.approx(0.05)
    nominal = box.nominal_robot(ur5)
    assert "payload" in nominal.link_names
    assert nominal.model.inertias[6].mass == pytest.approx(ur5.model.inertias[6].mass + 1.5)
    # Idempotent: the payload is attached once.
    assert box.nominal_robot(nominal) is nominal


def test_parameter_point_file(tmp_path, ur5):
    box = _box(ur5, {"payload": {"link": "wrist_3_link", "mass": [0, 3]}})
    path = tmp_path / "true.yaml"
    path.write_text(
        yaml.safe_dump({"links": {"forearm_link": {"mass": 2.5}}, "payload": {"mass": 2.0}})
    )
    point = load_parameter_point(path, ur5, box)
    plant = box.plant(ur5, point)
    assert plant.link("forearm_link").inertia.mass == 2.5
    assert plant.link("payload").inertia.mass == 2.0
    # Parameters not named stay nominal.
    np.testing.assert_allclose(
        physical_coordinates(plant.link("upper_arm_link").inertia),
        physical_coordinates(ur5.link("upper_arm_link").inertia),
    )


BAD_CASES = {
    "lo_greater_than_hi": (
        {"links": {"link2": {"mass": [10, 5]}}},
        "links.link2.mass",
        "greater than",
    ),
    "zero_mass": ({"links": {"link2": {"mass": [0, 10]}}}, "links.link2.mass", "strictly positive"),
    "negative_mass": (
        {"links": {"link2": {"mass": [-1, 10]}}},
        "links.link2.mass",
        "strictly positive",
    ),
    "nominal_outside": (
        {"links": {"link2": {"mass": [6, 10]}}},
        "links.link2.mass",
        "outside the box",
    ),
    "unknown_link": ({"links": {"link3": {"mass": "10%"}}}, "links.link3", "valid: link1, link2"),
    "fixed_link": (
        {"links": {"base_link": {"mass": [0, 1]}}},
        "links.base_link",
        "fixed to the base",
    ),
    "unknown_key": (
        {"links": {"link2": {"masss": "10%"}}},
        "links.link2.masss",
        "did you mean 'mass'",
    ),
    "unknown_top_key": ({"link": {}}, "link", "did you mean 'links'"),
    "wrong_type": ({"links": {"link2": {"mass": "heavy"}}}, "links.link2.mass", "not a number"),
    "wrong_type_list": ({"links": {"link2": {"mass": [1, 2, 3]}}}, "links.link2.mass", "3 entries"),
    "links_not_mapping": ({"links": ["link2"]}, "links", "expected a mapping"),
    "bad_disturbance": ({"disturbance": -3}, "disturbance", "'unknown'"),
    "mixed_kinds": (
        {"links": {"link2": {"mass": "1%", "barycentric": {"m": "1%"}}}},
        "barycentric",
        "not both",
    ),
    "payload_without_link": ({"payload": {"mass": [0, 1]}}, "payload.link", "valid: link1, link2"),
}


@pytest.mark.parametrize("case", sorted(BAD_CASES))
def test_bad_input_names_file_and_field(rr, tmp_path, case, capsys):
    document, fieldname, message = BAD_CASES[case]
    path = tmp_path / "box.yaml"
    path.write_text(yaml.safe_dump(document))
    with pytest.raises(InputError) as info:
        load_uncertainty(path, rr)
    assert str(path) in str(info.value)
    assert fieldname in str(info.value)
    assert message in str(info.value)
    assert main(["check", "rr_planar", "--uncertainty", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err


def _robot_with_link2_inertia(tmp_path, inertia_xml: str):
    text = (RR_DIR / "rr_planar.urdf").read_text()
    start = text.index('<link name="link2">')
    start = text.index("<inertia ", start)
    end = text.index("/>", start) + 2
    path = tmp_path / "arm.urdf"
    path.write_text(text[:start] + inertia_xml + text[end:])
    return load_robot(path)


def test_nominal_inertia_violating_triangle_inequality(tmp_path):
    robot = _robot_with_link2_inertia(
        tmp_path, '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="1.0"/>'
    )
    with pytest.raises(InputError, match="links.link2.*triangle inequality"):
        parse_uncertainty({"links": {"link2": {"mass": [5, 10]}}}, robot, source="box.yaml")


def test_nominal_inertia_not_positive_definite_in_urdf(tmp_path):
    with pytest.raises(InputError, match="link.link2.inertial.*positive semi-definite"):
        _robot_with_link2_inertia(
            tmp_path, '<inertia ixx="0.1" ixy="0" ixz="0" iyy="-0.1" iyz="0" izz="0.1"/>'
        )


def test_barycentric_box_on_non_physical_nominal(tmp_path):
    robot = _robot_with_link2_inertia(
        tmp_path, '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="1.0"/>'
    )
    with pytest.raises(InputError, match="links.link2.barycentric.*triangle inequality"):
        parse_uncertainty({"links": {"link2": {"barycentric": {"m": "10%"}}}}, robot, "box.yaml")


def test_yaml_syntax_error_names_line(tmp_path, rr):
    path = tmp_path / "box.yaml"
    path.write_text("links:\n  link2:\n    mass: [5, 10\n")
    with pytest.raises(InputError, match=r"box.yaml: YAML syntax error at line \d+"):
        load_uncertainty(path, rr)


def test_point_file_errors(tmp_path, rr, rr_box):
    path = tmp_path / "true.yaml"
    path.write_text(yaml.safe_dump({"links": {"link2": {"mas": 3}}}))
    with pytest.raises(InputError, match="did you mean 'mass'"):
        load_parameter_point(path, rr, rr_box)
    path.write_text(yaml.safe_dump({"links": {"link2": {"mass": 0}}}))
    with pytest.raises(InputError, match="mass must be > 0"):
        load_parameter_point(path, rr, rr_box)


def test_spatial_inertia_round_trip():
    rng = np.random.default_rng(3)
    for _ in range(10):
        A = rng.normal(size=(3, 3))
        inertia = pin.Inertia(rng.uniform(0.1, 5), rng.normal(size=3), A @ A.T)
        from urpc.model.uncertainty import inertia_from_physical

        back = inertia_from_physical(physical_coordinates(inertia))
        np.testing.assert_allclose(back.toDynamicParameters(), inertia.toDynamicParameters())
