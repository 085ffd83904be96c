"""Drives of modular arms: an actuator module's ``drive:`` (armature, damping, Coulomb friction),
carried into the assembled URDF, robot and box, and through the demo's simulations.

The references are read from the module files with plain ``yaml`` and the intervals computed
here by hand, independently of ``urpc.model.drives``.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from test_modular import ACTUATOR as PLAIN_ACTUATOR

from urpc.errors import InputError
from urpc.model.modular import assemble, load_assembly, load_module_library
from urpc.model.robot import load_robot
from urpc.model.uncertainty import load_uncertainty
from urpc.studies.demo import run_configuration, tool_change_run

ROOT = Path(__file__).resolve().parents[1]
MODULES = ROOT / "robots" / "modules"
ARM = ["base", "actuator_large", "elbow_large", "link_500", "elbow_small", "link_300"]
FIELDS = ("armature", "damping", "friction")

ACTUATOR = (
    PLAIN_ACTUATOR
    + """drive:
  armature: 30%
  damping: [0.5, 2]
  friction: [1, 3]
  nominal: {armature: 0.2, friction: 2.5}
"""
)
LINK = """
kind: link
inertial: {mass: 0.5, com_z: 0.05, ixx: 0.0005, iyy: 0.0005, izz: 0.0001}
proximal: {connector: M}
distal: {connector: M, xyz: [0, 0, 0.1]}
drive: {friction: [1, 3]}
"""


def library_with(tmp_path: Path, **extra: str) -> Path:
    folder = tmp_path / "modules"
    shutil.copytree(MODULES, folder)
    for name, text in extra.items():
        (folder / f"{name}.yaml").write_text(text)
    return folder


def expected_drive(name: str) -> np.ndarray:
    """``(3, 3)``: rows nominal, lower, upper of a shipped module's drive, by hand: ``x%`` is
    ``nominal (1 -+ x/100)``, ``[lo, hi]`` as written."""
    drive = yaml.safe_load((MODULES / f"{name}.yaml").read_text())["drive"]
    values = np.zeros((3, 3))
    for k, key in enumerate(FIELDS):
        center = float(drive["nominal"][key])
        entry = drive[key]
        if isinstance(entry, str):
            fraction = float(entry.rstrip("%")) / 100
            lo, hi = center * (1 - fraction), center * (1 + fraction)
        else:
            lo, hi = map(float, entry)
        values[:, k] = center, lo, hi
    return values


# ---------------------------------------------------------------------------- the module file
def test_a_module_drive_is_read_with_its_intervals(tmp_path):
    library = load_module_library(library_with(tmp_path, geared=ACTUATOR))
    drive = library["geared"].drive
    # armature 30 % around its nominal; damping absolute, nominal the middle; friction given.
    np.testing.assert_allclose(drive.nominal, [0.2, 1.25, 2.5])
    np.testing.assert_allclose(drive.lower, [0.14, 0.5, 1.0])
    np.testing.assert_allclose(drive.upper, [0.26, 2.0, 3.0])
    assert library["link_500"].drive is None


def test_every_shipped_actuator_has_a_drive():
    library = load_module_library()
    for name in library.of_kind("actuator"):
        drive = library[name].drive
        reference = expected_drive(name)
        np.testing.assert_allclose(drive.nominal, reference[0], rtol=1e-15)
        np.testing.assert_allclose([drive.lower, drive.upper], reference[1:], rtol=1e-15)
        assert np.all(reference[1] > 0) and np.all(reference[2] > reference[1])


@pytest.mark.parametrize("kind", ["link", "base"])
def test_a_drive_on_a_module_without_a_joint_is_refused(tmp_path, kind):
    text = LINK if kind == "link" else "kind: base\ninertial: {mass: 1}\n"
    text += "distal: {connector: L}\n" if kind == "base" else ""
    text += "drive: {friction: [1, 3]}\n" if kind == "base" else ""
    folder = library_with(tmp_path, broken=text)
    with pytest.raises(InputError) as error:
        load_module_library(folder)
    assert error.value.source == str(folder / "broken.yaml")
    assert error.value.field == "drive"
    assert "no joint" in str(error.value)


@pytest.mark.parametrize(
    "old, new, field, words",
    [
        ("nominal: {armature: 0.2, friction: 2.5}", "nominal: {friction: 2.5}", "drive.armature",
         "relative"),
        ("damping: [0.5, 2]", "damping: [-0.5, 2]", "drive.damping", "negative"),
        ("friction: 2.5}", "friction: 4}", "drive.friction", "outside"),
        ("friction: [1, 3]", "friction: [3, 1]", "drive.friction", "greater"),
        ("armature: 30%", "armatur: 30%", "drive.armatur", "armature"),
        ("nominal: {armature: 0.2", "nominal: {armature: -0.2", "drive.nominal.armature", ">= 0"),
    ],
)  # fmt: skip
def test_bad_drives_name_the_file_and_field(tmp_path, old, new, field, words):
    assert old in ACTUATOR
    folder = library_with(tmp_path, broken=ACTUATOR.replace(old, new))
    with pytest.raises(InputError) as error:
        load_module_library(folder)
    assert error.value.source == str(folder / "broken.yaml")
    assert error.value.field == field
    assert words in str(error.value)


# ---------------------------------------------------------------------------- the assembly
def test_the_assembled_robot_and_box_carry_the_drives(tmp_path):
    assembly = assemble([*ARM, "tool_gripper", "payload_1kg"], name="arm", out_dir=tmp_path)
    robot, box = assembly.load()
    expected = np.stack(
        [expected_drive(m) for m in ("actuator_large", "elbow_large", "elbow_small")], axis=-1
    )  # (nominal/lower/upper, field, joint)
    # A loaded robot is rigid; the box's joints: section gives the nominal model its drives.
    np.testing.assert_array_equal(robot.joint_parameters, 0.0)
    np.testing.assert_allclose(box.nominal_robot(robot).joint_parameters, expected[0], rtol=1e-15)
    assert box.joints.joint_names == robot.joint_names == ("joint1", "joint2", "joint3")
    np.testing.assert_allclose(box.joints.nominal, expected[0], rtol=1e-15)
    np.testing.assert_allclose(box.joints.lower, expected[1], rtol=1e-15)
    np.testing.assert_allclose(box.joints.upper, expected[2], rtol=1e-15)
    # The URDF carries the nominal damping and friction as <dynamics> (no armature).
    np.testing.assert_array_equal(robot.urdf_dynamics, expected[0][1:])
    # The written uncertainty file holds the same joint box.
    written = load_uncertainty(assembly.uncertainty_path, load_robot(assembly.urdf_path)).joints
    for name in ("nominal", "lower", "upper"):
        np.testing.assert_array_equal(getattr(written, name), getattr(box.joints, name))


def test_an_actuator_without_a_drive_is_a_rigid_joint(tmp_path):
    folder = library_with(tmp_path, plain=PLAIN_ACTUATOR)
    chain = ["base", "actuator_large", "link_500", "plain", "link_300"]
    assembly = assemble(chain, library=folder, out_dir=tmp_path)
    robot, box = assembly.load()
    assert list(assembly.uncertainty["joints"]) == ["joint1"]
    np.testing.assert_array_equal(box.nominal_robot(robot).joint_parameters[:, 1], 0.0)
    assert not box.joints.uncertain[:, 1].any()
    assert box.joints.uncertain[:, 0].all()


# ---------------------------------------------------------------------------- the demo
def test_an_arm_with_drives_is_drawn_with_them_and_meets_epsilon():
    run = run_configuration("arm_3dof", duration=2.0, repeats=1)
    box, point = run.arm.box, run.true_point
    drawn = point.joints
    assert np.all(drawn >= box.joints.lower) and np.all(drawn <= box.joints.upper)
    assert not np.allclose(drawn, box.joints.nominal)
    np.testing.assert_array_equal(run.plant.joint_parameters, drawn)
    assert run.result.metrics["met"], run.result.metrics
    summary = run.summary()
    assert list(summary["drives"]) == ["joint1", "joint2", "joint3"]
    assert summary["drives"]["joint3"]["module"] == "elbow_small"
    assert summary["drives"]["joint1"]["friction [N m]"]["interval"] == [2.0, 6.0]
    assert "joint3 drive: armature" in summary["true_parameters"]


def test_the_tool_change_keeps_the_drawn_drives():
    run = tool_change_run(duration=0.4, t_change=0.2)
    summary = run.summary()
    before, after = (summary["true_parameters"][k] for k in ("before", "after"))
    drives = [text[text.index("joint1 drive") :] for text in (before, after)]
    assert drives[0] == drives[1]
    assert before.split("payload: ")[1][:20] != after.split("payload: ")[1][:20]
    assert list(summary["drives"]) == ["joint1", "joint2", "joint3", "joint4"]
    assert summary["met"]


def test_assemblies_without_drives_still_load(tmp_path):
    folder = tmp_path / "modules"
    shutil.copytree(MODULES, folder)
    for path in folder.glob("*.yaml"):
        text = path.read_text()
        if "\ndrive:" in text:
            head, tail = text.split("\ndrive:", 1)
            rest = tail.split("\nproximal:", 1)[1]
            path.write_text(head + "\nproximal:" + rest)
    assembly = load_assembly("arm_3dof", library=folder, out_dir=tmp_path)
    robot, box = assembly.load()
    assert "joints" not in assembly.uncertainty
    np.testing.assert_array_equal(box.nominal_robot(robot).joint_parameters, 0.0)
    assert box.joints is None or not box.joints.active
