"""Bad controller files and bad ``--save-controller`` paths: one InputError (the CLI: one
``error:`` line, exit 2) naming the file and the field, no traceback, nothing left behind."""

import json
import os

import pytest

import urpc
from urpc.cli import main

_CACHE: dict = {}


def _saved(tmp_path, locked=()):
    """A controller of the RR arm at 1 kHz (``locked``: joints locked at 0), saved in tmp_path."""
    key = tuple(locked)
    if key not in _CACHE:
        robot = urpc.load_robot("rr_planar", {name: 0.0 for name in locked})
        box = urpc.load_uncertainty("rr_planar", robot)
        _CACHE[key] = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    return _CACHE[key].save(tmp_path / "c.json")


def _edited(tmp_path, edit):
    path = _saved(tmp_path)
    document = json.loads(path.read_text())
    edit(document)
    path.write_text(json.dumps(document))
    return path


def _set(section, field, value):
    return lambda d: d[section].__setitem__(field, value)


def _drop(section, field):
    return lambda d: d[section].pop(field)


CASES = {
    "box_a_list": (lambda d: d.__setitem__("box", []), "field 'box'", "not an object"),
    "box_without_document": (_drop("box", "document"), "field 'box.document'", "missing"),
    "law_a_number": (lambda d: d.__setitem__("law", 5), "field 'law'", "not an object"),
    "Kr_text": (
        _set("law", "Kr", "thirty"),
        "field 'law.Kr'",
        "'thirty' is not a number or list of numbers",
    ),
    "check_null": (lambda d: d.__setitem__("check", None), "field 'check'", "null"),
    "check_without_joint_parameters": (
        _drop("check", "joint_parameters"),
        "field 'check.joint_parameters'",
        "missing",
    ),
    "nominal_parameters_text": (
        _set("check", "nominal_parameters", ["a"]),
        "field 'check.nominal_parameters'",
        "not a list of numbers",
    ),
    "locked_joints_a_list": (
        _set("robot", "locked_joints", ["joint1"]),
        "field 'robot.locked_joints'",
        "not an object mapping joint names",
    ),
    "locked_joints_text": (
        _set("robot", "locked_joints", "joint1"),
        "field 'robot.locked_joints'",
        "not an object mapping joint names",
    ),
    "locked_joint_unknown": (
        _set("robot", "locked_joints", {"jointX": 0.0}),
        "field 'robot.locked_joints'",
        "valid: joint1, joint2",
    ),
    "urdf_a_number": (_set("robot", "urdf", 5), "field 'robot.urdf'", "5 is not a text"),
    "robot_missing": (lambda d: d.pop("robot"), "field 'robot'", "missing"),
    "bad_law_value": (_set("law", "epsilon", -1.0), "field 'law.epsilon'", ">= 1e-12"),
    "bad_law_method": (_set("law", "method", "nope"), "field 'law.method'", "valid: "),
    "bad_embedded_box": (
        lambda d: d["box"]["document"]["links"]["link2"].__setitem__("mass", [10, 5]),
        "field 'box.document.links.link2.mass'",
        "embedded copy",
    ),
    "continuous_time": (
        _set("law", "sample_period", None),
        "field 'law.sample_period'",
        "continuous-time",
    ),
    "ragged_joint_parameters": (
        _set("check", "joint_parameters", [[0.0, 0.0], [0.0]]),
        "field 'check'",
        "synthesize and save it again",
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_malformed_controller_file_names_the_file_and_the_field(case, tmp_path):
    edit, field, words = CASES[case]
    path = _edited(tmp_path, edit)
    with pytest.raises(urpc.InputError) as caught:
        urpc.load_controller(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: {field}:"), message
    assert words in message and "\n" not in message
    assert "uncertainty.yaml:" not in message  # the controller file, not the box's source


def test_a_continuous_time_controller_is_not_saved(tmp_path):
    robot = urpc.load_robot("rr_planar")
    controller = urpc.synthesize(robot, urpc.load_uncertainty("rr_planar", robot), 1e-2)
    with pytest.raises(urpc.InputError, match="field 'sample_period'.*continuous-time"):
        controller.save(tmp_path / "c.json")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize(
    "where, words",
    [
        ("adir", "is a folder; give a file name such as arm.json"),
        ("afile/c.json", "is a file, not a folder"),
    ],
)
def test_save_refuses_a_folder_or_a_path_under_a_file(where, words, tmp_path):
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("x")
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    with pytest.raises(urpc.InputError, match=words):
        controller.save(tmp_path / where)
    assert sorted(os.listdir(tmp_path)) == ["adir", "afile"]
    assert os.listdir(tmp_path / "adir") == []


def _cli(capsys, *argv):
    code = main(list(argv))
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("error:")]
    return code, err, lines


@pytest.mark.parametrize(
    "where, words",
    [
        ("adir", "--save-controller {}: is a folder; give a file name such as arm.json"),
        ("nodir/c.json", "--save-controller {}: the folder"),
        ("afile/c.json", "--save-controller {}: "),
        ("old.json", "--save-controller {}: the file exists; give --force"),
    ],
)
def test_run_checks_the_save_controller_path_first(where, words, tmp_path, capsys, monkeypatch):
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("x")
    (tmp_path / "old.json").write_text("old")
    monkeypatch.chdir(tmp_path)

    def synthesis_must_not_run(*args, **kwargs):
        raise AssertionError("synthesized before the path was checked")

    monkeypatch.setattr("urpc.control.synthesis.synthesize", synthesis_must_not_run)
    code, err, lines = _cli(
        capsys,
        "run",
        "rr_planar/s3_ic1",
        "--robot-address",
        "udp://127.0.0.1:9",
        "--save-controller",
        where,
    )
    assert code == 2 and "Traceback" not in err
    assert len(lines) == 1 and words.format(where) in lines[0], err
    assert (tmp_path / "old.json").read_text() == "old"
    assert sorted(os.listdir(tmp_path)) == ["adir", "afile", "old.json"]


def test_run_saves_no_controller_when_it_fails_on_bad_input(tmp_path, capsys):
    """No robot answers (exit 2 after 5 s): the controller file is not written."""
    target = tmp_path / "c.json"
    code, err, lines = _cli(
        capsys,
        "run",
        "rr_planar/s3_ic1",
        "--robot-address",
        "udp://127.0.0.1:9",
        "--save-controller",
        str(target),
    )
    assert code == 2 and "Traceback" not in err
    assert len(lines) == 1 and "no state from the robot" in lines[0]
    assert not target.exists() and os.listdir(tmp_path) == []


def test_run_refuses_a_continuous_time_controller_file(tmp_path, capsys):
    path = _edited(tmp_path, _set("law", "sample_period", None))
    code, err, lines = _cli(
        capsys, "run", "rr_planar/s3_ic1", "--robot-address", "udp://127.0.0.1:9",
        "--controller", str(path),
    )  # fmt: skip
    assert code == 2 and "Traceback" not in err and len(lines) == 1
    assert "field 'law.sample_period'" in lines[0] and "continuous-time" in lines[0]


def test_run_names_the_joints_of_a_controller_for_other_locked_joints(tmp_path, capsys):
    path = _saved(tmp_path, locked=["joint1"])
    code, err, lines = _cli(
        capsys, "run", "rr_planar/s3_ic1", "--robot-address", "udp://127.0.0.1:9",
        "--controller", str(path),
    )  # fmt: skip
    assert code == 2 and "Traceback" not in err and len(lines) == 1
    message = lines[0]
    assert "rr_planar with 1 joint (joint2; locked: joint1)" in message, message
    assert "rr_planar with 2 joints (joint1, joint2; locked: none)" in message, message


def _scenario(tmp_path, edit):
    """The RR arm's scenario 3 (1 kHz) written to tmp_path after ``edit(data)``, its box file
    copied beside it (edited too when ``edit`` returns a new box document)."""
    import yaml

    from urpc.studies.scenario import load_scenario

    source = load_scenario("rr_planar/s3_ic1").source
    data = yaml.safe_load(open(source))
    root = os.path.dirname(source)
    box = yaml.safe_load(open(os.path.join(root, data["uncertainty"])))
    data["uncertainty"] = "box.yaml"
    data["true_parameters"] = os.path.join(root, data["true_parameters"])
    data["controller_options"]["interval"].pop("sampled_law")
    box = edit(data, box) or box
    (tmp_path / "box.yaml").write_text(yaml.safe_dump(box))
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    return str(tmp_path / "s.yaml")


@pytest.mark.parametrize(
    "edit, words",
    [
        (lambda d, b: None, None),  # the scenario the controller was saved for: no refusal
        (
            lambda d, b: d.__setitem__("epsilon", 2e-2),
            "synthesized for epsilon = 0.01, but {} asks for epsilon = 0.02",
        ),
        (
            lambda d, b: d.__setitem__("sample_period", 5e-4),
            "synthesized for sample_period = 0.001, but {} asks for sample_period = 0.0005",
        ),
        (
            lambda d, b: b["links"]["link2"].__setitem__("mass", [5, 12]),
            "box is not the scenario's uncertainty box (the intervals of link2 differ)",
        ),
        (
            lambda d, b: b.__setitem__("disturbance", 3.0),
            "(the disturbance bound (None saved, 3.0 in the scenario) differ)",
        ),
        (
            lambda d, b: d["controller_options"]["interval"].__setitem__("kappa_P", 3),
            "has kappa_P = 2, but {} states kappa_P: 3",
        ),
        (
            lambda d, b: d["controller_options"]["interval"].__setitem__("Kr", [30, 20]),
            "has Kr = [30, 30], but {} states Kr: [30, 20]",
        ),
        (
            lambda d, b: d["controller_options"]["interval"].__setitem__("sampled_law", "paper"),
            "has sampled_law = implicit, but {} states sampled_law: paper",
        ),
        (lambda d, b: d["controller_options"]["interval"].__setitem__("Kr", 30), None),
        (  # a diagonal matrix, as synthesize takes it
            lambda d, b: d["controller_options"]["interval"].__setitem__("Kr", [[30, 0], [0, 30]]),
            None,
        ),
        (
            lambda d, b: d["controller_options"]["interval"].__setitem__("Kr", [[30, 0], [0, 20]]),
            "has Kr = [30, 30], but {} states Kr: [[30, 0], [0, 20]]",
        ),
    ],
    ids=[
        "same",
        "epsilon",
        "sample_period",
        "link_interval",
        "disturbance_bound",
        "kappa_P",
        "Kr",
        "sampled_law",
        "same_Kr_as_a_scalar",
        "same_Kr_as_a_matrix",
        "Kr_matrix",
    ],  # fmt: skip
)
def test_run_refuses_a_saved_controller_whose_numbers_are_not_the_scenarios(
    edit, words, tmp_path, capsys
):
    """A scenario edited after its controller was saved: ``urpc run --controller`` would judge
    ``met`` against one epsilon while the controller adapts to another, or run a guarantee made
    for another box. One error naming the saved file, the field and both values; the scenario
    it was saved for passes the check (and fails only for want of a robot)."""
    path = _saved(tmp_path)
    scenario = _scenario(tmp_path, edit)
    code, err, lines = _cli(
        capsys, "run", scenario, "--robot-address", "udp://127.0.0.1:9", "--controller", str(path),
    )  # fmt: skip
    assert code == 2 and "Traceback" not in err and len(lines) == 1, err
    if words is None:
        assert "no state from the robot" in lines[0], lines[0]
    else:
        assert words.format(scenario) in lines[0], lines[0]
        assert str(path) in lines[0]


def test_run_compares_only_the_law_the_scenario_states(tmp_path, capsys):
    """A controller saved with the paper's law, run with a scenario that states no law: the
    synthesis default (implicit) is not the scenario's word, so nothing is refused."""
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3, sampled_law="paper")
    path = controller.save(tmp_path / "paper.json")
    scenario = _scenario(tmp_path, lambda d, b: None)  # sampled_law removed from the file
    code, err, lines = _cli(
        capsys, "run", scenario, "--robot-address", "udp://127.0.0.1:9", "--controller", str(path),
    )  # fmt: skip
    assert code == 2 and len(lines) == 1 and "no state from the robot" in lines[0], err


@pytest.mark.parametrize(
    "version, shown", [(True, "true"), (1.0, "1.0"), ("1", "'1'")], ids=["true", "1.0", "text"]
)
def test_the_version_is_the_integer_1(version, shown, tmp_path):
    # true and 1.0 compare equal to 1 in Python: both loaded as version 1.
    path = _edited(tmp_path, lambda d: d.__setitem__("version", version))
    with pytest.raises(urpc.InputError) as caught:
        urpc.load_controller(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: field 'version': version {shown}; "), message
    assert "this urpc reads version 1 (the integer 1)" in message


@pytest.mark.parametrize(
    "old, new, field",
    [
        ('"version": 1', '"version": 2, "version": 1', "version"),
        ('"epsilon": ', '"epsilon": 5.0, "epsilon": ', "law.epsilon"),
        ('"mass": ', '"mass": [1, 2], "mass": ', "box.document.links.link"),
    ],
    ids=["top", "law", "embedded-box"],
)
def test_a_key_given_twice_is_refused_naming_it(old, new, field, tmp_path):
    """JSON keeps the last of two equal keys without a word, so an edit that left the old value
    above the new one loaded either, depending on their order."""
    path = _saved(tmp_path)
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(urpc.InputError) as caught:
        urpc.load_controller(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: field '{field}"), message
    assert "appears more than once in its object" in message and "\n" not in message
