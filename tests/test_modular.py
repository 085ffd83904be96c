"""Modular arms: module files, composition into one URDF and one box, errors.

The references here are independent of ``urpc.model.modular``: the module files are read with plain
``yaml``, the equivalent URDF is written by hand (module frames reached through chains of
single-axis fixed joints, so no transform is composed in the test), and Pinocchio compares the
dynamics.
"""

from __future__ import annotations

import itertools
import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from urpc.errors import InputError
from urpc.model.inertia import inertia_problem
from urpc.model.modular import assemble, load_assembly, load_module_library
from urpc.model.robot import load_robot
from urpc.model.uncertainty import PHYSICAL_FIELDS, load_uncertainty, physical_coordinates

ROOT = Path(__file__).resolve().parents[1]
MODULES = ROOT / "robots" / "modules"
ASSEMBLIES = ROOT / "robots" / "assemblies"
ARM = ["base", "actuator_large", "elbow_large", "link_500", "elbow_small", "link_300"]
INERTIA_FIELDS = ("ixx", "ixy", "iyy", "ixz", "iyz", "izz")


def module_doc(name: str) -> dict:
    return yaml.safe_load((MODULES / f"{name}.yaml").read_text())


def nominal(doc: dict) -> dict[str, float]:
    return {key: float(doc["inertial"].get(key, 0.0)) for key in PHYSICAL_FIELDS}


