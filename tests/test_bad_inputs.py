"""The bad-input catalog: every malformed input gives one clear error, through the API (a typed
exception) and through the CLI (exit code 2, one stderr line starting with 'error:', no traceback,
naming the file and the field), and leaves no partial output behind.

Each case builds its files in a temporary folder, then states the CLI arguments, the API call and
the words the message must contain.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from conftest import RR_DIR

import urpc
from urpc.cli import main
from urpc.errors import InputError, UrpcError

RR_URDF = (RR_DIR / "rr_planar.urdf").read_text()
RR_BOX = (RR_DIR / "uncertainty.yaml").read_text()


def _rr_with(old: str, new: str) -> str:
    assert old in RR_URDF, old
    return RR_URDF.replace(old, new, 1)


LINK2_INERTIA = (
    '<inertia ixx="1.6666666666666667" ixy="0" ixz="0"\n'
    '               iyy="0.4166666666666667" iyz="0" izz="1.6666666666666667"/>'
)
LINK2_MASS = '<mass value="5.0"/>'
LINK2_INERTIAL = RR_URDF[RR_URDF.index("<inertial>", RR_URDF.index('<link name="link2">')) :]
LINK2_INERTIAL = LINK2_INERTIAL[: LINK2_INERTIAL.index("</inertial>") + len("</inertial>")]


@dataclass
class Case:
    """One bad input: files to write, the CLI arguments and the API call that must fail."""

    files: dict[str, str]
    argv: list[str]
    api: Callable[[Path], object] | None
    words: tuple[str, ...]
    exception: type[Exception] = InputError
    names_file: str | None = None  # the file the message must name (default: the first file)
    extra: dict = field(default_factory=dict)


def _check(robot: str, box: str | None = None) -> list[str]:
    argv = ["check", robot]
    return argv + (["--uncertainty", box] if box else [])


def _bound(*vectors: str, method: str | None = None) -> list[str]:
    argv = ["bound", "rr_planar"]
    for name, value in zip(("--q", "--qd", "--qd-a", "--qdd-a"), vectors, strict=True):
        argv += [name, value]
    return argv + (["--method", method] if method else [])


def _enclose(q, qd, qd_a, qdd_a, method: str = "vertex"):
    """The API twin of :func:`_bound`: ``enclose`` on the RR arm's shipped box."""

    def call(tmp: Path):
        robot = urpc.load_robot("rr_planar")
        box = urpc.load_uncertainty(RR_DIR / "uncertainty.yaml", robot)
        vectors = (np.array(v, dtype=float) for v in (q, qd, qd_a, qdd_a))
        return urpc.make_bound(method, robot, box).enclose(*vectors)

    return call


def _load_box(robot_path: str, box_path: str):
    def call(tmp: Path):
        robot = urpc.load_robot(tmp / robot_path if robot_path.endswith(".urdf") else robot_path)
        return urpc.load_uncertainty(tmp / box_path, robot)

    return call


def _box_case(text: str, *words: str) -> Case:
    return Case(
        {"box.yaml": text},
        _check("rr_planar", "{tmp}/box.yaml"),
        _load_box("rr_planar", "box.yaml"),
        words,
    )


def _urdf_case(text: str, *words: str) -> Case:
    return Case(
        {"arm.urdf": text},
        _check("{tmp}/arm.urdf"),
        lambda tmp: urpc.load_robot(tmp / "arm.urdf"),
        words,
    )


ZERO_INERTIA = '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>'

