"""The performance suite (``urpc.studies.benchmark.run_benchmarks``, ``urpc bench``).

Speed targets are not asserted (the machine is shared); the tests check that every figure is
there, positive and finite, on a tiny configuration that runs in a few seconds, and that the
figures agree with each other: a ratio is its two timings divided, the table prints the timings.
"""

from __future__ import annotations

import json
import math

import pytest

from urpc.__main__ import main
from urpc.studies.benchmark import (
    DEFAULT_LOOP_STEPS,
    LATENCY_KEYS,
    SUITE_KEYS,
    SuiteSettings,
    format_benchmarks,
    format_latency,
    format_profile,
    profile_control_step,
    run_benchmarks,
)

#: Quick mode restricted to the RR arm, one method, 200 loop steps, 0.1 s simulations and a 2-run
#: campaign.
TINY = SuiteSettings.quick(
    robots=("rr_planar",),
    methods=("hull",),
    repeats=3,
    loop_steps=200,
    sim_duration=0.1,
    synthesis_repeats=1,
    assemblies=("arm_3dof",),
    campaign_runs=2,
    campaign_duration=0.1,
)


def _positive_finite(value) -> bool:
    return isinstance(value, float | int) and math.isfinite(value) and value > 0


def _check_latency(row: dict, steps: int) -> None:
    """A loop-latency row: the documented keys, positive percentiles in order, the steps run."""
    assert tuple(row) == LATENCY_KEYS and row["steps"] == steps
    assert all(_positive_finite(row[key]) for key in LATENCY_KEYS)
    assert row["p50"] <= row["p99"] <= row["p99_9"] <= row["max"]


def _check_suite(result: dict) -> None:
    assert set(result) == set(SUITE_KEYS)
    assert set(result["rho"]) == set(result["rho_over_rnea"]) == {"rr_planar"}
    for figure in ("rho", "rho_over_rnea"):
        assert set(result[figure]["rr_planar"]) == {"hull"}
        assert _positive_finite(result[figure]["rr_planar"]["hull"])
    for figure in ("rnea", "control_step"):
        assert set(result[figure]) == {"rr_planar"}
        assert _positive_finite(result[figure]["rr_planar"])
    assert set(result["loop_step"]) == {"rr_planar"}
    _check_latency(result["loop_step"]["rr_planar"], TINY.loop_steps)
    assert set(result["sim_speed"]) == {"rr_planar/s2_ic1", "rr_planar/s3_ic1"}
    assert set(result["synthesis"]) == {"rr_planar", "assembly/arm_3dof"}
    for figure in ("sim_speed", "synthesis"):
        assert all(_positive_finite(v) for v in result[figure].values())
    assert _positive_finite(result["campaign_runs_per_minute"])
    # rho / RNEA is the two measured timings divided, not a separate measurement.
    ratio = result["rho"]["rr_planar"]["hull"] / result["rnea"]["rr_planar"]
    assert result["rho_over_rnea"]["rr_planar"]["hull"] == ratio
    machine = result["machine"]
    assert machine["cpu_count"] >= 1 and machine["python"] and machine["pinocchio"]


def test_quick_suite_has_every_figure_positive_and_finite():
    result = run_benchmarks(quick=True, settings=TINY)
    _check_suite(result)
    table = format_benchmarks(result, TINY)
    assert table.count("\n") == 1 + 9  # header, rule, one row per figure and case
    assert "rr_planar / hull" in table and "<= 10 us" in table
    loop = next(line for line in table.splitlines() if line.startswith("| loop step |"))
    row = result["loop_step"]["rr_planar"]
    assert "rr_planar, 200 steps (p50 / p99 / p99.9 / max)" in loop
    assert f"{1e6 * row['p50']:.1f} / {1e6 * row['p99']:.1f} / " in loop
    row = next(line for line in table.splitlines() if "rr_planar / hull" in line)
    assert f"{1e6 * result['rho']['rr_planar']['hull']:.1f}" in row  # the measured rho, in us


def test_cli_bench_json_prints_one_object(capsys, monkeypatch):
    monkeypatch.setattr(SuiteSettings, "quick", classmethod(lambda cls, **changes: TINY))
    assert main(["bench", "--quick", "--json", "--no-progress"]) == 0
    out, err = capsys.readouterr()
    _check_suite(json.loads(out))
    assert err == ""


