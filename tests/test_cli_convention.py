"""One command-line convention (issue 11): robot, metavars, choices, output folders checked before
any work, progress bars only on a terminal and never above an error line, figures that agree with
the text, units of prismatic joints, and the README's reference in agreement with ``--help``."""

from __future__ import annotations

import io
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from urpc.cli import main
from urpc.sim.metrics import describe_final_window, final_window, series_metrics

ROOT = Path(__file__).resolve().parents[1]
RR = ROOT / "robots" / "rr_planar"

# Two prismatic joints (a gantry): positions in m, forces in N.
GANTRY_URDF = """<?xml version="1.0"?>
<robot name="gantry">
  <link name="base"/>
  <joint name="x" type="prismatic">
    <parent link="base"/><child link="cart"/><axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.5" effort="200" velocity="1"/>
  </joint>
  <link name="cart">
    <inertial><mass value="3.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="z" type="prismatic">
    <parent link="cart"/><child link="head"/><axis xyz="0 0 1"/>
    <limit lower="-0.3" upper="0.3" effort="200" velocity="1"/>
  </joint>
  <link name="head">
    <inertial><origin xyz="0 0 0.05"/><mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
</robot>
"""


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _help(capsys, *command) -> str:
    with pytest.raises(SystemExit) as info:
        main([*command, "--help"])
    assert info.value.code == 0
    return " ".join(capsys.readouterr().out.split())  # argparse wraps lines


class _Terminal(io.StringIO):
    """A stderr that says it is a terminal."""

    def isatty(self) -> bool:
        return True


# ------------------------------------------------------------------ options, metavars, choices
COMMANDS_WITH_OUT = [
    ("simulate",),
    ("reproduce-paper",),
    ("campaign",),
    ("demo", "reconfigure"),
    ("demo", "tool-change"),
]


@pytest.mark.parametrize("command", COMMANDS_WITH_OUT)
def test_every_output_folder_is_out_dir_with_json_and_no_progress(capsys, command):
    text = _help(capsys, *command)
    assert "--out DIR" in text and "--json" in text and "--no-progress" in text
    assert "shown only when stderr is a terminal" in text
    assert "--out OUT" not in text


@pytest.mark.parametrize(
    "command, default",
    [
        (("simulate",), "nothing is written"),
        (("reproduce-paper",), "urpc-results/paper"),
        (("campaign",), "urpc-results/campaign/SCENARIO"),
        (("demo", "reconfigure"), "urpc-results/reconfigure"),
        (("demo", "tool-change"), "urpc-results/tool-change"),
    ],
)
def test_output_defaults_are_stated_in_help_and_in_the_readme(capsys, command, default):
    assert f"(default: {default})" in _help(capsys, *command)
    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("## Command line") : readme.index("## Documentation")]
    assert default in section, default


@pytest.mark.parametrize("command", [("check",), ("bound",), ("simulate",), ("certify",)])
def test_robot_and_uncertainty_have_the_same_metavars(capsys, command):
    text = _help(capsys, *command)
    assert "--robot ROBOT" in text and "--uncertainty FILE" in text
    assert "UNCERTAINTY" not in text


@pytest.mark.parametrize("command", [("simulate",), ("campaign",)])
def test_plant_lists_its_choices_everywhere(capsys, command):
    assert "--plant {pinocchio,mujoco}" in _help(capsys, *command)


def test_check_and_bound_take_the_robot_positional_or_as_robot(capsys):
    positional = _run(capsys, "check", "rr_planar", "--json")
    option = _run(capsys, "check", "--robot", "rr_planar", "--json")
    assert positional[0] == option[0] == 0 and json.loads(positional[1]) == json.loads(option[1])
    state = ("--q", "0.1,0.2", "--qd", "1,1", "--qd-a", "1,1", "--qdd-a", "2,2", "--json")
    assert (
        _run(capsys, "bound", "rr_planar", *state)[1]
        == _run(capsys, "bound", "--robot", "rr_planar", *state)[1]
    )
    code, out, err = _run(capsys, "check", "rr_planar", "--robot", "ur5")
    assert code == 2 and out == "" and "two robots given" in err and err.count("\n") == 1
    code, out, err = _run(capsys, "check")
    assert (
        code == 2
        and err.startswith("error: ")
        and "give a robot: a URDF path or a name" in err
        and err.count("\n") == 1
    )


