"""The starting box of ``urpc init``: URDF nominal values, the asked widths, physical everywhere."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from urpc.errors import InputError
from urpc.model.box_template import (
    BoxTemplateSettings,
    box_template,
    link_templates,
    physical_inertia_width,
)
from urpc.model.parameter_box import physical_coordinates
from urpc.model.robot import load_robot
from urpc.model.uncertainty import parse_uncertainty
from urpc.studies.campaign import physically_consistent


@pytest.fixture(scope="module")
def ur10():
    return load_robot("ur10")


def _box(robot, settings: BoxTemplateSettings | None = None, source="ur10"):
    text = box_template(robot, settings or BoxTemplateSettings(), robot_source=source)
    return text, parse_uncertainty(yaml.safe_load(text), robot, source="template")


def test_every_moving_link_with_mass_is_listed_around_its_urdf_values(ur10):
    _, box = _box(ur10)
    massive = [n for n in ur10.moving_link_names if ur10.link(n).inertia.mass > 0]
    assert [b.link for b in box.links] == massive
    for link_box in box.links:
        urdf = physical_coordinates(ur10.link(link_box.link).inertia)
        assert np.allclose(link_box.nominal, urdf)
        mass = urdf[0]
        assert (link_box.lower[0], link_box.upper[0]) == pytest.approx((0.9 * mass, 1.1 * mass))
        assert np.allclose(link_box.upper[1:4] - link_box.lower[1:4], 0.02)


def test_inertia_widths_are_narrowed_only_where_the_box_would_leave_physics(ur10):
    templates = {t.link: t for t in link_templates(ur10, BoxTemplateSettings())}
    assert templates["shoulder_link"].inertia_relative == 0.2  # a compact body keeps 20 %
    slender = templates["upper_arm_link"]  # ixx = iyy >> izz: a 20 % box breaks I1 + I2 >= I3
    assert 0 < slender.inertia_relative < 0.2 and "narrowed" in slender.note
    assert templates["tool0"].inertia_relative is None  # massless: left out


def test_every_point_of_the_template_box_is_a_rigid_body(ur10):
    _, box = _box(ur10)
    rng = np.random.default_rng(1)
    assert all(physically_consistent(box, box.sample(rng)) for _ in range(300))
    n = box.n_uncertain
    corners = rng.integers(0, 2**n, size=100)
    assert all(physically_consistent(box, box.vertex(int(v))) for v in corners)


def test_physical_inertia_width_of_a_rod_and_a_sphere():
    sphere = np.eye(3) * 0.4
    assert physical_inertia_width(sphere, 0.2) == 0.2
    rod = np.diag([1.0, 1.0, 0.1])  # slack of the triangle inequality: 0.1 out of 2.1
    width = physical_inertia_width(rod, 0.2)
    assert width == pytest.approx(0.1 / 2.1, abs=1e-3) and width <= 0.1 / 2.1
    thin = np.diag([1.0, 1.0, 0.0])  # on the boundary: no room at all
    assert physical_inertia_width(thin, 0.2) == 0.0


def test_payload_and_exact_widths(ur10):
    settings = BoxTemplateSettings(0.0, 0.0, 0.0, payload_link="tool0", payload_mass=2.5)
    text, box = _box(ur10, settings)
    assert box.n_uncertain == 1 and box.payloads[0].link == "tool0"
    assert "every width is 0" in text


def test_settings_and_payload_link_are_checked(ur10):
    with pytest.raises(InputError, match="0, 1"):
        BoxTemplateSettings(mass_relative=1.0)
    with pytest.raises(InputError, match="both"):
        BoxTemplateSettings(payload_link="tool0")
    with pytest.raises(InputError, match="did you mean 'tool0'"):
        box_template(
            ur10, BoxTemplateSettings(payload_link="tool", payload_mass=1.0), robot_source="ur10"
        )