CASES: dict[str, Case] = {
    # ---------------------------------------------------------------- URDF files
    "urdf_missing": Case({}, _check("{tmp}/none.urdf"), lambda tmp: urpc.load_robot(tmp / "none.urdf"), ("does not exist",), names_file="none.urdf"),
    "urdf_malformed_xml": _urdf_case(RR_URDF[:-40], "malformed XML"),
    "urdf_not_a_robot": _urdf_case("<html><body/></html>", "not a URDF", "<robot name=...>"),
    "urdf_empty_file": _urdf_case("", "malformed XML"),
    "urdf_floating_base": _urdf_case(_rr_with('name="joint1" type="revolute"', 'name="joint1" type="floating"'), "joint 'joint1'", "'floating'", "revolute"),
    "urdf_planar_joint": _urdf_case(_rr_with('name="joint2" type="revolute"', 'name="joint2" type="planar"'), "joint 'joint2'", "'planar'"),
    "urdf_link_without_inertial": _urdf_case(_rr_with(LINK2_INERTIAL, ""), "joint 'joint2' moves no mass", "<inertial>"),
    "urdf_zero_mass": _urdf_case(_rr_with(LINK2_MASS, '<mass value="0"/>').replace(LINK2_INERTIA, ZERO_INERTIA), "joint 'joint2' moves no mass"),
    "urdf_negative_mass": _urdf_case(_rr_with(LINK2_MASS, '<mass value="-5"/>'), "link.link2.inertial", ">= 0"),
    "urdf_inertia_not_psd": _urdf_case(_rr_with(LINK2_INERTIA, '<inertia ixx="1" ixy="0" ixz="0" iyy="-1" iyz="0" izz="1"/>'), "link.link2.inertial", "positive semi-definite"),
    "urdf_inertia_slightly_negative": _urdf_case(_rr_with(LINK2_INERTIA, '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="-1e-10"/>'), "link.link2.inertial", "principal moment", "-1e-10"),
    "urdf_limit_lower_above_upper": _urdf_case(_rr_with('lower="-6.283185307179586" upper="6.283185307179586"', 'lower="1" upper="-1"'), "joint.joint1.limit", "lower 1", "upper -1"),
    "urdf_joint_to_unknown_link": _urdf_case(_rr_with('<parent link="link1"/>', '<parent link="link9"/>'), "joint.joint2.parent", "unknown link 'link9'", "link1"),
    "urdf_mass_not_a_number": _urdf_case(_rr_with(LINK2_MASS, '<mass value="heavy"/>'), "link.link2.inertial.mass.value", '"heavy"', "not a number"),
    "robot_unknown_name": Case({}, _check("ur55"), lambda tmp: urpc.load_robot("ur55"), ("unknown robot 'ur55'", "did you mean"), names_file=""),
    "urdf_mimic_joint": _urdf_case(_rr_with('<child link="link2"/>', '<child link="link2"/>\n    <mimic joint="joint1" multiplier="1" offset="0"/>'), "joint.joint2.mimic", "'joint2' mimics joint 'joint1'", "lock both"),
    "urdf_mimic_joint_panda": Case({}, ["check", "panda"], lambda tmp: urpc.load_robot("panda"), ("panda.urdf", "'panda_finger_joint2' mimics", "--lock panda_finger_joint1,panda_finger_joint2"), names_file=""),
    "urdf_mimic_joint_half_locked": Case({}, ["check", "panda", "--lock", "panda_finger_joint2"], lambda tmp: urpc.load_robot("panda", locked_joints=["panda_finger_joint2"]), ("mimics", "lock both"), names_file=""),
    "urdf_closed_loop_two_parents": _urdf_case(_rr_with('<link name="tool"/>', '<link name="tool"/>\n<joint name="closing" type="revolute"><parent link="tool"/><child link="link1"/><axis xyz="0 -1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'), "closed kinematic loop", "'link1' is the child of joints 'joint1' and 'closing'"),
    "urdf_closed_loop_cycle": _urdf_case(_rr_with('<link name="tool"/>', '<link name="tool"/>\n<joint name="closing" type="fixed"><parent link="tool"/><child link="base_link"/></joint>'), "closed kinematic loop", "cycle"),
    "locked_joint_by_name_outside_limits": Case({"arm.urdf": _rr_with('lower="-6.283185307179586" upper="6.283185307179586"', 'lower="0.33" upper="2.0"')}, ["check", "{tmp}/arm.urdf", "--lock", "joint1"], lambda tmp: urpc.load_robot(tmp / "arm.urdf", locked_joints=["joint1"]), ("cannot lock joint 'joint1' at 0", "[0.33, 2]", "locked_joints.joint1")),
    "locked_joint_value_outside_limits_api": Case({}, ["check", "panda", "--lock", "panda_finger_joint1,panda_finger_joint2,panda_joint4"], lambda tmp: urpc.load_robot("panda", locked_joints={"panda_finger_joint1": 0, "panda_finger_joint2": 0, "panda_joint4": 10.0}), ("cannot lock joint 'panda_joint4' at", "outside its limits"), names_file=""),
    "locked_joint_unknown": Case({}, ["check", "panda", "--lock", "panda_finger"], lambda tmp: urpc.load_robot("panda", locked_joints=["panda_finger"]), ("cannot lock unknown joint", "panda_finger_joint1"), names_file=""),
    # ---------------------------------------------------------------- uncertainty files
    "box_missing_file": Case({}, _check("rr_planar", "{tmp}/none.yaml"), _load_box("rr_planar", "none.yaml"), ("does not exist",), names_file="none.yaml"),
    "box_is_a_folder": Case({}, _check("rr_planar", "{tmp}"), lambda tmp: urpc.load_uncertainty(tmp, urpc.load_robot("rr_planar")), ("is a folder, not a file",), names_file=""),
    "urdf_is_a_folder": Case({}, _check("{tmp}"), lambda tmp: urpc.load_robot(tmp), ("field 'robot'", "is a folder, not a file"), names_file=""),
    "true_parameters_is_a_folder": Case({}, ["simulate", "--robot", "rr_planar", "--true-params", "{tmp}", "--duration", "0.01"], None, ("field 'true_parameters'", "is a folder, not a file"), names_file=""),
    "box_yaml_syntax": _box_case("links:\n  link2:\n    mass: [5, 10\n", "YAML syntax error at line"),
    "box_yaml_tabs": _box_case("links:\n\tlink2: {}\n", "YAML syntax error"),
    "box_top_level_list": _box_case("- link2\n", "expected a mapping"),
    "box_lo_greater_than_hi": _box_case("links: {link2: {mass: [10, 5]}}", "links.link2.mass", "greater than"),
    "box_zero_mass": _box_case("links: {link2: {mass: [0, 10]}}", "links.link2.mass", "strictly positive"),
    "box_nominal_outside": _box_case("links: {link2: {com_x: [0.6, 0.7]}}", "links.link2.com_x", "outside the box"),
    "box_unknown_link": _box_case("links: {link9: {mass: 10%}}", "links.link9", "link1, link2"),
    "box_unknown_key": _box_case("links: {link2: {mas: 10%}}", "links.link2.mas", "did you mean 'mass'"),
    "box_unknown_barycentric_key": _box_case("links: {link2: {barycentric: {mx: 1%}}}", "links.link2.barycentric.mx", "h_x"),
    "box_wrong_type": _box_case("links: {link2: {mass: heavy}}", "links.link2.mass", "not a number"),
    "box_three_ends": _box_case("links: {link2: {mass: [1, 2, 3]}}", "links.link2.mass", "3 entries"),
    "box_infinite_end": _box_case("links: {link2: {mass: [5, .inf]}}", "links.link2.mass", "non-finite"),
    "box_negative_width": _box_case("links: {link2: {mass: '-10%'}}", "links.link2.mass", "negative width"),
    "box_bad_disturbance": _box_case("disturbance: lots", "disturbance", "'unknown'"),
    "box_payload_unknown_link": _box_case("payload: {link: hand, mass: [0, 1]}", "payload.link", "link1, link2"),
    "box_payload_name_clash": _box_case("payload: {name: link1, link: link2, mass: [0, 1]}", "payload.name", "already a link"),
    "box_non_physical_nominal": Case(
        {"arm.urdf": _rr_with(LINK2_INERTIA, '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="1"/>'), "box.yaml": "links: {link2: {mass: [5, 10]}}"},
        _check("{tmp}/arm.urdf", "{tmp}/box.yaml"), _load_box("arm.urdf", "box.yaml"), ("links.link2", "triangle inequality"), names_file="box.yaml",
    ),
    # ------------------------------------------- boxes that describe no rigid body (issue 10.3)
    "box_negative_principal_moment": _box_case("links: {link2: {ixx: [-1, 2]}}", "links.link2.ixx", "'link2'", "lower end -1 of ixx is negative", "no rigid body"),
    "box_negative_mass_end_payload": _box_case("payload: {link: link2, mass: [-1, 3]}", "payload.mass", "non-negative"),
    "box_barycentric_negative_diagonal": _box_case("links: {link2: {barycentric: {I_yy: [-1, 20]}}}", "links.link2.barycentric.I_yy", "'link2'", "negative"),
    "box_barycentric_negative_mass": _box_case("links: {link2: {barycentric: {m: [-1, 20]}}}", "links.link2.barycentric.m", "strictly positive"),
    "box_mass_overflowing_bound": _box_case("links: {link2: {mass: [5, 1e300]}}", "links.link2", "'link2'", "too large for a finite bound", "1e+300"),
    "box_com_overflowing_bound": _box_case("links: {link2: {com_x: ['-1e200', '+1e200']}}", "links.link2", "too large for a finite bound"),
    "box_payload_without_rigid_body": _box_case("payload: {link: link2, mass: [1, 2], ixx: [0, 0.1], iyy: [0, 0.1], izz: [1, 2]}", "payload", "not physical", "triangle inequality"),
    "box_empty_file": _box_case("", "the file is empty", "links: {}"),
    "box_comment_only_file": _box_case("# nothing uncertain?\n", "the file is empty", "links: {}"),
    "box_expression_overflow": _box_case("links: {link2: {mass: ['+0', '10**10**10']}}", "links.link2.mass", "'10**10**10' overflows"),
    "box_literal_overflow": _box_case("links: {link2: {mass: 1e309}}", "links.link2.mass", "'1e309' overflows"),
    "box_disturbance_overflow": _box_case("disturbance: 1e309", "disturbance", "overflows"),
    # ------------------------------------------------- joint drives (issue 12)
    "box_joint_unknown": _box_case("joints: {joint3: {friction: [0, 1]}}", "joints.joint3", "unknown joint 'joint3'", "joint1, joint2"),
    "box_joint_unknown_key": _box_case("joints: {joint2: {frction: [0, 1]}}", "joints.joint2.frction", "did you mean 'friction'"),
    "box_joint_negative_friction": _box_case("joints: {joint2: {friction: [-1, 1]}}", "joints.joint2.friction", "negative lower end", ">= 0"),
    "box_joint_negative_armature": _box_case("joints: {joint1: {armature: ['-0.1', '+0.1']}}", "joints.joint1.armature", "negative lower end"),
    "box_joint_nominal_outside": _box_case("joints: {joint1: {damping: [1, 2], nominal: {damping: 3}}}", "joints.joint1.damping", "outside the box", "nominal"),
    "box_joint_negative_nominal": _box_case("joints: {joint1: {nominal: {friction: -1}}}", "joints.joint1.nominal.friction", ">= 0"),
    "box_joint_relative_lo_gt_hi": _box_case("joints: {joint1: {friction: [2, 1]}}", "joints.joint1.friction", "greater than"),
    # ------------------------------------------------- issue 21: hostile and unchecked inputs
    "point_joints_without_box_section": Case({"point.yaml": "joints: {joint1: {friction: 0.5}}"}, ["simulate", "--robot", "rr_planar", "--true-params", "{tmp}/point.yaml", "--duration", "0.01"], lambda tmp: urpc.load_parameter_point(tmp / "point.yaml", urpc.load_robot("rr_planar"), urpc.load_uncertainty("rr_planar", urpc.load_robot("rr_planar"))), ("joints.joint1.friction", "no 'joints:' section")),
    "point_negative_inertia": Case({"point.yaml": "links: {link2: {ixx: -1}}"}, ["simulate", "rr_planar/s3_ic1", "--no-certify", "--true-params", "{tmp}/point.yaml", "--duration", "0.01"], lambda tmp: urpc.load_parameter_point(tmp / "point.yaml", urpc.load_robot("rr_planar"), urpc.load_uncertainty("rr_planar", urpc.load_robot("rr_planar"))), ("links.link2", "not physical", "ixx = -1")),
    "identify_excite_negative_seed": Case({}, ["identify", "rr_planar", "--excite", "--out", "{tmp}/ex.csv", "--seed", "-1"], None, ("--seed", "integer >= 0"), names_file=""),
    "box_link_given_twice": _box_case("links:\n  link2: {mass: [9, 11]}\n  link2: {mass: [8, 12]}\n", "field 'links.link2'", "given twice", "lines 2 and 3"),
    "scenario_key_given_twice": Case({"s.yaml": "robot: rr_planar\nepsilon: 0.5\nepsilon: 1.0e-2\n"}, ["simulate", "{tmp}/s.yaml", "--no-certify", "--duration", "0.01"], None, ("field 'epsilon'", "given twice", "lines 2 and 3")),
    "virtual_robot_q0_outside_limits": Case({}, ["virtual-robot", "rr_planar", "--port", "0", "--wait", "1", "--q0", "100,0"], None, ("field 'q0'", "joint1 starts at 100", "outside its limits"), names_file=""),
    "virtual_robot_period_too_short": Case({}, ["virtual-robot", "rr_planar", "--port", "0", "--wait", "1", "--period", "1e-7"], None, ("field 'period'", "at least 0.0001 s"), names_file=""),
    "virtual_robot_watchdog_shorter_than_two_periods": Case({}, ["virtual-robot", "rr_planar", "--port", "0", "--wait", "1", "--watchdog-ms", "0.001"], None, ("field 'watchdog-ms'", "less than two periods"), names_file=""),
    "identify_excite_rate_below_ten_samples_per_harmonic": Case({}, ["identify", "rr_planar", "--excite", "--out", "{tmp}/ex.csv", "--rate", "1e-3"], None, ("field '--rate'", "fewer than 10 samples"), names_file=""),
    "identify_excite_out_not_csv": Case({}, ["identify", "rr_planar", "--excite", "--out", "{tmp}/ex.txt"], None, ("field '--out'", "ending in .csv"), names_file=""),
    "simulate_torque_limit_override_names_the_command_line": Case({}, ["simulate", "rr_planar/s3_ic1", "--torque-limit", "1,2,3", "--no-certify"], None, ("command-line override", "field 'torque_limit'", "3 entries"), names_file=""),
    "init_options_give_a_box_out_of_range": Case({}, ["init", "rr_planar", "--out", "{tmp}/b.yaml", "--com", "1e300"], None, ("--mass, --com, --inertia and --payload", "was not written"), names_file=""),
    "urdf_zero_axis": _urdf_case(_rr_with('<axis xyz="0 -1 0"/>', '<axis xyz="0 0 0"/>'), "joint.joint1.axis.xyz", "non-zero axis"),
    "urdf_negative_effort": _urdf_case(_rr_with('effort="1000" velocity="20"/>', 'effort="-5" velocity="20"/>'), "joint.joint1.limit.effort", "negative effort limit"),
    "urdf_negative_damping": _urdf_case(_rr_with('effort="1000" velocity="20"/>', 'effort="1000" velocity="20"/><dynamics damping="-1" friction="0"/>'), "joint.joint1.dynamics.damping", "negative damping"),
    "simulate_out_unwritable_for_root_too": Case({}, ["simulate", "rr_planar/s3_ic1", "--out", "/proc/urpc-out"], None, ("/proc/urpc-out", "cannot write the output folder"), names_file=""),
    "campaign_out_unwritable_for_root_too": Case({}, ["campaign", "rr_planar/s3_ic1", "--runs", "2", "--out", "/proc/urpc-out"], None, ("/proc/urpc-out", "cannot write the output folder"), names_file=""),
    "campaign_neither_scenario_nor_robot": Case({}, ["campaign", "--runs", "2"], None, ("give a scenario file", "--robot"), names_file=""),
    "urdf_revolute_without_limit": _urdf_case(_rr_with('<limit lower="-6.283185307179586" upper="6.283185307179586" effort="1000" velocity="20"/>', ""), "joint.joint1.limit", "no <limit>", "continuous"),
    "urdf_limit_without_effort": _urdf_case(_rr_with('effort="1000" velocity="20"', 'velocity="20"'), "Pinocchio cannot parse", "limit has no effort"),
    "box_yaml_alias_bomb": _box_case("links:\n  link2:\n    com_x: [&a [x, x, x, x, x, x, x, x, x, x], &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a], &c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b], &d [*c, *c, *c, *c, *c, *c, *c, *c, *c, *c], &e [*d, *d, *d, *d, *d, *d, *d, *d, *d, *d], &f [*e, *e, *e, *e, *e, *e, *e, *e, *e, *e]]\n", "aliases", "more than"),
    "box_yaml_too_deep": _box_case("links: " + "[" * 40 + "]" * 40, "nested deeper than"),
    "simulate_duration_beyond_memory": Case({}, ["simulate", "--robot", "rr_planar", "--duration", "1e12"], None, ("field 'duration'", "1e+12 s", "samples", "at most"), names_file=""),
    "scenario_duration_beyond_memory_names_the_file": Case({"box.yaml": "links: {link2: {mass: [5, 15]}}\n", "long.yaml": "robot: rr_planar\nuncertainty: box.yaml\nsample_period: 1.0e-3\nepsilon: 1.0e-2\nduration: 1.0e9\n"}, ["simulate", "{tmp}/long.yaml"], None, ("field 'duration'", "1e+09 s", "samples", "at most"), names_file="long.yaml"),
    "negative_epsilon_reaches_urpc": Case({}, ["simulate", "rr_planar/s3_ic1", "--epsilon", "-1e-2"], None, ("epsilon must be > 0", "-1e-2"), names_file=""),
    "negative_percentage_reaches_urpc": Case({}, ["init", "rr_planar", "--out", "{tmp}/box.yaml", "--mass", "-5%"], None, ("--mass", "'-5%' must lie in [0%, 100%)"), names_file=""),
    "negative_runs_reaches_urpc": Case({}, ["campaign", "rr_planar/s3_ic1", "--runs", "-2"], None, ("--runs", "'-2' must be an integer >= 1"), names_file=""),
    "box_joint_relative_width_of_zero": _box_case("joints: {joint1: {friction: 50%}}", "joints.joint1.friction", "nominal friction of 0", "no width at all", "[0, 1]"),
    "box_joint_relative_armature_of_zero": _box_case("joints: {joint2: {armature: 10%}}", "joints.joint2.armature", "URDFs carry no armature"),
    # ------------------------------------------------------------ API mistakes (issue 10.6)
    "box_for_another_robot": Case({}, _check("ur5", str(RR_DIR / "uncertainty.yaml")), lambda tmp: urpc.load_uncertainty("rr_planar", urpc.load_robot("ur5")), ("this box is for robot 'rr_planar'", "not for 'ur5'", "field 'robot'"), names_file="uncertainty.yaml"),
    # ---------------------------------------------------------------- states and methods
    "bound_wrong_length": Case({}, _bound("0.1", "0,0", "0,0", "0,0"), None, ("--q has 1 values", "2 joints"), names_file=""),
    "bound_nan_state": Case({}, _bound("nan,0", "0,0", "0,0", "0,0"), _enclose([np.nan, 0], [0, 0], [0, 0], [0, 0]), ("finite",), names_file=""),
    "bound_inf_state": Case({}, _bound("0,0", "inf,0", "0,0", "0,0"), _enclose([0, 0], [np.inf, 0], [0, 0], [0, 0]), ("finite",), names_file=""),
    "bound_nan_qdd_a_api": Case({}, _bound("0,0", "0,0", "0,0", "nan,0"), _enclose([0, 0], [0, 0], [0, 0], [0, np.nan], method="hull"), ("qdd", "finite"), names_file=""),
    "bound_overflowing_state": Case({}, _bound("1e308,1e308", "1e308,1e308", "0,0", "0,0"), _enclose([1e308] * 2, [1e308] * 2, [0, 0], [0, 0]), ("overflow", "qd"), names_file=""),
    "bound_overflowing_state_hull": Case({}, _bound("0,0", "1e300,1", "1,1", "0,0", method="hull"), _enclose([0, 0], [1e300, 1], [1, 1], [0, 0], method="hull"), ("overflow",), names_file=""),
    "bound_overflowing_state_rigorous": Case({}, _bound("0.3,0.5", "1e200,1e200", "1e200,1e200", "0,0", method="rigorous"), _enclose([0.3, 0.5], [1e200] * 2, [1e200] * 2, [0, 0], method="rigorous"), ("overflow",), names_file=""),
    "bound_unknown_method": Case({}, _bound("0,0", "0,0", "0,0", "0,0", method="interval"), lambda tmp: urpc.make_bound("interval", urpc.load_robot("rr_planar"), None), ("'interval'", "hull"), names_file=""),
}  # fmt: skip


