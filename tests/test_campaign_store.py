"""Campaigns that lose nothing (issue 21.2): every run recorded as it finishes, resumed after a
SIGKILL at a random point or a Ctrl-C to results equal to an uninterrupted campaign, Ctrl-C
stopping the workers within 5 s, a second campaign on a folder in use refused at start.

The scenario runs the computed-torque controller (no certificate to compute) for 0.1 s, so that
each campaign takes seconds; what is tested is the bookkeeping, which does not depend on the law.
"""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import RR_DIR

from urpc.cli import main
from urpc.errors import InputError
from urpc.studies.campaign import (
    LOCK_NAME,
    RUNS_NAME,
    STORE_NAME,
    SUMMARY_NAME,
    CampaignStore,
    campaign_settings,
    run_campaign,
)
from urpc.studies.scenario import load_scenario

RUNS = 6
#: Keys of summary.json that measure the execution (time, workers), not the results.
EXECUTION = {"wall_time", "runs_per_minute", "run_cpu_time_mean", "runs_per_minute_per_core", "workers"}  # fmt: skip


@pytest.fixture(scope="module")
def scenario_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("scenario") / "quick.yaml"
    path.write_text(
        f"name: quick\nrobot: rr_planar\nuncertainty: {RR_DIR / 'uncertainty.yaml'}\n"
        "trajectory: paper\nsample_period: 1.0e-3\ndisturbance: 10\nepsilon: 1.0e-2\n"
        "duration: 0.1\ncontroller: computed-torque\n"
    )
    return path


@pytest.fixture(scope="module")
def reference(scenario_file, tmp_path_factory):
    """The uninterrupted campaign, in this process."""
    out = tmp_path_factory.mktemp("reference") / "campaign"
    run_campaign(str(scenario_file), RUNS, workers=1, seed=3, out=out)
    return out


def _results(out: Path) -> tuple[str, dict]:
    summary = json.loads((out / SUMMARY_NAME).read_text())
    return (out / RUNS_NAME).read_text(), {k: v for k, v in summary.items() if k not in EXECUTION}


def _argv(scenario_file: Path, out: Path, *extra: str) -> list[str]:
    return [
        "campaign", str(scenario_file), "--runs", str(RUNS), "--seed", "3", "--workers", "2",
        "--out", str(out), "--no-progress", *extra,
    ]  # fmt: skip


def _start(argv: list[str]) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "urpc", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group: the workers are in it too
    )


def _recorded(out: Path) -> int:
    if not (out / STORE_NAME).exists():
        return 0
    try:
        with sqlite3.connect(out / STORE_NAME, timeout=5) as connection:
            return connection.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
    except sqlite3.OperationalError:  # the table is not created yet
        return 0


def _wait_for(out: Path, records: int, process: subprocess.Popen, timeout: float = 240.0) -> None:
    deadline = time.monotonic() + timeout
    while _recorded(out) < records:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no run recorded in time"
        time.sleep(0.05)