# ---------------------------------------------------------------------------- hand-written URDF
def _numbers(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def _origin(xyz=(0, 0, 0), rpy=(0, 0, 0)) -> str:
    return f'<origin xyz="{_numbers(xyz)}" rpy="{_numbers(rpy)}"/>'


def _inertial(values: dict[str, float]) -> str:
    v = values
    return (
        f"<inertial>{_origin((v['com_x'], v['com_y'], v['com_z']))}"
        f'<mass value="{v["mass"]!r}"/>'
        f'<inertia ixx="{v["ixx"]!r}" ixy="{v["ixy"]!r}" ixz="{v["ixz"]!r}" '
        f'iyy="{v["iyy"]!r}" iyz="{v["iyz"]!r}" izz="{v["izz"]!r}"/></inertial>'
    )


def _fixed(name: str, parent: str, child: str, origin: str) -> str:
    return (
        f'<joint name="{name}" type="fixed"><parent link="{parent}"/><child link="{child}"/>'
        f"{origin}</joint>"
    )


def hand_written_urdf(chain: list[str], payload: str | None = None) -> str:
    """The URDF of ``chain`` written from the module files.

    Between two modules: the parent's output frame (its xyz, rpy verbatim), then the inverse of
    the child's input frame ``(Trans(t) Rz Ry Rx)^-1 = Rx(-r) Ry(-p) Rz(-y) Trans(-t)`` as three
    single-axis fixed joints and a translation, the last one being the actuator's joint.
    """
    parts = ['<robot name="by_hand">']
    previous, previous_doc = None, None
    for i, name in enumerate(chain):
        doc = module_doc(name)
        link = f"body{i}"
        parts.append(f'<link name="{link}">{_inertial(nominal(doc))}</link>')
        if previous is not None:
            distal, proximal = previous_doc["distal"], doc["proximal"]
            r, p, y = proximal["rpy"]
            chain_links = [f"flange{i}", f"flange{i}_r", f"flange{i}_rp", f"flange{i}_rpy"]
            origins = [
                _origin(distal["xyz"], distal["rpy"]),
                _origin(rpy=(-r, 0, 0)),
                _origin(rpy=(0, -p, 0)),
                _origin(rpy=(0, 0, -y)),
            ]
            parent = previous
            for child, origin in zip(chain_links, origins, strict=True):
                parts.append(f'<link name="{child}"/>')
                parts.append(_fixed(f"{child}_joint", parent, child, origin))
                parent = child
            last = _origin([-c for c in proximal["xyz"]])
            if doc["kind"] == "actuator":
                joint = doc["joint"]
                parts.append(
                    f'<joint name="hand_joint{i}" type="revolute"><parent link="{parent}"/>'
                    f'<child link="{link}"/>{last}<axis xyz="{" ".join(map(str, joint["axis"]))}"/>'
                    f'<limit lower="{joint["lower"]}" upper="{joint["upper"]}" '
                    f'effort="{joint["effort"]}" velocity="{joint["velocity"]}"/></joint>'
                )
            else:
                parts.append(_fixed(f"body{i}_joint", parent, link, last))
        previous, previous_doc = link, doc
    end = previous_doc["distal"]
    parts.append('<link name="hand_tcp"/>')
    parts.append(_fixed("hand_tcp_joint", previous, "hand_tcp", _origin(end["xyz"], end["rpy"])))
    if payload is not None:
        doc = module_doc(payload)
        assert doc["proximal"]["xyz"] == [0, 0, 0] and doc["proximal"]["rpy"] == [0, 0, 0]
        parts.append(f'<link name="hand_payload">{_inertial(nominal(doc))}</link>')
        parts.append(_fixed("hand_payload_joint", "hand_tcp", "hand_payload", _origin()))
    parts.append("</robot>")
    return "\n".join(parts)


def random_states(model: pin.Model, rng: np.random.Generator, count: int):
    for _ in range(count):
        q = rng.uniform(model.lowerPositionLimit, model.upperPositionLimit)
        yield q, rng.normal(size=model.nv) * 2.0, rng.normal(size=model.nv) * 5.0


def assert_same_dynamics(model_a: pin.Model, model_b: pin.Model, seed: int = 0) -> None:
    assert model_a.nv == model_b.nv
    data_a, data_b = model_a.createData(), model_b.createData()
    for q, qd, qdd in random_states(model_a, np.random.default_rng(seed), 20):
        Ma, Mb = pin.crba(model_a, data_a, q), pin.crba(model_b, data_b, q)
        np.testing.assert_allclose(np.triu(Ma), np.triu(Mb), rtol=0, atol=1e-10)
        np.testing.assert_allclose(
            pin.computeGeneralizedGravity(model_a, data_a, q),
            pin.computeGeneralizedGravity(model_b, data_b, q),
            rtol=0,
            atol=1e-10,
        )
        np.testing.assert_allclose(
            pin.computeCoriolisMatrix(model_a, data_a, q, qd),
            pin.computeCoriolisMatrix(model_b, data_b, q, qd),
            rtol=0,
            atol=1e-10,
        )
        np.testing.assert_allclose(
            pin.rnea(model_a, data_a, q, qd, qdd),
            pin.rnea(model_b, data_b, q, qd, qdd),
            rtol=0,
            atol=1e-10,
        )


def test_dynamics_equal_a_hand_written_urdf(tmp_path):
    assembly = assemble(ARM, name="arm", out_dir=tmp_path)
    robot = load_robot(assembly.urdf_path)
    by_hand = pin.buildModelFromXML(hand_written_urdf(ARM))
    assert robot.dof == by_hand.nv == 3
    assert_same_dynamics(robot.model, by_hand)
    np.testing.assert_array_equal(robot.effort_limit, by_hand.effortLimit)
    np.testing.assert_array_equal(robot.velocity_limit, by_hand.velocityLimit)
    # The kinematics too: the TCP frame at random configurations.
    data, hand_data = robot.model.createData(), by_hand.createData()
    tcp, hand_tcp = robot.model.getFrameId("tcp"), by_hand.getFrameId("hand_tcp")
    for q, _, _ in random_states(by_hand, np.random.default_rng(1), 10):
        pin.framesForwardKinematics(robot.model, data, q)
        pin.framesForwardKinematics(by_hand, hand_data, q)
        np.testing.assert_allclose(
            data.oMf[tcp].homogeneous, hand_data.oMf[hand_tcp].homogeneous, atol=1e-12
        )


def test_arm_is_three_dimensional(tmp_path):
    robot = load_robot(assemble(ARM, name="arm", out_dir=tmp_path).urdf_path)
    data = robot.model.createData()
    pin.computeJointJacobians(robot.model, data, np.array([0.3, 0.4, -0.5]))
    axes = [data.oMi[j].rotation @ [0, 0, 1] for j in (1, 2, 3)]
    np.testing.assert_allclose(axes[0], [0, 0, 1], atol=1e-12)  # yaw about the vertical
    assert abs(axes[0] @ axes[1]) < 1e-12  # shoulder pitch perpendicular to it
    np.testing.assert_allclose(np.cross(axes[1], axes[2]), 0, atol=1e-12)  # elbow parallel


def test_payload_is_the_box_payload_at_the_tcp(tmp_path):
    chain = [*ARM, "tool_gripper", "payload_1kg"]
    robot, box = assemble(chain, name="arm", out_dir=tmp_path).load()
    assert [(p.name, p.link) for p in box.payloads] == [("payload", "tcp")]
    assert "payload" not in robot.link_names  # the URDF holds no payload
    by_hand = pin.buildModelFromXML(hand_written_urdf(chain[:-1], payload="payload_1kg"))
    # The nominal model carries the drives' armature, which a URDF cannot hold.
    actuators = [name for name in chain if module_doc(name)["kind"] == "actuator"]
    by_hand.armature = np.array([module_doc(n)["drive"]["nominal"]["armature"] for n in actuators])
    assert_same_dynamics(box.nominal_robot(robot).model, by_hand)
    doc = module_doc("payload_1kg")
    payload_box = box.link_box("payload")
    assert payload_box.lower[0] == doc["uncertainty"]["mass"][0] == 0.8
    assert payload_box.upper[0] == doc["uncertainty"]["mass"][1] == 1.2
    k = PHYSICAL_FIELDS.index("com_z")
    assert (payload_box.lower[k], payload_box.upper[k]) == tuple(doc["uncertainty"]["com_z"])


# ---------------------------------------------------------------------------- the combined box
def expected_interval(spec, value: float) -> tuple[float, float]:
    """The interval forms used by the shipped modules, evaluated independently."""
    if isinstance(spec, list):
        return float(spec[0]), float(spec[1])
    text = str(spec)
    if text.endswith("%"):
        fraction = float(text[:-1]) / 100
        return value - abs(value) * fraction, value + abs(value) * fraction
    assert text.startswith("+-")
    return value - float(text[2:]), value + float(text[2:])


def test_each_module_box_lands_on_its_link(tmp_path):
    chain = ["base", "actuator_large", "elbow_large", "link_500", "elbow_small", "link_300"]
    chain += ["elbow_small", "tool_gripper"]
    assembly = assemble(chain, name="arm", out_dir=tmp_path)
    robot, box = assembly.load()
    links = {part.link: part.module for part in assembly.parts}
    assert sorted(b.link for b in box.links) == sorted(name for name in links if name != "m0_base")
    for link_box in box.links:
        doc = module_doc(links[link_box.link])
        values = nominal(doc)
        for k, key in enumerate(PHYSICAL_FIELDS):
            expected = values[key], values[key]
            if key in doc["uncertainty"]:
                expected = expected_interval(doc["uncertainty"][key], values[key])
            assert link_box.nominal[k] == pytest.approx(values[key], abs=1e-15)
            assert (link_box.lower[k], link_box.upper[k]) == pytest.approx(expected, abs=1e-15)


def test_modules_fixed_to_the_world_are_not_in_the_box(tmp_path):
    # The adapter sits between the base and the first joint: its mass never enters M, C, g.
    chain = ["base", "adapter_l_m", "actuator_small", "link_300", "tool_vacuum"]
    assembly = assemble(chain, name="small", out_dir=tmp_path)
    robot, box = assembly.load()
    assert robot.dof == 1
    assert sorted(b.link for b in box.links) == [
        "m2_actuator_small",
        "m3_link_300",
        "m4_tool_vacuum",
    ]
    assert "payload" not in assembly.uncertainty


def test_the_written_file_is_the_document(tmp_path):
    assembly = load_assembly(ASSEMBLIES / "arm_4dof.yaml", out_dir=tmp_path)
    robot, box = assembly.load()
    from_file = load_uncertainty(assembly.uncertainty_path, robot)
    assert yaml.safe_load(assembly.uncertainty_path.read_text()) == assembly.uncertainty
    assert [b.link for b in from_file.links] == [b.link for b in box.links]
    for a, b in zip(from_file.links, box.links, strict=True):
        np.testing.assert_array_equal(a.lower, b.lower)
        np.testing.assert_array_equal(a.upper, b.upper)
        np.testing.assert_array_equal(a.nominal, b.nominal)
    assert from_file.payloads == box.payloads


ROTATED_PAYLOAD = """
kind: payload
inertial: {mass: 2.0, com_x: 0.01, com_y: -0.01, com_z: 0.05, ixx: 0.004, iyy: 0.003, izz: 0.002,
           ixy: 0.0002}
proximal: {connector: tcp, xyz: [0.02, -0.01, 0.005], rpy: [0, 0, 1.5707963267948966]}
uncertainty:
  mass: [1.5, 2.5]
  com_x: [0.0, 0.02]
  com_y: [-0.03, 0.01]
  com_z: +-0.01
  ixx: [0.0035, 0.0045]
  iyy: [0.0028, 0.0032]
  ixy: [0.0001, 0.0003]
"""


def copied_library(tmp_path: Path, **extra: str) -> Path:
    folder = tmp_path / "modules"
    shutil.copytree(MODULES, folder)
    for name, text in extra.items():
        (folder / f"{name}.yaml").write_text(text)
    return folder


def test_a_rotated_payload_box_is_mapped_into_the_tcp_frame(tmp_path):
    folder = copied_library(tmp_path, payload_turned=ROTATED_PAYLOAD)
    chain = ["base", "actuator_large", "link_500", "actuator_small", "tool_gripper"]
    robot, box = assemble([*chain, "payload_turned"], library=folder, out_dir=tmp_path).load()
    payload_box = box.link_box("payload")
    # Reference: Pinocchio moves the payload's inertia into the TCP frame at every box corner.
    doc = yaml.safe_load(ROTATED_PAYLOAD)
    proximal = pin.SE3(
        pin.rpy.rpyToMatrix(np.array(doc["proximal"]["rpy"])), np.array(doc["proximal"]["xyz"])
    )
    payload_in_tcp = proximal.inverse()
    values = nominal(doc)
    ranges = [
        expected_interval(doc["uncertainty"].get(k, [values[k]] * 2), values[k])
        for k in PHYSICAL_FIELDS
    ]
    corners = np.array(
        [physical_coordinates(payload_in_tcp.act(_inertia(c))) for c in itertools.product(*ranges)]
    )
    np.testing.assert_allclose(payload_box.lower, corners.min(axis=0), atol=1e-15)
    np.testing.assert_allclose(payload_box.upper, corners.max(axis=0), atol=1e-15)
    center = physical_coordinates(
        payload_in_tcp.act(_inertia([values[k] for k in PHYSICAL_FIELDS]))
    )
    np.testing.assert_allclose(payload_box.nominal, center, atol=1e-15)


def test_a_payload_box_must_be_physical(tmp_path):
    text = ROTATED_PAYLOAD.split("uncertainty:")[0] + "uncertainty:\n  barycentric: {m: 10%}\n"
    folder = copied_library(tmp_path, payload_bary=text)
    with pytest.raises(InputError) as error:
        load_module_library(folder)
    assert error.value.field == "uncertainty.barycentric"


def _inertia(values) -> pin.Inertia:
    m, cx, cy, cz, ixx, ixy, iyy, ixz, iyz, izz = values
    return pin.Inertia(
        m, np.array([cx, cy, cz]), np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    )


# ---------------------------------------------------------------------------- shipped assemblies
@pytest.mark.parametrize("name, dof", [("arm_3dof", 3), ("arm_4dof", 4), ("arm_4dof_vacuum", 4)])
def test_shipped_assemblies_load_and_are_non_degenerate(tmp_path, name, dof):
    assembly = load_assembly(ASSEMBLIES / f"{name}.yaml", out_dir=tmp_path)
    robot, box = assembly.load()
    assert assembly.name == robot.name == name
    assert robot.dof == assembly.dof == dof
    assert robot.joint_names == tuple(f"joint{k}" for k in range(1, dof + 1))
    assert [p.name for p in box.payloads] == ["payload"]
    # The heaviest corner of the box (every coordinate at its upper end, a physical body for the
    # shipped modules) must be held statically within the actuators' effort limits.
    heaviest = box.plant(robot, {b.link: b.upper for b in box.links})
    rng = np.random.default_rng(2)
    lower, upper = robot.position_limits
    for _ in range(50):
        q = rng.uniform(lower, upper)
        for plant in (box.nominal_robot(robot), heaviest):
            assert np.linalg.eigvalsh(plant.M(q)).min() > 1e-3  # positive definite
            gravity = plant.g(q)
            assert np.all(np.abs(gravity) <= robot.effort_limit)
        assert np.count_nonzero(np.abs(box.nominal_robot(robot).g(q)) > 1e-3) >= 2


def test_shipped_assemblies_load_by_name(tmp_path):
    by_name = load_assembly("arm_3dof", out_dir=tmp_path)
    assert by_name.modules == (*ARM, "tool_gripper", "payload_1kg")
    assert by_name.uncertainty == load_assembly(ASSEMBLIES / "arm_3dof.yaml").uncertainty
    with pytest.raises(InputError, match="did you mean 'arm_3dof'"):
        load_assembly("arm_3dfo", out_dir=tmp_path)


def test_parts_name_the_urdf_links_and_joints(tmp_path):
    import yourdfpy

    assembly = load_assembly(ASSEMBLIES / "arm_3dof.yaml", out_dir=tmp_path)
    urdf = yourdfpy.URDF.load(str(assembly.urdf_path), build_scene_graph=False, load_meshes=False)
    joints = {joint.name: joint for joint in urdf.robot.joints}
    assert assembly.modules == tuple(
        yaml.safe_load((ASSEMBLIES / "arm_3dof.yaml").read_text())["modules"]
    )
    for part in assembly.parts[1:-1]:
        joint = joints[part.joint]
        assert joint.child == part.link
        assert joint.type == ("revolute" if part.kind == "actuator" else "fixed")
    assert assembly.parts[-1].kind == "payload" and assembly.parts[-1].joint is None
    assert {link.name for link in urdf.robot.links} == {
        *(p.link for p in assembly.parts[:-1]),
        "tcp",
    }


# ---------------------------------------------------------------------------- module files
def test_module_inertias_follow_their_shapes():
    """Tubes: thin-walled formula from the density; cylinders and boxes: solid bodies."""
    library = load_module_library()
    assert {"base", "tool_gripper", "payload_1kg"} <= set(library)
    assert len(library.of_kind("actuator")) >= 4 and len(library.of_kind("link")) >= 3
    for name in library:
        doc = module_doc(name)
        values, shape = nominal(doc), doc["shape"]
        m = values["mass"]
        if "tube" in shape:
            r, t, L, rho = (shape["tube"][k] for k in ("radius", "wall", "length", "density"))
            m = rho * 2 * np.pi * r * t * L
            expected = {"ixx": m * (r**2 / 2 + L**2 / 12), "izz": m * r**2}
            expected["iyy"] = expected["ixx"]
        elif "cylinder" in shape:
            r, h = shape["cylinder"]["radius"], shape["cylinder"]["length"]
            expected = {"ixx": m * (3 * r**2 + h**2) / 12, "izz": m * r**2 / 2}
            expected["iyy"] = expected["ixx"]
        else:
            a, b, c = shape["box"]["size"]
            expected = {
                "ixx": m * (b**2 + c**2) / 12,
                "iyy": m * (a**2 + c**2) / 12,
                "izz": m * (a**2 + b**2) / 12,
            }
        expected.update(mass=m, ixy=0.0, ixz=0.0, iyz=0.0)
        expected.update(zip(("com_x", "com_y", "com_z"), shape.get("xyz", [0, 0, 0]), strict=True))
        for key, value in expected.items():  # the files give 8 significant digits
            assert values[key] == pytest.approx(value, rel=1e-7, abs=1e-12), (name, key)


def test_every_corner_of_every_module_box_is_a_physical_body():
    for module in load_module_library().modules.values():
        if module.box is None:
            continue
        uncertain = [k for k in range(4, 10) if module.box.uncertain[k]]
        for corner in itertools.product(*[(0, 1)] * len(uncertain)):
            values = module.box.nominal.copy()
            for k, upper in zip(uncertain, corner, strict=True):
                values[k] = module.box.upper[k] if upper else module.box.lower[k]
            tensor = np.asarray(module.box.inertia(values).inertia)
            assert inertia_problem(tensor) is None, (module.name, corner)


def test_the_library_is_read_once_and_again_after_a_change(tmp_path):
    assert load_module_library() is load_module_library()
    folder = copied_library(tmp_path)
    first = load_module_library(folder)
    assert load_module_library(folder) is first
    (folder / "payload_2kg.yaml").write_text((MODULES / "payload_3kg.yaml").read_text())
    second = load_module_library(folder)
    assert second is not first and "payload_2kg" in second


# ---------------------------------------------------------------------------- errors
@pytest.mark.parametrize(
    "chain, field, words",
    [
        ([], "modules", ["empty", "actuator_large"]),
        (
            ["base", "actuator_lrge"],
            "modules[1]",
            ["unknown module", "did you mean 'actuator_large'"],
        ),
        (
            ["base", "actuator_small"],
            "modules[1]",
            [
                "'actuator_small' (input connector 'M')",
                "'base' (output connector 'L')",
                "actuator_large",
            ],
        ),
        (["base", "link_500", "tool_gripper"], "modules", ["no joint", "actuator_large"]),
        (
            ["base", "actuator_large", "link_500", "tool_gripper", "payload_1kg", "payload_3kg"],
            "modules[4]",
            ["must be the last module"],
        ),
        (["actuator_large", "link_500"], "modules[0]", ["starts with a base"]),
        (["base", "actuator_large", "base"], "modules[2]", ["only the first module may be a base"]),
    ],
)
def test_bad_assemblies_are_refused_with_a_clear_message(tmp_path, chain, field, words):
    with pytest.raises(InputError) as error:
        assemble(chain, out_dir=tmp_path)
    assert error.value.field == field
    for word in words:
        assert word in str(error.value)


def test_bad_arguments_are_refused(tmp_path):
    with pytest.raises(InputError, match="list of module names"):
        assemble("base", out_dir=tmp_path)
    with pytest.raises(InputError, match="assembly name"):
        assemble(["base", "actuator_large"], name="my arm", out_dir=tmp_path)


def test_assembly_file_errors_name_the_file_and_field(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("modules: [base, actuator_large, link_50]\n")
    with pytest.raises(InputError) as error:
        load_assembly(path, out_dir=tmp_path)
    assert error.value.source == str(path) and error.value.field == "modules[2]"
    assert "did you mean 'link_500'" in str(error.value)
    path.write_text("modulez: [base]\n")
    with pytest.raises(InputError, match="did you mean 'modules'"):
        load_assembly(path, out_dir=tmp_path)


ACTUATOR = """
kind: actuator
inertial: {mass: 1.0, ixx: 0.001, iyy: 0.001, izz: 0.001}
joint: {axis: [0, 0, 1], lower: -1, upper: 1, effort: 10, velocity: 1}
proximal: {connector: M}
distal: {connector: M, xyz: [0, 0, 0.1]}
uncertainty: {mass: 5%}
"""


@pytest.mark.parametrize(
    "old, new, field",
    [
        ("kind: actuator", "kind: actuatr", "kind"),
        ("joint: {axis: [0, 0, 1], lower: -1, upper: 1, effort: 10, velocity: 1}", "", "joint"),
        ("proximal: {connector: M}", "proximal: {xyz: [0, 0, 0]}", "proximal.connector"),
        ("izz: 0.001", "izz: 0.003", "inertial"),  # triangle inequality violated
        ("mass: 5%", "mass: [2, 3]", "uncertainty.mass"),  # nominal outside the box
        ("lower: -1", "lower: 2", "joint.lower"),
        ("distal: {connector: M", "distal: {conector: M", "distal.conector"),
    ],
)
def test_bad_module_files_name_the_file_and_field(tmp_path, old, new, field):
    assert old in ACTUATOR
    folder = copied_library(tmp_path, broken=ACTUATOR.replace(old, new))
    with pytest.raises(InputError) as error:
        load_module_library(folder)
    assert error.value.source == str(folder / "broken.yaml")
    assert error.value.field == field


def test_mujoco_reads_the_same_dynamics_from_the_urdf(tmp_path):
    """A second, independent reader of the generated URDF (the simulation cross-check)."""
    mujoco = pytest.importorskip("mujoco")
    assembly = load_assembly(ASSEMBLIES / "arm_4dof_vacuum.yaml", out_dir=tmp_path)
    robot = load_robot(assembly.urdf_path)
    model = mujoco.MjModel.from_xml_path(str(assembly.urdf_path))
    data = mujoco.MjData(model)
    assert model.nv == robot.dof
    for q, _, _ in random_states(robot.model, np.random.default_rng(3), 10):
        data.qpos[:] = q
        mujoco.mj_forward(model, data)
        M = np.zeros((model.nv, model.nv))
        try:
            mujoco.mj_fullM(model, data, M)  # recent MuJoCo
        except TypeError:
            mujoco.mj_fullM(model, M, data.qM)
        np.testing.assert_allclose(M, robot.M(q), atol=1e-10)
        np.testing.assert_allclose(data.qfrc_bias, robot.g(q), atol=1e-10)  # qd = 0