def _materialize(case: Case, tmp_path: Path) -> list[str]:
    for name, text in case.files.items():
        (tmp_path / name).write_text(text)
    return [arg.replace("{tmp}", str(tmp_path)) for arg in case.argv]


def test_catalog_has_at_least_thirty_cases():
    assert len(CASES) >= 30


@pytest.mark.parametrize("name", sorted(CASES))
def test_cli_exit_2_with_one_line(name, tmp_path, capsys):
    case = CASES[name]
    argv = _materialize(case, tmp_path)
    before = sorted(tmp_path.rglob("*"))
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    for word in case.words:
        assert word in err, f"{word!r} not in {err!r}"
    names_file = case.names_file if case.names_file is not None else next(iter(case.files), "")
    if names_file:
        assert names_file in err
    assert sorted(tmp_path.rglob("*")) == before  # nothing written


@pytest.mark.parametrize("name", sorted(n for n, c in CASES.items() if c.api is not None))
def test_api_raises_typed_error(name, tmp_path):
    case = CASES[name]
    _materialize(case, tmp_path)
    with pytest.raises(case.exception) as info:
        case.api(tmp_path)
    assert isinstance(info.value, UrpcError)
    for word in case.words:
        assert word in str(info.value)


@pytest.mark.parametrize("method", sorted(urpc.BOUND_METHODS))
def test_bound_rejects_wrong_shapes_in_the_api(method):
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty(RR_DIR / "uncertainty.yaml", robot)
    bound = urpc.make_bound(method, robot, box)
    with pytest.raises(InputError, match="q has shape"):
        bound.enclose(np.zeros(3), np.zeros(2), np.zeros(2), np.zeros(2))
    with pytest.raises(InputError, match="qdd_a has shape"):
        bound.rho(np.zeros(2), np.zeros(2), np.zeros(2), np.zeros((2, 2)))