def _group_gone(process: subprocess.Popen, timeout: float = 5.0) -> bool:
    """Whether every process of the campaign's group (parent and workers) has exited."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            os.killpg(process.pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


def test_the_records_are_exact_and_the_outputs_built_from_them(reference, scenario_file):
    rows, summary = _results(reference)
    assert summary["runs"] == RUNS and rows.count("\n") == RUNS + 1
    scenario = load_scenario(str(scenario_file))
    settings = campaign_settings(scenario, RUNS, 3, 2.0, None)
    with CampaignStore.open(reference, settings, resume=True) as store:
        outcomes = store.outcomes()
    again = run_campaign(str(scenario_file), RUNS, workers=1, seed=3)  # no folder: in memory
    for index, outcome in enumerate(again.outcomes):
        recorded = outcomes[index]
        assert recorded.spec == outcome.spec and recorded.status == outcome.status
        for name, value in outcome.metrics.items():
            if name not in ("wall_time", "step_time_median"):
                same = recorded.metrics[name] == value or (
                    value != value and recorded.metrics[name] != recorded.metrics[name]
                )
                assert same, name


@pytest.mark.parametrize("seed", [0, 1])
def test_sigkill_at_a_random_point_keeps_the_finished_runs_and_resumes_equal(
    reference, scenario_file, tmp_path, capsys, seed
):
    out = tmp_path / "campaign"
    records = int(np.random.default_rng(seed).integers(1, RUNS))  # kill after 1..RUNS-1 records
    process = _start(_argv(scenario_file, out))
    _wait_for(out, records, process)
    time.sleep(float(np.random.default_rng(seed + 10).uniform(0.0, 0.3)))
    process.kill()
    process.communicate()
    assert _group_gone(process), "workers left running after their campaign was killed"
    kept = _recorded(out)
    assert records <= kept <= RUNS
    # Nothing half-written: the records (with SQLite's WAL) and the lock, no output yet; only a
    # kill that lands after the last run, while the outputs are written, leaves them under
    # their visible partial names (atomic.write_files), which the resumed campaign replaces.
    names = {p.name for p in out.iterdir()}
    store = {STORE_NAME, f"{STORE_NAME}-wal", f"{STORE_NAME}-shm", LOCK_NAME}
    outputs = {n for n in names - store if ".partial" in n}
    assert names <= store | outputs, names
    assert not outputs or kept == RUNS, (outputs, kept)
    # Without --resume the records are not overwritten; with it the campaign completes.
    assert main(_argv(scenario_file, out)) == 2
    assert "--resume" in capsys.readouterr().err
    assert main(_argv(scenario_file, out, "--resume", "--json")) == 0
    capsys.readouterr()
    assert _results(out) == _results(reference)


def test_ctrl_c_stops_within_5_s_keeps_the_runs_and_says_how_to_resume(
    reference, scenario_file, tmp_path, capsys
):
    out = tmp_path / "campaign"
    process = _start(_argv(scenario_file, out))
    _wait_for(out, 1, process)
    start = time.monotonic()
    os.killpg(process.pid, signal.SIGINT)  # what a terminal's Ctrl-C does
    _, err = process.communicate(timeout=30)
    stopped = time.monotonic() - start
    assert _group_gone(process, timeout=5.0 - min(stopped, 5.0) + 0.5)
    assert stopped < 5.0, stopped
    assert process.returncode == 130
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: interrupted"), err
    assert "--resume" in lines[0] and str(out) in lines[0]
    kept = _recorded(out)
    assert 1 <= kept <= RUNS and f"{kept} of {RUNS} runs" in lines[0]
    command = lines[0].split("continue with: ", 1)[1]
    assert command.startswith("urpc campaign ") and command.endswith(" --resume")
    assert main(_argv(scenario_file, out, "--resume", "--json")) == 0
    capsys.readouterr()
    assert _results(out) == _results(reference)


def test_a_second_campaign_on_a_folder_in_use_is_refused_at_start(scenario_file, tmp_path, capsys):
    out = tmp_path / "campaign"
    process = _start(_argv(scenario_file, out))
    try:
        _wait_for(out, 1, process)
        start = time.monotonic()
        assert main(_argv(scenario_file, out, "--resume")) == 2
        assert time.monotonic() - start < 5.0
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "in use by another campaign" in err and str(out) in err
    finally:
        process.kill()
        process.communicate()


def test_resume_with_other_settings_is_refused_naming_them(reference, scenario_file, capsys):
    argv = _argv(scenario_file, reference, "--resume")
    argv[argv.index("--seed") + 1] = "4"
    assert main([*argv, "--duration", "0.2"]) == 2
    err = capsys.readouterr().err
    assert "cannot resume" in err and "seed: recorded 3, now 4" in err
    assert "scenario duration: recorded 0.1, now 0.2" in err and err.count("\n") == 1


def test_a_damaged_record_file_is_one_error_line(scenario_file, tmp_path, capsys):
    out = tmp_path / "campaign"
    out.mkdir()
    (out / STORE_NAME).write_bytes(b"not a database at all" * 100)
    assert main(_argv(scenario_file, out, "--resume")) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and STORE_NAME in err


def test_resume_of_a_complete_campaign_reads_the_records_and_a_new_one_replaces_it(
    reference, scenario_file, tmp_path
):
    result = run_campaign(str(scenario_file), RUNS, workers=1, seed=3, out=reference, resume=True)
    assert result.runs == RUNS
    out = tmp_path / "campaign"
    run_campaign(str(scenario_file), 2, workers=1, seed=3, out=out)
    run_campaign(str(scenario_file), 3, workers=1, seed=4, out=out)  # finished: replaced
    assert json.loads((out / SUMMARY_NAME).read_text())["runs"] == 3


def test_an_interrupted_campaign_is_not_replaced_without_resume(scenario_file, tmp_path):
    out = tmp_path / "campaign"
    scenario = load_scenario(str(scenario_file))
    settings = campaign_settings(scenario, RUNS, 3, 2.0, None)
    done = run_campaign(str(scenario_file), RUNS, workers=1, seed=3)
    with CampaignStore.open(out, settings, resume=False) as store:
        store.add(done.outcomes[0])  # what a campaign killed after its first run leaves
    with pytest.raises(InputError, match="interrupted campaign .1 of 6 runs"):
        run_campaign(str(scenario_file), 2, workers=1, seed=3, out=out)
    result = run_campaign(str(scenario_file), RUNS, workers=1, seed=3, out=out, resume=True)
    assert result.rows() == done.rows()


def test_vertex_runs_beyond_the_runs_say_so(scenario_file, tmp_path, capsys):
    argv = ["campaign", str(scenario_file), "--runs", "2", "--vertex-runs", "5", "--workers", "1"]
    assert main([*argv, "--out", str(tmp_path / "c"), "--json"]) == 0
    out, err = capsys.readouterr()
    assert "warning: vertex_runs 5 exceeds the 2 runs: runs only 2 vertex runs" in err
    assert json.loads(out)["vertex_runs"] == 2


def test_resume_with_nothing_recorded_says_it_starts_from_the_first_run(
    scenario_file, tmp_path, capsys
):
    """``--resume`` on a folder with no recorded run (a mistyped --out, or a campaign killed
    before its first run): one warning naming the folder, then the whole campaign."""
    out = tmp_path / "typo"
    argv = ["campaign", str(scenario_file), "--runs", "2", "--workers", "1", "--json"]
    assert main([*argv, "--out", str(out), "--resume"]) == 0
    stdout, err = capsys.readouterr()
    assert f"warning: {out}: nothing to resume (no run recorded in {STORE_NAME})" in err, err
    assert json.loads(stdout)["runs"] == 2
    assert main([*argv, "--out", str(out), "--resume"]) == 0  # finished: read back, no warning
    assert "nothing to resume" not in capsys.readouterr().err
