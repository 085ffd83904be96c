"""The CLI contract: exit 0 on success, exit 2 with one 'error:' line for bad input, --json."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import rr_closed_form

from urpc.__main__ import main


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_help_exits_zero():
    result = subprocess.run(
        [sys.executable, "-m", "urpc", "--help"], capture_output=True, text=True
    )
    assert result.returncode == 0 and "check" in result.stdout and "bound" in result.stdout


def test_robots_lists_builtin_and_example_robot_data(capsys):
    code, out, _ = _run(capsys, "robots", "--json")
    listing = json.loads(out)
    assert code == 0 and "rr_planar" in listing["builtin"]
    assert {"ur5", "panda"} <= set(listing["example_robot_data"])


def test_check_prints_table_one(capsys):
    code, out, _ = _run(capsys, "check", "rr_planar", "--json")
    summary = json.loads(out)
    (link,) = summary["links"]
    fields = {f["field"]: f for f in link["fields"] if f["uncertain"]}
    assert code == 0 and set(fields) == {"mass", "com_x", "iyy"}
    assert (fields["mass"]["lower"], fields["mass"]["upper"]) == (5, 10)
    assert fields["iyy"]["upper"] == pytest.approx(20 / 12)
    code, out, _ = _run(capsys, "check", "rr_planar")
    assert code == 0 and "0.525" in out and "unknown bound" in out


def test_bound_json_contains_sampled_mismatch(capsys):
    q, qd, qa, qdda = [0.3, -0.5], [1.0, 0.5], [0.7, -0.2], [2.0, -1.0]
    code, out, _ = _run(
        capsys, "bound", "rr_planar", "--q", "0.3,-0.5", "--qd", "1,0.5", "--qd-a", "0.7,-0.2",
        "--qdd-a", "2,-1", "--method", "hull", "--json",
    )  # fmt: skip
    result = json.loads(out)
    assert code == 0 and set(result) >= {"lower", "upper", "rho", "method"}
    M0, C0, g0 = rr_closed_form(np.array(q), np.array(qd), 5, 0.5, 5 / 12)
    rng = np.random.default_rng(0)
    for _ in range(200):
        m2, lc2, I2 = rng.uniform(5, 10), rng.uniform(0.5, 0.525), rng.uniform(5 / 12, 20 / 12)
        M, C, g = rr_closed_form(np.array(q), np.array(qd), m2, lc2, I2)
        w = (M - M0) @ qdda + (C - C0) @ qa + g - g0
        assert np.all(w >= np.array(result["lower"])) and np.all(w <= np.array(result["upper"]))


@pytest.mark.parametrize(
    "argv, message",
    [
        (["bound", "rr_planar", "--q", "0.1", "--qd", "0,0", "--qd-a", "0,0", "--qdd-a", "0,0"], "--q has 1 values"),
        (["bound", "rr_planar", "--q", "nan,0", "--qd", "0,0", "--qd-a", "0,0", "--qdd-a", "0,0"], "finite"),
        (["bound", "rr_planar", "--q", "0,0", "--qd", "0,0", "--qd-a", "0,0", "--qdd-a", "0,0", "--method", "exact"], "--method: invalid choice: 'exact'"),
        (["bound", "rr_planar", "--q", "0,0"], "required"),
        (["check", "no_such_robot"], "unknown robot"),
        (["check", "panda", "--lock", "finger"], "cannot lock unknown joint"),
        (["frobnicate"], "invalid choice"),
    ],
)  # fmt: skip
def test_bad_input_exit_2_one_line(capsys, argv, message):
    code, out, err = _run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and message in err and err.count("\n") == 1


def test_malformed_urdf_from_the_console_script(tmp_path):
    path = tmp_path / "broken.urdf"
    path.write_text("<robot name='x'><link name='a'></robot>")
    result = subprocess.run(
        [sys.executable, "-m", "urpc", "check", str(path)], capture_output=True, text=True
    )
    assert result.returncode == 2
    assert result.stderr.startswith("error: ") and result.stderr.count("\n") == 1
    assert "broken.urdf" in result.stderr and "Traceback" not in result.stderr