# ------------------------------------------------------------------ API mistakes (issue 10.6)
# Mistakes that only the Python API can make: each raises an InputError naming the argument and
# what is expected (not a raw AttributeError, TypeError or NotADirectoryError).
_API: dict = {}


def _rr():
    """The RR arm, its shipped box and a controller synthesized at 1 kHz (built once)."""
    if not _API:
        robot = urpc.load_robot("rr_planar")
        box = urpc.load_uncertainty("rr_planar", robot)
        controller = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3)
        _API.update(robot=robot, box=box, controller=controller)
    return _API["robot"], _API["box"], _API["controller"]


def _simulate(**changes):
    robot, box, controller = _rr()
    arguments = dict(
        plant=robot, controller=controller, trajectory=urpc.PaperTrajectory(), duration=0.01,
    )  # fmt: skip
    arguments.update(changes)
    return urpc.simulate(**arguments)


def _save_into_a_file(tmp: Path):
    result = _simulate()
    (tmp / "existing").write_text("a file")
    return result.save(tmp / "existing")


def _ur5_controller():
    ur5 = urpc.load_robot("ur5")
    box = urpc.parse_uncertainty({"links": {"wrist_3_link": {"mass": "10%"}}}, ur5)
    return urpc.synthesize(ur5, box, epsilon=1e-2, sample_period=1e-3)