# ------------------------------------------------------------------ --out checked before any work
def test_simulate_out_is_checked_before_the_run(capsys, tmp_path, monkeypatch):
    import urpc.studies.scenario as scenario_module

    def no_run(*args, **kwargs):
        raise AssertionError("the simulation ran before --out was checked")

    monkeypatch.setattr(scenario_module, "simulate_setup", no_run)
    blocker = tmp_path / "file"
    blocker.write_text("in the way")
    code, out, err = _run(capsys, "simulate", "rr_planar/s3_ic1", "--out", blocker / "run")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert (
        err.startswith("error: ")
        and "not a writable folder" in err
        and "choose another --out" in err
    )
    code, out, err = _run(capsys, "simulate", "rr_planar/s3_ic1", "--out", blocker)
    assert code == 2 and "exists and is not a folder" in err
    assert blocker.read_text() == "in the way" and sorted(tmp_path.iterdir()) == [blocker]


@pytest.mark.parametrize(
    "command",
    [
        ("reproduce-paper", "--duration", "0.01"),
        ("campaign", "rr_planar/s3_ic1", "--runs", "1", "--duration", "0.01"),
        ("demo", "reconfigure", "--duration", "0.01"),
        ("demo", "tool-change", "--duration", "0.01"),
    ],
)
def test_every_writing_command_checks_out_first(capsys, tmp_path, command):
    blocker = tmp_path / "file"
    blocker.write_text("in the way")
    code, out, err = _run(capsys, *command, "--out", blocker / "sub")
    assert code == 2 and out == "" and err.startswith("error: ") and err.count("\n") == 1
    assert "not a writable folder" in err
    assert sorted(tmp_path.iterdir()) == [blocker]


