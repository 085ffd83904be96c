"""``urpc init``: a starting box that check, simulate and campaign accept with no edit."""

from __future__ import annotations

import json
import shutil
import urllib.parse
from pathlib import Path

import pytest
import yaml

from urpc.cli import main
from urpc.cli.init import _schema_reference

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = ROOT / "docs" / "schemas" / "uncertainty.schema.json"


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def user_urdf(tmp_path):
    """A user's own arm: a URDF file outside the package, given by path."""
    path = tmp_path / "my_arm.urdf"
    shutil.copy(ROOT / "robots" / "rr_planar" / "rr_planar.urdf", path)
    return path


@pytest.mark.parametrize("robot", ["ur10", "kinova", "z1", "urdf"])
def test_init_then_check_and_simulate_with_no_edit(capsys, tmp_path, user_urdf, robot):
    robot = str(user_urdf) if robot == "urdf" else robot
    box = tmp_path / "box.yaml"
    code, out, err = _run(capsys, "init", robot, "--out", box)
    assert code == 0, err
    assert f"wrote {box}" in out and "urpc simulate --robot" in out
    code, out, err = _run(capsys, "check", robot, "--uncertainty", box)
    assert code == 0 and "moving links" in out, err
    code, out, err = _run(
        capsys, "simulate", "--robot", robot, "--uncertainty", box, "--duration", 1, "--json"
    )
    assert code == 0, err
    assert json.loads(out)["met"] is True


def test_init_file_is_commented_and_names_the_schema(capsys, tmp_path):
    box = tmp_path / "box.yaml"
    assert _run(capsys, "init", "ur10", "--out", box)[0] == 0
    text = box.read_text()
    first = text.splitlines()[0]
    # The editor line names the schema: a relative path inside the source tree, else (a plain
    # install) the installed copy as a file URI; either way the published schema itself.
    assert first.startswith("# yaml-language-server: $schema=")
    reference = first.split("$schema=", 1)[1]
    named = (
        Path(urllib.parse.urlparse(reference).path)
        if "://" in reference
        else box.parent / reference
    )
    assert named.read_text() == SCHEMA.read_text()
    assert "# URDF 7.778 kg -> [7.0002, 8.5558]" in text  # shoulder_link mass, +-10 %
    document = yaml.safe_load(text)
    assert document["robot"] == "ur10" and document["disturbance"] == "unknown"
    assert set(document["links"]) == {
        "shoulder_link",
        "upper_arm_link",
        "forearm_link",
        "wrist_1_link",
        "wrist_2_link",
        "wrist_3_link",
    }
    assert document["links"]["shoulder_link"] == {
        "mass": "10%",
        "com_x": "+-0.01",
        "com_y": "+-0.01",
        "com_z": "+-0.01",
        "ixx": "20%",
        "iyy": "20%",
        "izz": "20%",
    }


def test_schema_reference_is_relative_inside_the_tree_and_a_uri_outside(tmp_path):
    schema = tmp_path / "tree" / "docs" / "schemas" / "uncertainty.schema.json"
    inside = tmp_path / "tree" / "robots" / "my_arm" / "uncertainty.yaml"
    inside.parent.mkdir(parents=True)
    assert _schema_reference(schema, inside) == "../../docs/schemas/uncertainty.schema.json"
    outside = tmp_path / "elsewhere" / "box.yaml"
    assert _schema_reference(schema, outside) == schema.as_uri()


def test_init_options_and_payload(capsys, tmp_path):
    box = tmp_path / "box.yaml"
    code, out, err = _run(
        capsys,
        "init",
        "ur10",
        "--out",
        box,
        "--mass",
        "5%",
        "--com",
        "0.002",
        "--inertia",
        "0%",
        "--payload",
        "tool0:3",
        "--json",
    )
    assert code == 0, err
    summary = json.loads(out)
    assert summary["payload"] == {"link": "tool0", "mass": [0.0, 3.0]}
    assert summary["exact_links"] == {
        "ee_link": "massless in the URDF",
        "tool0": "massless in the URDF",
    }
    document = yaml.safe_load(box.read_text())
    assert document["links"]["wrist_3_link"] == {
        "mass": "5%",
        "com_x": "+-0.002",
        "com_y": "+-0.002",
        "com_z": "+-0.002",
    }
    assert document["payload"] == {"name": "payload", "link": "tool0", "mass": [0, 3]}
    assert summary["uncertain_parameters"] == 6 * 4 + 1
    code, out, _ = _run(capsys, "check", "ur10", "-u", box)
    assert code == 0 and "'payload' fixed to link 'tool0'" in out


def test_init_refuses_an_existing_file_unless_forced(capsys, tmp_path):
    box = tmp_path / "box.yaml"
    box.write_text("mine\n")
    code, _, err = _run(capsys, "init", "rr_planar", "--out", box)
    assert code == 2 and err.startswith("error:") and "--force" in err
    assert box.read_text() == "mine\n"
    assert _run(capsys, "init", "rr_planar", "--out", box, "--force")[0] == 0
    assert "links:" in box.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.yaml"]  # no temporary left


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["init", "ur10"], "--out"),
        (["init", "ur10", "--out", "x.yaml", "--mass", "10"], "percentage"),
        (["init", "ur10", "--out", "x.yaml", "--inertia", "100%"], "[0%, 100%)"),
        (["init", "ur10", "--out", "x.yaml", "--com", "-1"], ">= 0"),
        (["init", "ur10", "--out", "x.yaml", "--payload", "tool0"], "LINK:KG"),
        (["init", "ur10", "--out", "x.yaml", "--payload", "tool:1"], "did you mean 'tool0'"),
        (["init", "anymal", "--out", "x.yaml"], "floating-base"),
        (["init", "no_such_arm", "--out", "x.yaml"], "unknown robot"),
    ],
)
def test_init_bad_input_exits_2_with_one_line(capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    code, _, err = _run(capsys, *argv)
    assert code == 2 and err.startswith("error:") and len(err.strip().splitlines()) == 1
    assert message in err
    assert not (tmp_path / "x.yaml").exists()


def test_simulate_without_a_box_points_to_init(capsys):
    code, _, err = _run(capsys, "simulate", "--robot", "ur10")
    assert code == 2 and "urpc init ur10 --out box.yaml" in err


def test_campaign_accepts_an_init_box(capsys, tmp_path):
    box = tmp_path / "box.yaml"
    assert _run(capsys, "init", "z1", "--out", box)[0] == 0
    scenario = tmp_path / "z1.yaml"
    scenario.write_text(yaml.safe_dump({"robot": "z1", "uncertainty": "box.yaml", "duration": 0.2}))
    code, out, err = _run(
        capsys,
        "campaign",
        scenario,
        "--runs",
        2,
        "--workers",
        1,
        "--out",
        tmp_path / "campaign",
        "--no-progress",
        "--json",
    )
    assert code == 0, err
    assert (tmp_path / "campaign" / "runs.csv").is_file()