def _paper_trajectory_on_ur5(tmp: Path):
    ur5 = urpc.load_robot("ur5")
    box = urpc.parse_uncertainty({"links": {"wrist_3_link": {"mass": "10%"}}}, ur5)
    controller = urpc.synthesize(ur5, box, epsilon=1e-2, sample_period=1e-3)
    return urpc.simulate(ur5, controller, urpc.PaperTrajectory(), duration=0.01)


API_CASES: dict[str, tuple[Callable[[Path], object], tuple[str, ...]]] = {
    "synthesize_box_path": (lambda tmp: urpc.synthesize(_rr()[0], "box.yaml", epsilon=1e-2), ("field 'box'", "ParameterBox", "urpc.load_uncertainty('box.yaml', robot)")),
    "synthesize_box_path_with_method": (lambda tmp: urpc.synthesize(_rr()[0], "box.yaml", epsilon=1e-2, method="hull"), ("field 'box'", "got str")),
    "make_bound_box_path": (lambda tmp: urpc.make_bound("vertex", _rr()[0], Path("box.yaml")), ("field 'box'", "got PosixPath")),
    "make_bound_robot_name": (lambda tmp: urpc.make_bound("vertex", "rr_planar", _rr()[1]), ("field 'robot'", "urpc.load_robot")),
    "simulate_box_as_controller": (lambda tmp: _simulate(controller=_rr()[1]), ("field 'controller'", "urpc.synthesize", "got ParameterBox")),
    "simulate_box_as_plant": (lambda tmp: _simulate(plant=_rr()[1]), ("field 'plant'", "got ParameterBox")),
    "simulate_trajectory_is_a_list": (lambda tmp: _simulate(trajectory=[0, 0]), ("field 'trajectory'", "reference(t)", "got list")),
    "simulate_epsilon_text": (lambda tmp: _simulate(epsilon="0.01"), ("field 'epsilon'", "'0.01' is a str, not a number")),
    "simulate_duration_text": (lambda tmp: _simulate(duration="1"), ("field 'duration'", "not a number")),
    "simulate_paper_trajectory_on_ur5": (_paper_trajectory_on_ur5, ("field 'trajectory'", "PaperTrajectory(amplitude=", "has 2 joints", "'ur5' has 6")),
    "load_uncertainty_dict": (lambda tmp: urpc.load_uncertainty({"links": {}}, _rr()[0]), ("field 'path'", "got dict", "urpc.parse_uncertainty(document, robot)")),
    "load_uncertainty_robot_name": (lambda tmp: urpc.load_uncertainty("rr_planar", "rr_planar"), ("field 'robot'", "urpc.load_robot")),
    "load_parameter_point_box_path": (lambda tmp: urpc.load_parameter_point("rr_planar", _rr()[0], "box.yaml"), ("field 'box'", "ParameterBox")),
    "save_into_an_existing_file": (_save_into_a_file, ("existing", "not a folder")),
    "simulate_torque_limit_of_3_joints": (lambda tmp: _simulate(torque_limit=[1, 2, 3]), ("field 'torque_limit'", "3 entries", "2 joints")),
    "simulate_torque_limit_text": (lambda tmp: _simulate(torque_limit="abc"), ("field 'torque_limit'", "not a number")),
    "simulate_seed_text": (lambda tmp: _simulate(seed="abc"), ("field 'seed'", "integer >= 0")),
    "simulate_seed_negative": (lambda tmp: _simulate(seed=-1), ("field 'seed'", "integer >= 0")),
    "simulate_duration_beyond_memory": (lambda tmp: _simulate(duration=1e12), ("field 'duration'", "samples", "at most")),
    "simulate_continuous_duration_beyond_memory": (lambda tmp: _simulate(controller=urpc.synthesize(_rr()[0], _rr()[1], epsilon=1e-2), duration=1e12), ("field 'duration'", "samples")),
    "load_samples_of_a_folder": (lambda tmp: urpc.load_samples(tmp), ("is a folder, not a file",)),
    "load_controller_of_a_folder": (lambda tmp: urpc.load_controller(tmp), ("is a folder, not a file",)),
    "certify_negative_duration": (lambda tmp: urpc.certify(_rr()[2], urpc.PaperTrajectory(), duration=-1), ("field 'duration'", "> 0")),
    "certify_nan_duration": (lambda tmp: urpc.certify(_rr()[2], urpc.PaperTrajectory(), duration=float("nan")), ("field 'duration'", "> 0")),
    "certify_negative_disturbance": (lambda tmp: urpc.certify(_rr()[2], urpc.PaperTrajectory(), duration=1.0, disturbance_bound=-1), ("field 'disturbance_bound'", ">= 0")),
    "certify_computed_torque": (lambda tmp: urpc.certify(_controllers()["computed-torque"], urpc.PaperTrajectory(), duration=1.0), ("field 'controller'", "interval", "ComputedTorqueController")),
    "certify_paper_trajectory_on_ur5": (lambda tmp: urpc.certify(_ur5_controller(), urpc.PaperTrajectory(), duration=0.5), ("field 'trajectory'", "has 2 joints", "'ur5' has 6")),
    "certify_trajectory_is_a_list": (lambda tmp: urpc.certify(_rr()[2], [0, 0], duration=0.5), ("field 'trajectory'", "reference(t)", "got list")),
    "control_loop_paper_trajectory_on_ur5": (lambda tmp: urpc.ControlLoop(_ur5_controller(), urpc.PaperTrajectory()), ("field 'trajectory'", "has 2 joints", "'ur5' has 6")),
    "plant_point_of_3_values": (lambda tmp: _rr()[1].plant(_rr()[0], {"link2": [1, 2, 3]}), ("field 'point.link2'", "10 finite numbers")),
    "plant_point_text": (lambda tmp: _rr()[1].plant(_rr()[0], {"link2": "heavy"}), ("field 'point.link2'", "10 finite numbers")),
    "plant_joints_of_the_wrong_shape": (lambda tmp: _rr()[1].plant(_rr()[0], {"<joints>": [1, 2]}), ("field 'point.<joints>'", "(3, 2)")),
    "physically_consistent_unknown_link": (lambda tmp: urpc.physically_consistent(_rr()[1], {"link9": np.zeros(10)}), ("field 'point.link9'", "link2")),
    "save_under_an_existing_file": (lambda tmp: (tmp / "f").write_text("x") and _simulate().save(tmp / "f" / "run"), ("'", "not a writable folder")),
}  # fmt: skip


