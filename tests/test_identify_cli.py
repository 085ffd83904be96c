"""``urpc identify`` on the command line, and the excitation trajectory."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

import urpc
from urpc.cli import main
from urpc.identify import excite
from urpc.identify.data import read_columns, write_csv
from urpc.identify.simulated import plant_torques

PAYLOAD = np.array([2.0, 0.01, -0.01, 0.05, 0.003, 0.0, 0.004, 0.0, 0.0, 0.0035])


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """An excitation trajectory written by the CLI, and the UR5 with a 2 kg payload recorded
    along it (with and without qd/qdd columns)."""
    folder = tmp_path_factory.mktemp("identify")
    trajectory = folder / "traj.csv"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["identify", "--excite", "ur5", "--payload", "tool0", "--out",
                     str(trajectory), "--rate", "50", "--json"]) == 0  # fmt: skip
    (folder / "excite.json").write_text(printed.getvalue())
    robot = urpc.load_robot("ur5")
    prior = urpc.load_uncertainty("ur5", robot)
    columns = read_columns(trajectory)
    state = [np.column_stack([columns[f"{p}{i}"] for i in range(1, 7)]) for p in ("q", "qd", "qdd")]
    tau = plant_torques(prior.plant(robot, {"payload": PAYLOAD}), *state)
    tau += np.random.default_rng(0).uniform(-0.3, 0.3, tau.shape)
    full = dict(columns) | {f"tau{i + 1}": tau[:, i] for i in range(6)}
    (folder / "rec.csv").write_text(write_csv(None, full))
    positions = {k: v for k, v in full.items() if not k.startswith("qd")}
    (folder / "rec_q.csv").write_text(write_csv(None, positions))
    np.savez(folder / "rec.npz", **full)
    return folder


def test_excite_writes_a_trajectory_inside_the_limits(recorded, capsys):
    robot = urpc.load_robot("ur5")
    columns = read_columns(recorded / "traj.csv")
    q = np.column_stack([columns[f"q{i}"] for i in range(1, 7)])
    qd = np.column_stack([columns[f"qd{i}"] for i in range(1, 7)])
    lower, upper = robot.position_limits
    assert np.all(q >= lower) and np.all(q <= upper)
    assert np.all(np.abs(qd) <= 0.5 * robot.velocity_limit + 1e-12)
    assert columns["t"][-1] == pytest.approx(10.0)


def test_excitation_is_well_conditioned_and_its_bounds_hold():
    robot = urpc.load_robot("ur5")
    result = excite(robot, payload="tool0", starts=1, evaluations=100)
    assert result.rank == 10 and result.condition < 20
    trajectory = result.trajectory
    t = np.linspace(0, 10, 20001)
    q, qd, qdd = trajectory.evaluate(t)
    # Independent reference: the derivatives' bounds against finite differences of qdd.
    h = t[1] - t[0]
    jerk = np.gradient(qdd, h, axis=0)
    snap = np.gradient(jerk, h, axis=0)
    assert np.all(np.abs(jerk).max(axis=0) <= result.jerk * (1 + 1e-6))
    assert np.all(np.abs(snap[2:-2]).max(axis=0) <= result.snap * (1 + 1e-3))
    assert np.allclose(np.gradient(q, h, axis=0)[1:-1], qd[1:-1], atol=1e-5)


def test_full_robot_excitation_reports_the_base_parameters():
    robot = urpc.load_robot("rr_planar")
    result = excite(robot, starts=1, evaluations=60)
    # The planar RR arm's inertial parameters: 20 columns, of which few combinations enter.
    assert 3 <= result.rank < 20
    assert len(result.base) == result.rank
    assert any("does not enter" in line for line in result.combinations)


@pytest.mark.parametrize("name", ["rec.csv", "rec.npz"])
def test_identify_writes_a_box_that_check_reads(recorded, name, capsys):
    out = recorded / f"box_{name}.yaml"
    code = main(["identify", "ur5", "--data", str(recorded / name), "--prior", "ur5",
                 "--torque-noise", "0.3", "--payload", "tool0", "--out", str(out), "--json"])  # fmt: skip
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["rank"] == 10 and summary["samples"] == 501
    robot = urpc.load_robot("ur5")
    box = urpc.load_uncertainty(str(out), robot)
    payload = box.link_box("payload")
    assert np.all(payload.lower <= PAYLOAD) and np.all(PAYLOAD <= payload.upper)
    assert payload.upper[0] - payload.lower[0] < 0.01
    text = out.read_text()
    assert "identified," in text and "% of the prior width" in text
    assert "wrist_1_link" in text and "prior, unchanged" in text


def test_identify_from_positions_only(recorded, capsys):
    out = recorded / "box_q.yaml"
    excitation = json.loads((recorded / "excite.json").read_text())
    jerk, snap = max(excitation["jerk_bound"]), max(excitation["snap_bound"])
    args = ["identify", "ur5", "--data", str(recorded / "rec_q.csv"), "--torque-noise", "0.3",
            "--payload", "tool0", "--out", str(out)]  # fmt: skip
    assert main(args) == 2
    assert "--jerk-bound" in capsys.readouterr().err
    assert main([*args, "--jerk-bound", str(jerk), "--snap-bound", str(snap)]) == 0
    box = urpc.load_uncertainty(str(out), urpc.load_robot("ur5"))
    payload = box.link_box("payload")
    assert np.all(payload.lower <= PAYLOAD) and np.all(PAYLOAD <= payload.upper)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--data", "missing.csv", "--torque-noise", "1"], "missing.csv: file does not exist"),
        (["--data", "{traj}", "--torque-noise", "1"], "missing column 'tau1'"),
        (["--data", "{rec}"], "--torque-noise"),
        (["--data", "{rec}", "--torque-noise", "1,2"], "one per joint"),
        (["--data", "{rec}", "--torque-noise", "nan"], "finite numbers"),
        (["--data", "{rec}", "--torque-noise", "1", "--payload", "wrist_2_link"], "valid: tool0"),
        (
            ["--data", "{rec}", "--torque-noise", "0.001", "--payload", "tool0"],
            "no parameter vector",
        ),
        (["--data", "{rec}", "--torque-noise", "1", "--prior", "rr_planar"], "this box is for"),
        ([], "give --data"),
    ],
)
def test_bad_input_gives_one_error_line(recorded, tmp_path, capsys, extra, message):
    extra = [e.format(traj=recorded / "traj.csv", rec=recorded / "rec.csv") for e in extra]
    code = main(["identify", "ur5", *extra, "--out", str(tmp_path / "box.yaml")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("error:") and message in err[0], err


def test_wrong_joint_count_and_nan_name_the_file_and_column(recorded, tmp_path, capsys):
    rec = recorded / "rec.csv"
    assert main(["identify", "rr_planar", "--data", str(rec), "--torque-noise", "1",
                 "--out", str(tmp_path / "b.yaml")]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert "rec.csv: field 'q3'" in err and "2 joints (joint1, joint2)" in err
    lines = rec.read_text().splitlines()
    header = lines[0].split(",")
    row = lines[5].split(",")
    row[header.index("tau2")] = "nan"
    bad = tmp_path / "nan.csv"
    bad.write_text("\n".join([lines[0], *lines[1:5], ",".join(row), *lines[6:]]) + "\n")
    assert main(["identify", "ur5", "--data", str(bad), "--torque-noise", "1",
                 "--out", str(tmp_path / "b.yaml")]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert "nan.csv: field 'tau2'" in err and "finite" in err
