"""Hostile option values (a fuzzing helper's findings): values that passed every check and then
exhausted the memory or hung, paths the file system refuses, an empty path, and a Ctrl-C during
the import that a third-party library swallows. Each is one ``error:`` line and exit code 2 in
the CLI (an ``InputError`` in the API), before any work and with nothing written."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from conftest import RR_DIR

import urpc
from urpc.cli import main
from urpc.errors import InputError
from urpc.studies.campaign import run_campaign
from urpc.studies.campaign.run import MAX_RUNS
from urpc.studies.scenario import load_scenario
from urpc.trajectories import PaperTrajectory


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _one_error_line(code, out, err, *words):
    assert code == 2 and out == "" and err.startswith("error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    for word in words:
        assert word in err, f"{word!r} not in {err!r}"


@pytest.mark.parametrize(
    "command",
    [
        ("check", "rr_planar", "-u", "{long}.yaml"),
        ("simulate", "rr_planar/s3_ic1", "--no-certify", "--duration", "0.01", "--out", "{long}"),
        ("init", "rr_planar", "--out", "{long}.yaml"),
    ],
)
def test_a_name_too_long_for_the_file_system_is_one_error_line(capsys, tmp_path, command):
    long = tmp_path / ("a" * 300)
    argv = [part.format(long=long) for part in command]
    _one_error_line(*_run(capsys, *argv), "shorter path")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "command",
    [
        ("simulate", "rr_planar/s3_ic1", "--no-certify", "--duration", "0.01"),
        ("campaign", "rr_planar/s3_ic1", "--no-certify", "--duration", "0.01", "--runs", "1"),
        ("init", "rr_planar"),
    ],
)
def test_an_empty_out_is_refused_not_read_as_the_current_folder(
    capsys, tmp_path, monkeypatch, command
):
    monkeypatch.chdir(tmp_path)
    _one_error_line(*_run(capsys, *command, "--out", ""), "--out", "empty path")
    assert list(tmp_path.iterdir()) == []


def test_a_delay_longer_than_the_run_is_refused():
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    with pytest.raises(InputError, match="actuation_delay.*longer than the run.*at most 50"):
        urpc.simulate(robot, controller, PaperTrajectory(), duration=0.05, actuation_delay=10**11)


def test_campaign_counts_and_spreads_that_cannot_be_drawn_are_refused_at_once(tmp_path):
    scenario = load_scenario(RR_DIR / "scenarios" / "s3_ic1.yaml")
    with pytest.raises(InputError, match=f"at most {MAX_RUNS}"):
        run_campaign(scenario, 10**14, out=tmp_path / "huge")
    with pytest.raises(InputError, match="ic_spread.*at most 100"):
        run_campaign(scenario, 1, ic_spread=1e300, out=tmp_path / "spread")
    assert list(tmp_path.iterdir()) == []


def test_a_scheduler_of_another_protocol_is_refused_at_once(tmp_path):
    pytest.importorskip("distributed")
    scenario = load_scenario(RR_DIR / "scenarios" / "s3_ic1.yaml")
    for address in ("udp://127.0.0.1:8786", "inproc://nothing", "ws://127.0.0.1:1"):
        with pytest.raises(InputError, match="is not tcp:// or tls://"):
            run_campaign(scenario, 1, scheduler=address)


def test_an_epsilon_below_the_rounding_of_q_is_refused():
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    with pytest.raises(InputError, match="epsilon.*>= 1e-12"):
        urpc.synthesize(robot, box, 1e-300)
    assert urpc.synthesize(robot, box, 1e-12).epsilon == 1e-12


@pytest.mark.parametrize("option", [("--rate", "1e9"), ("--frequency", "1e-9")])
def test_an_exciting_trajectory_too_long_to_write_is_refused(capsys, tmp_path, option):
    out = tmp_path / "x.csv"
    _one_error_line(
        *_run(capsys, "identify", "rr_planar", "--excite", "--out", out, *option), "--rate"
    )
    assert not out.exists()


def test_identify_names_an_unknown_payload_link(capsys, tmp_path):
    data = tmp_path / "d.csv"
    data.write_text("t,q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2\n0,0,0,0,0,0,0,0,0\n")
    code, out, err = _run(
        capsys, "identify", "rr_planar", "--data", data, "--torque-noise", "1",
        "--payload", "link9", "--out", tmp_path / "x.yaml",
    )  # fmt: skip
    _one_error_line(code, out, err, "'link9' is not a link of rr_planar", "link2")


def test_virtual_robot_lists_its_words_for_an_unknown_true_point(capsys):
    code, out, err = _run(
        capsys, "virtual-robot", "rr_planar", "--port", "47399", "--true-params", "samples"
    )
    _one_error_line(code, out, err, "'sample'", "'nominal'")


def test_a_ctrl_c_during_the_urdf_library_import_is_delivered_after_it(tmp_path):
    """trimesh (imported by yourdfpy) catches every exception of its optional imports, a
    KeyboardInterrupt too: a Ctrl-C there used to leave a half-imported library and a TypeError
    traceback. Here a SIGINT arrives in the middle of trimesh's import: it must surface as a
    KeyboardInterrupt once yourdfpy is imported whole."""
    script = textwrap.dedent(
        """
        import os, signal, sys
        import importlib.abc

        # A terminal's Ctrl-C (a background job of a script starts with SIGINT ignored).
        signal.signal(signal.SIGINT, signal.default_int_handler)

        class Interrupt(importlib.abc.MetaPathFinder):
            def find_spec(self, name, path, target=None):
                if name == "trimesh.path":  # imported under "except BaseException"
                    sys.meta_path.remove(self)
                    os.kill(os.getpid(), signal.SIGINT)
                return None

        sys.meta_path.insert(0, Interrupt())
        from urpc.model.urdf import yourdfpy_module
        try:
            module = yourdfpy_module()
        except KeyboardInterrupt:
            import types
            import trimesh
            import yourdfpy
            assert callable(yourdfpy.URDF.load) and isinstance(trimesh.path, types.ModuleType)
            print("interrupted after the import")
        else:
            print("not interrupted")
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
        env={**os.environ, "PYTHONWARNINGS": "ignore", "OPENBLAS_NUM_THREADS": "2"},
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "interrupted after the import", done.stdout + done.stderr[-2000:]


def test_a_delay_as_long_as_the_run_is_accepted():
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    result = urpc.simulate(
        robot, controller, PaperTrajectory(), duration=0.05, actuation_delay=50,
        q0=np.zeros(2),
    )  # fmt: skip
    assert result.info["actuation_delay"] == 50