#: Cases in code this change does not own (src/urpc/control/*): expected to fail until fixed there.
@pytest.mark.parametrize("name", sorted(API_CASES))
def test_api_mistakes_raise_input_errors_naming_the_argument(name, tmp_path):
    call, words = API_CASES[name]
    with pytest.raises(InputError) as info:
        call(tmp_path)
    for word in words:
        assert word in str(info.value), f"{word!r} not in {str(info.value)!r}"


def test_the_controller_accepts_lists_and_refuses_text_for_epsilon():
    from urpc.control.base import Reference

    robot, box, controller = _rr()
    as_lists = controller.output(
        0.0, [0.1, 0], [0, 0], Reference([0, 0], [0, 0], [0, 0]), controller.initial_state()
    )
    zeros = np.zeros(2)
    as_arrays = controller.output(
        0.0, np.array([0.1, 0]), zeros, Reference(zeros, zeros, zeros), controller.initial_state()
    )
    np.testing.assert_array_equal(as_lists, as_arrays)
    with pytest.raises(InputError, match="field 'epsilon'.*not a number"):
        urpc.synthesize(robot, box, epsilon="0.01")


def test_array_likes_are_accepted_where_arrays_are_expected():
    robot, box, controller = _rr()
    for method in sorted(urpc.BOUND_METHODS):
        bound = urpc.make_bound(method, robot, box)
        state = ([0.1, 0.2], [1, -1], (1.0, 1.0), [2, 2])
        lower, upper = bound.enclose(*state)
        expected = bound.enclose(*(np.array(v, dtype=float) for v in state))
        np.testing.assert_array_equal(lower, expected[0])
        np.testing.assert_array_equal(upper, expected[1])
        np.testing.assert_array_equal(bound.rho(*state), bound.rho(*map(np.asarray, state)))
        with pytest.raises(InputError, match="qd"):
            bound.enclose([0.1, 0.2], [1], [1, 1], [2, 2])
    result = _simulate(q0=[0, 0], qd0=(0, 0), torque_limit=[100, 100])
    assert np.all(np.isfinite(result.q))