def test_cli_bench_loop_steps_flag_reaches_the_suite(capsys, monkeypatch):
    monkeypatch.setattr(SuiteSettings, "quick", classmethod(lambda cls, **changes: TINY))
    assert main(["bench", "--quick", "--json", "--no-progress", "--loop-steps", "150"]) == 0
    result = json.loads(capsys.readouterr().out)
    _check_latency(result["loop_step"]["rr_planar"], 150)


def test_cli_bench_loop_prints_the_latency_table(capsys):
    from urpc.cli.bench import DEFAULT_LOOP_STEPS as CLI_DEFAULT

    assert CLI_DEFAULT == DEFAULT_LOOP_STEPS == SuiteSettings().loop_steps
    assert main(["bench", "loop", "--robots", "rr_planar", "--steps", "200", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert set(result) == {"machine", "loop_step"} and set(result["loop_step"]) == {"rr_planar"}
    _check_latency(result["loop_step"]["rr_planar"], 200)
    assert main(["bench", "loop", "--robots", "rr_planar", "--steps", "100"]) == 0
    out = capsys.readouterr().out
    assert "| robot | step p50 [us] | p99 [us] | p99.9 [us] | max [us] | one RNEA [us]" in out
    assert out.count("| rr_planar |") == 1
    assert format_latency({}).count("\n") == 1  # header and rule only


@pytest.mark.parametrize("argv", [["bench", "bounds", "--json"], ["bench", "--json", "bounds"]])
def test_cli_bench_bounds_json(capsys, argv):
    code = main([*argv, "--robots", "rr_planar", "--repeats", "3"])
    out, _ = capsys.readouterr()
    result = json.loads(out)
    assert code == 0 and {"rho", "rho_over_rnea", "rnea", "machine"} <= set(result)
    for figure in ("rho", "rho_over_rnea"):
        assert set(result[figure]["rr_planar"]) == {"hull", "vertex", "rigorous"}
        assert all(_positive_finite(v) for v in result[figure]["rr_planar"].values())


@pytest.mark.parametrize(
    "argv",
    [
        ["bench", "bounds", "--robots", "atlas"],
        ["bench", "bounds", "--methods", "exact", "--robots", "rr_planar"],
        ["bench", "bounds", "--repeats", "0"],
        ["bench", "--repeats", "3"],
        ["bench", "--loop-steps", "0"],
        ["bench", "loop", "--robots", "atlas"],
        ["bench", "loop", "--steps", "-5"],
    ],
)
def test_cli_bench_bad_input_exits_2_with_one_line(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith("error:") and err.count("\n") == 1


def test_profile_control_step_parts():
    profile = profile_control_step(["rr_planar"], repeats=3)
    times = profile["rr_planar"]
    for part in ("output", "regressor", "bound", "nominal", "arithmetic", "rnea"):
        assert _positive_finite(times[part])
    assert "sampled_law" not in times  # the RR arm's scenario runs the paper's law
    assert "rr_planar" in format_profile(profile)


def test_profile_control_step_of_the_implicit_law():
    """The Panda's 1 kHz scenario runs the implicit law: its parts and the paper-law step."""
    times = profile_control_step(["panda"], repeats=3)["panda"]
    for part in ("output", "output_paper_law", "sampled_law", "inertia", "crba", "solve"):
        assert _positive_finite(times[part]), part


def test_cli_bench_certificate_prints_the_cost_next_to_the_control_steps(capsys):
    assert main(["bench", "certificate", "--arms", "chain3", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["certificate"]
    assert [r["arm"] for r in rows] == ["chain3"] and rows[0]["dof"] == 3
    row = rows[0]
    assert row["certify_s"] > 0 and row["steps_s"] > 0
    assert row["ratio"] == pytest.approx(row["certify_s"] / row["steps_s"])
    assert row["cells"] >= 8 and isinstance(row["certified"], bool)


def test_cli_bench_certificate_refuses_an_unknown_arm(capsys):
    assert main(["bench", "certificate", "--arms", "atlas"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and "chainN" in err and "ur5" in err
