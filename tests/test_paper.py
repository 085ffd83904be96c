"""``urpc.studies.paper.reproduce_paper`` and ``urpc reproduce-paper`` on very short runs.

References: each parallel run equals a serial in-process run of the same shipped scenario
(bit for bit); the betas equal an in-process ``estimate_betas``; the report's table and JSON agree
with each run's own ``summary.json``; the design-condition numbers follow from their formulas.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from conftest import RR_DIR

from urpc.__main__ import main
from urpc.control.r_alpha import PAPER_BETAS, estimate_betas
from urpc.model.robot import load_robot
from urpc.model.uncertainty import load_uncertainty
from urpc.sim.metrics import METRIC_NAMES
from urpc.sim.results import SimulationResult
from urpc.studies.paper import PAPER_CONTROLLERS, PAPER_RUNS, reproduce_paper
from urpc.studies.scenario import load_scenario, run_scenario

DURATION = 0.3
FIGURES = {
    "fig1_trajectory.png",
    "fig2_s1_ic1_interval.png",
    "fig3_s1_ic2_interval.png",
    "errors_s2_interval.png",
    "errors_s3_interval.png",
    "fig4_s2_ic2_comparison.png",
    "fig5_s3_ic2_comparison.png",
}


@pytest.fixture(scope="module")
def reproduction(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper") / "nested" / "paper"
    calls = []
    document = reproduce_paper(
        out, duration=DURATION, workers=2, progress=lambda *args: calls.append(args)
    )
    return out, document, calls


def test_writes_the_report_figures_and_every_run(reproduction):
    out, document, calls = reproduction
    assert {p.name for p in (out / "figures").iterdir()} == FIGURES
    for name in FIGURES:
        assert (out / "figures" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    runs = sorted(p.name for p in (out / "runs").iterdir())
    assert runs == sorted(f"s{n}_ic{ic}-{c}" for n, ic in PAPER_RUNS for c in PAPER_CONTROLLERS)
    for run in runs:  # npz and summary, no 7 MB CSV table
        assert sorted(p.name for p in (out / "runs" / run).iterdir()) == [
            "result.npz",
            "summary.json",
        ]
    assert sorted(p.name for p in out.iterdir()) == [
        "figures",
        "results.json",
        "results.md",
        "runs",
    ]
    assert [p.name for p in out.parent.iterdir()] == ["paper"]  # no staging left behind
    assert [c[0] for c in calls] == list(range(1, 13)) and {c[1] for c in calls} == {12}
    assert document["files"] == sorted(
        str(p.relative_to(out)) for p in out.rglob("*") if p.is_file()
    )


def test_results_json_has_one_summary_per_run(reproduction):
    out, document, _ = reproduction
    saved = json.loads((out / "results.json").read_text())
    assert saved["runs"] == json.loads(json.dumps(document["runs"]))
    runs = saved["runs"]
    assert [(r["scenario"], r["initial_condition"], r["controller"]) for r in runs] == [
        (n, f"IC{ic}", c) for n, ic in PAPER_RUNS for c in PAPER_CONTROLLERS
    ]
    for run in runs:
        assert {"scenario", "initial_condition", "controller", "epsilon"} <= set(run)
        assert set(METRIC_NAMES) <= set(run)
        assert run["duration"] == pytest.approx(DURATION)
        folder = (
            out
            / "runs"
            / f"s{run['scenario']}_ic{run['initial_condition'][-1]}-{run['controller']}"
        )
        summary = json.loads((folder / "summary.json").read_text())
        assert {k: run[k] for k in summary} == summary
        assert run["epsilon"] == (1e-3 if run["scenario"] == 1 else 1e-2)
        assert run["sample_period"] == {1: None, 2: 1e-4, 3: 1e-3}[run["scenario"]]


def test_the_markdown_table_shows_each_runs_own_summary(reproduction):
    """Each row of results.md, read back, is that run's summary.json: met, entry time, final
    error and phi (``-`` for r-alpha, which has none) to the printed 4 digits."""
    out, _, _ = reproduction
    lines = (out / "results.md").read_text().splitlines()
    header = next(line for line in lines if line.startswith("| scenario |"))
    columns = [c.strip() for c in header.strip("|").split("|")]
    rows = [line for line in lines[lines.index(header) + 2 :] if line.startswith("| ")][:12]
    assert len(rows) == 12
    for line in rows:
        cells = dict(zip(columns, (c.strip() for c in line.strip("|").split("|")), strict=True))
        folder = f"s{cells['scenario']}_ic{cells['IC'][-1]}-{cells['controller']}"
        summary = json.loads((out / "runs" / folder / "summary.json").read_text())
        assert cells["met"] == ("yes" if summary["met"] else "no"), folder
        for column, key in (
            ("entry time [s]", "entry_time"),
            ("final error [rad]", "final_error"),
            ("phi [N m s/rad]", "phi"),
        ):
            value = summary.get(key)
            if value is None:
                assert cells[column] == "-", (folder, column)
            else:
                assert float(cells[column]) == pytest.approx(value, rel=5e-4), (folder, column)
        assert ("phi" in summary) == (cells["controller"] == "interval")


def test_parallel_runs_equal_serial_runs(reproduction):
    out, _, _ = reproduction
    for number, ic, controller in ((3, 2, "interval"), (2, 1, "r-alpha"), (1, 2, "interval")):
        scenario = load_scenario(f"rr_planar/s{number}_ic{ic}").with_overrides(duration=DURATION)
        serial = run_scenario(scenario, controller)
        parallel = SimulationResult.load(out / "runs" / f"s{number}_ic{ic}-{controller}")
        for name in ("t", "q", "qd", "torque", "disturbance"):
            np.testing.assert_array_equal(getattr(parallel, name), getattr(serial, name))
        assert parallel.diagnostics.keys() == serial.diagnostics.keys()
        for name, series in serial.diagnostics.items():
            np.testing.assert_array_equal(parallel.diagnostics[name], series)


def test_betas_and_design_conditions(reproduction):
    _, document, _ = reproduction
    robot = load_robot("rr_planar")
    box = load_uncertainty(RR_DIR / "uncertainty.yaml", robot)
    betas = estimate_betas(robot, box, disturbance_bound=10.0)
    for name in ("beta0", "beta1", "beta2", "beta3"):
        assert document["betas"][name] == betas.as_dict()[name]
    assert document["betas"]["paper"] == PAPER_BETAS.as_dict()
    assert document["betas"]["n_samples"] == 100_000
    estimated = document["design_conditions"]["estimated_betas"]
    eta_max = 1e-2**2 * 35.0 * betas.beta0 / betas.beta1  # (alpha r)^2 lambda_min(Q) beta0/beta1
    assert estimated["eta_max"] == pytest.approx(eta_max, rel=1e-12)
    assert estimated["tolerance"] == (7e-5 <= eta_max) and estimated["rate_Q"] == (
        35 >= betas.beta1
    )
    paper = document["design_conditions"]["paper_betas"]
    assert paper["hold"] and paper["eta_max"] == pytest.approx(1e-4 * 35 * 0.86 / 34.27)


def test_markdown_table_matches_the_json(reproduction):
    out, document, _ = reproduction
    text = (out / "results.md").read_text()
    rows = [line for line in text.splitlines() if re.match(r"\| [123] \| IC", line)]
    assert len(rows) == 12
    for line, run in zip(rows, document["runs"], strict=True):
        cells = [c.strip() for c in line.strip("|").split("|")]
        assert cells[:3] == [str(run["scenario"]), run["initial_condition"], run["controller"]]
        assert cells[3] == ("yes" if run["met"] else "no")
        assert float(cells[5]) == pytest.approx(run["final_error"], rel=1e-3)
        assert float(cells[9]) == pytest.approx(run["torque_variation"], rel=1e-3)
    assert "| beta0 |" in text and "0.86" in text


def test_cli_runs_serially_and_prints_one_json_object(capsys, tmp_path):
    argv = ["reproduce-paper", "--out", str(tmp_path / "p"), "--duration", "0.05", "--workers", "1"]
    code = main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert code == 0 and err == ""
    document = json.loads(out)
    assert len(document["runs"]) == 12 and document["workers"] == 1
    assert document["out_dir"] == str(tmp_path / "p")
    assert json.loads((tmp_path / "p" / "results.json").read_text())["runs"] == document["runs"]