def test_a_controller_runs_at_the_period_it_was_synthesized_for():
    """The period is stated once, at synthesis: simulate takes no second copy."""
    robot, box, controller = _rr()
    sampled = _simulate(duration=0.02)
    assert sampled.sample_period == controller.sample_period == 1e-3 and len(sampled.t) == 21
    continuous = _simulate(controller=urpc.synthesize(robot, box, epsilon=1e-2), duration=0.02)
    assert continuous.sample_period is None and continuous.info["integrator"] == "Radau"
    with pytest.raises(TypeError, match="sample_period"):
        _simulate(sample_period=2e-3)
    with pytest.raises(InputError, match="field 'sample_period'"):
        urpc.synthesize(robot, box, epsilon=1e-2, sample_period=-1e-3)


# ------------------------------------------------- state vectors of the wrong size (controllers)
def _controllers():
    """The three laws on the RR arm, each at 1 kHz."""
    from urpc.control.computed_torque import synthesize_computed_torque
    from urpc.control.r_alpha import synthesize_r_alpha

    robot, box, interval = _rr()
    return {
        "interval": interval,
        "computed-torque": synthesize_computed_torque(robot, box, sample_period=1e-3),
        "r-alpha": synthesize_r_alpha(robot, box, sample_period=1e-3),
    }