def test_a_write_error_names_the_folder_not_a_temporary_file(capsys, tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    def broken(self, path, **kwargs):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(Figure, "savefig", broken)
    out = tmp_path / "run"
    code, text, err = _run(
        capsys, "simulate", "rr_planar/s3_ic1", "--duration", "0.05", "--out", out
    )
    error = err.splitlines()[-1]
    assert (
        code == 2 and error == f"error: {out}: cannot write the results (No space left on device)"
    )
    assert list(tmp_path.iterdir()) == []


def test_campaign_writes_under_urpc_results_by_default(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = _run(
        capsys, "campaign", "rr_planar/s3_ic1", "--runs", "1", "--duration", "0.05",
        "--workers", "1",
    )  # fmt: skip
    folder = tmp_path / "urpc-results" / "campaign" / "s3_ic1"
    assert code == 0 and (folder / "summary.json").is_file()
    assert f"outputs              {folder}/" in out
    assert (
        "campaign s3_ic1: 1 run (0 of 8 vertices, 1 uniform; 0 inconsistent draws rejected)" in out
    )


# ------------------------------------------------------------------ progress
def test_no_bar_when_stderr_is_not_a_terminal(capsys, tmp_path):
    """A redirected log gets no carriage returns from any command (capsys is not a terminal)."""
    runs = [
        ("simulate", "rr_planar/s3_ic1", "--duration", "0.2"),
        ("campaign", "rr_planar/s3_ic1", "--runs", "2", "--duration", "0.05", "--workers", "1",
         "--out", tmp_path / "c"),
        ("demo", "reconfigure", "--assemblies", "arm_3dof", "--duration", "0.05", "--out",
         tmp_path / "d"),
        ("reproduce-paper", "--duration", "0.01", "--workers", "1", "--out", tmp_path / "p"),
    ]  # fmt: skip
    for argv in runs:
        code, out, err = _run(capsys, *argv)
        assert code == 0, err
        assert "\r" not in err and "%|" not in err, argv
        assert all(line.startswith("warning: ") for line in err.splitlines()), argv


def test_a_bar_on_a_terminal_and_none_with_no_progress(capsys, monkeypatch):
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    assert main(["simulate", "rr_planar/s3_ic1", "--duration", "0.2"]) == 0
    assert "simulate:" in terminal.getvalue() and "%|" in terminal.getvalue()
    quiet = _Terminal()
    monkeypatch.setattr(sys, "stderr", quiet)
    assert main(["simulate", "rr_planar/s3_ic1", "--duration", "0.2", "--no-progress"]) == 0
    assert "%|" not in quiet.getvalue()


def test_a_failing_run_clears_its_bar_before_the_error_line(capsys, monkeypatch, tmp_path):
    document = {
        "robot": "rr_planar",
        "uncertainty": str(RR / "uncertainty.yaml"),
        "true_parameters": "nominal",
        "controller": "computed-torque",
        "controller_options": {"computed-torque": {"natural_frequency": 1e4}},
        "initial_condition": {"offset": [1e-3, 0]},
        "duration": 1.0,
    }
    import yaml

    path = tmp_path / "diverging.yaml"
    path.write_text(yaml.safe_dump(document))
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    assert main(["simulate", str(path)]) == 2
    text = terminal.getvalue()
    assert "%|" in text  # the bar was shown ...
    last = text.rstrip("\n").split("\n")[-1]
    # ... and cleared: after its last carriage return the line holds the error alone
    assert last.split("\r")[-1].startswith("error: the simulation diverged")
    assert last.split("\r")[-2].strip() == ""


def test_every_reporter_is_the_one_mechanism():
    from urpc.sim.progress import Progress, SimulationProgress
    from urpc.studies.campaign.progress import CampaignProgress
    from urpc.studies.demo.progress import ProgressReporter
    from urpc.studies.paper.runs import RunReporter

    for reporter in (SimulationProgress, CampaignProgress, ProgressReporter, RunReporter):
        assert issubclass(reporter, Progress)
    calls = []
    with RunReporter(lambda *args: calls.append(args), 2) as report:
        report.done("a")
        report.done("b")
    assert calls == [(1, 2, "a"), (2, 2, "b")]
    counts = []
    campaign = CampaignProgress(lambda done, total: counts.append((done, total)), 3)
    campaign.advance()
    assert counts == [(1, 3)]
    fractions = []
    with ProgressReporter(fractions.append, "demo", 2) as demo:
        demo.part(1, 2)(0.5)
    assert fractions == [0.75]


# ------------------------------------------------------------------ figures that agree with the text
def test_final_error_covers_the_final_quarter_of_a_short_run():
    """A 1 s run that leaves a transient at 0.18 s is met, and its final error (max over the last
    quarter, not the last second) is below epsilon: the two figures agree."""
    t = np.arange(1001) / 1000.0
    error = np.where(t < 0.179, 0.0116, 0.004)
    error[0] = 0.0
    metrics = series_metrics(t, error, np.zeros((len(t), 2)), 0.01)
    assert metrics["met"] is True and metrics["entry_time"] == pytest.approx(0.179)
    assert metrics["final_error"] == 0.004
    assert final_window(1.0) == 0.25 and final_window(10.0) == 1.0
    assert describe_final_window(1.0) == "the last 0.25 s, the final quarter"
    assert describe_final_window(8.0) == "the last second"


@pytest.mark.parametrize("duration", [0.4, 1.0, 5.0])
def test_a_met_run_never_reports_a_final_error_above_epsilon(duration):
    rng = np.random.default_rng(0)
    t = np.arange(round(duration * 1000) + 1) / 1000.0
    for _ in range(50):
        entry = rng.uniform(0.0, 0.75) * duration
        error = np.where(t < entry, 0.02, rng.uniform(0.0, 0.0099, len(t)))
        metrics = series_metrics(t, error, np.zeros((len(t), 1)), 0.01)
        assert metrics["met"] and metrics["final_error"] < 0.01


def test_simulate_text_says_what_final_covers(capsys):
    code, out, _ = _run(capsys, "simulate", "rr_planar/s3_ic1", "--duration", "1")
    assert code == 0
    line = next(line for line in out.splitlines() if line.startswith("final error"))
    assert "(max over the last 0.25 s, the final quarter)" in line
    ratio = float(re.search(r"= ([0-9.e+-]+) x epsilon", line).group(1))
    assert "result       MET" in out and ratio < 1.0


def test_prismatic_joints_are_reported_in_m_and_n(capsys, tmp_path):
    urdf = tmp_path / "gantry.urdf"
    urdf.write_text(GANTRY_URDF)
    box = tmp_path / "box.yaml"
    assert _run(capsys, "init", urdf, "--out", box)[0] == 0
    code, out, err = _run(
        capsys, "simulate", "--robot", urdf, "-u", box, "--duration", "0.4", "--out", tmp_path / "r"
    )
    assert code == 0, err
    assert "epsilon = 0.01 m" in out and "rad" not in out.replace("gantry", "")
    assert re.search(
        r"torque +peak [0-9.]+ N \(largest \|u_i\|\), RMS [0-9.]+ N \(of \|\|u\|\|\), "
        r"variation [0-9.]+ N/s",
        out,
    )
    assert "phi = 1 N s/m" in out and "s/m" in out
    code, out, _ = _run(capsys, "bound", urdf, "-u", box, "--q", "0,0", "--qd", "0,0",
                        "--qd-a", "0,0", "--qdd-a", "0,0")  # fmt: skip
    rows = [line.split() for line in out.splitlines()[2:]]
    assert code == 0 and [row[-1] for row in rows] == ["N", "N"]
    from urpc.sim.results import SimulationResult

    result = SimulationResult.load(tmp_path / "r")
    assert result.info["joint_kinds"] == ["prismatic", "prismatic"]
    figures = result.plot()
    assert [a.get_ylabel() for a in figures["torque"].axes] == ["$u_{1}$ [N]", "$u_{2}$ [N]"]
    # The drives of a prismatic joint are in kg, N s/m and N (docs/joint-dynamics.md).
    box.write_text(box.read_text() + "joints:\n  x: {armature: [0.5, 1.5], damping: [1, 3]}\n")
    code, out, err = _run(capsys, "check", urdf, "-u", box)
    assert code == 0, err
    rows = {
        line.split()[1]: line.split()[-1] for line in out.splitlines() if line.startswith("  x ")
    }
    assert rows == {"armature": "kg", "damping": "s/m"}, out  # "N s/m": its last word
    error_axes = figures["error"].axes[0]
    assert error_axes.get_ylabel() == "$\\|e\\|$ [m]"
    assert "$\\varepsilon$ = 0.01 m" in error_axes.get_legend_handles_labels()[1]
    assert figures["trajectory"].axes[0].get_ylabel() == "joint position [m]"


def test_one_link_reads_one_link(capsys, tmp_path):
    urdf = tmp_path / "slider.urdf"
    start, end = GANTRY_URDF.index('  <joint name="z"'), GANTRY_URDF.index("</robot>")
    urdf.write_text(GANTRY_URDF[:start] + GANTRY_URDF[end:])  # the cart alone: one link
    code, out, _ = _run(capsys, "init", urdf, "--out", tmp_path / "box.yaml")
    assert code == 0 and out.startswith(f"wrote {tmp_path / 'box.yaml'}: ")
    assert " uncertain parameters in 1 link of gantry" in out.splitlines()[0]
    code, out, _ = _run(capsys, "check", urdf, "-u", tmp_path / "box.yaml")
    assert code == 0 and "(1 joint)" in out and " in 1 link\n" in out