_TWO = np.zeros(2)
_BAD_STATES = {
    "q_too_long": ((np.zeros(3), _TWO, urpc.Reference(_TWO, _TWO, _TWO)), "q has shape (3,)"),
    "q_too_short": ((np.zeros(1), _TWO, urpc.Reference(_TWO, _TWO, _TWO)), "q has shape (1,)"),
    "qd_too_long": ((_TWO, np.zeros(4), urpc.Reference(_TWO, _TWO, _TWO)), "qd has shape (4,)"),
    "q_text": (("abc", _TWO, urpc.Reference(_TWO, _TWO, _TWO)), "field 'q'"),
    "reference_of_3_joints": (
        (_TWO, _TWO, urpc.Reference(np.zeros(3), np.zeros(3), np.zeros(3))),
        "reference.q has shape (3,)",
    ),
    "reference_of_1_joint": (
        (_TWO, _TWO, urpc.Reference(np.zeros(1), np.zeros(1), np.zeros(1))),
        "reference.q has shape (1,)",
    ),
    "qd_of_1_joint": ((_TWO, np.zeros(1), urpc.Reference(_TWO, _TWO, _TWO)), "qd has shape (1,)"),
    "reference_is_a_tuple": ((_TWO, _TWO, (_TWO, _TWO, _TWO)), "field 'reference'"),
}


@pytest.mark.parametrize("law", ["interval", "computed-torque", "r-alpha"])
@pytest.mark.parametrize("case", sorted(_BAD_STATES))
def test_controller_output_names_the_vector_of_the_wrong_size(law, case):
    controller = _controllers()[law]
    (q, qd, reference), words = _BAD_STATES[case]
    with pytest.raises(InputError) as info:
        controller.output(0.0, q, qd, reference, controller.initial_state())
    assert words in str(info.value)
    if "shape" in words:
        assert "2 joints" in str(info.value)


@pytest.mark.parametrize("case", ["q_too_long", "reference_of_3_joints"])
def test_controller_advance_names_the_vector_of_the_wrong_size(case):
    controller = _controllers()["interval"]
    (q, qd, reference), words = _BAD_STATES[case]
    state = controller.initial_state()
    for call in (controller.advance, controller.state_derivative):
        with pytest.raises(InputError, match=words.replace("(", r"\(").replace(")", r"\)")):
            call(0.0, q, qd, reference, state)


def test_a_box_applied_to_another_robot_is_refused_naming_the_links():
    """A box made for the UR5 on the RR arm used to return the RR arm's nominal plant silently."""
    ur5 = urpc.load_robot("ur5")
    box = urpc.load_uncertainty("ur5", ur5)
    rr = urpc.load_robot("rr_planar")
    with pytest.raises(InputError) as caught:
        box.plant(rr)
    assert caught.value.field == "robot"
    payloads = {payload.name for payload in box.payloads}
    bounded = [b.link for b in box.links if b.link not in payloads]
    assert "does not have" in str(caught.value) and all(n in str(caught.value) for n in bounded)
    with pytest.raises(InputError):
        box.nominal_robot(rr)
    assert box.plant(ur5).dof == 6  # its own robot is still fine


@pytest.mark.parametrize("value", [-1.0, 0.0, float("nan"), "big"])
def test_simulate_refuses_a_max_state_that_is_not_a_positive_number(value):
    rr = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", rr)
    controller = urpc.synthesize(rr, box, 1e-2, sample_period=1e-3)
    with pytest.raises(InputError) as caught:
        urpc.simulate(
            box.plant(rr), controller, urpc.trajectories.PaperTrajectory(), duration=0.01,
            solver=urpc.SolverOptions(max_state=value),
        )  # fmt: skip
    assert caught.value.field == "max_state"
