"""``urpc simulate``: scenario files and direct mode, overrides, --json, --out, the error contract.

References: the metrics the CLI prints are those of an in-process ``run_scenario`` of the same
scenario; the true parameters it states are those of ``sample_true_parameters`` and the shipped
parameter file; a diverging run is a real one (computed torque with a far too stiff gain for its
sampling period).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import RR_DIR

from urpc.__main__ import main
from urpc.model.inertia import inertia_problem
from urpc.sim.metrics import METRIC_NAMES
from urpc.sim.results import SimulationResult
from urpc.studies.scenario import build, load_scenario, run_scenario, sample_true_parameters

SUMMARY_KEYS = {  # "phi", "kappa": the interval law's diagnostics
    *METRIC_NAMES, "phi", "kappa", "epsilon", "controller", "scenario", "plant", "true_parameters",
    "certified", "not_certified", "certificate", "final_error_window", "actuation_delay",
    "disturbance_model",
}  # fmt: skip
TIMINGS = ("step_time_median", "wall_time")


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _json(capsys, *argv) -> dict:
    code, out, err = _run(capsys, *argv, "--json")
    assert code == 0, err
    # No progress bar when stderr is not a terminal; only warnings (e.g. "not certified").
    assert all(line.startswith("warning: ") for line in err.splitlines()), err
    return json.loads(out)  # exactly one JSON object


def test_shipped_scenario_json_matches_an_in_process_run(capsys):
    summary = _json(capsys, "simulate", "rr_planar/s3_ic2", "--duration", "0.5")
    assert set(summary) == SUMMARY_KEYS
    assert summary["controller"] == "interval" and summary["epsilon"] == 0.01
    assert summary["scenario"] == "s3_ic2" and summary["plant"] == "pinocchio"
    # The shipped s3 runs the paper's law (the reproduction): not certified, and it says why.
    assert summary["certified"] is False and "paper law" in summary["not_certified"]
    assert summary["true_parameters"]["inside_box"] is True
    assert summary["true_parameters"]["values"] == {
        "link2": {"mass": 10.0, "com_x": 0.525, "iyy": pytest.approx(20 / 12)}
    }
    reference = run_scenario(load_scenario("rr_planar/s3_ic2").with_overrides(duration=0.5))
    for name in METRIC_NAMES:
        if name not in TIMINGS:
            assert summary[name] == reference.metrics[name], name


def test_flags_override_the_scenario_file(capsys):
    summary = _json(
        capsys, "simulate", "rr_planar/s2_ic1", "--controller", "r-alpha", "--epsilon", "0.05",
        "--sample-period", "1e-3", "--duration", "0.2", "--seed", "3",
    )  # fmt: skip
    assert summary["controller"] == "r-alpha" and summary["epsilon"] == 0.05
    assert "phi" not in summary and "kappa" not in summary  # r-alpha has no diagnostics
    scenario = load_scenario("rr_planar/s2_ic1").with_overrides(
        controller="r-alpha", epsilon=0.05, sample_period=1e-3, duration=0.2, seed=3
    )
    reference = run_scenario(scenario)
    assert summary["torque_variation"] == reference.metrics["torque_variation"]


@pytest.mark.parametrize("model", ["against", "worst", "lightest"])
def test_the_disturbance_model_flag_runs_the_adversary_at_its_bound(capsys, tmp_path, model):
    """``--disturbance-model``: the run's disturbance has the bound's norm at every sample
    where it acts (``against`` and ``worst`` vanish where ``r = 0``, at most the first sample
    here, which starts on the reference), it is the in-process run of the same scenario with
    ``disturbance_model`` set, and the summary says which."""
    out = tmp_path / model
    argv = ("simulate", "rr_planar/s3_ic1", "--disturbance-model", model, "--duration", "0.3",
            "--no-certify", "--out", out)  # fmt: skip
    summary = _json(capsys, *argv)
    assert summary["disturbance_model"] == model
    result = SimulationResult.load(out)
    norms = np.linalg.norm(result.disturbance[1:-1], axis=1)
    assert np.allclose(norms, 10.0, rtol=1e-12), norms.min()
    scenario = load_scenario("rr_planar/s3_ic1").with_overrides(
        disturbance_model=model, duration=0.3
    )
    reference = run_scenario(scenario)
    assert np.array_equal(reference.disturbance, result.disturbance)
    assert summary["final_error"] == reference.metrics["final_error"]


def test_out_writes_result_files_and_figures(capsys, tmp_path):
    out = tmp_path / "deep" / "run"
    code, text, err = _run(
        capsys, "simulate", "rr_planar/s3_ic1", "--duration", "0.3", "--out", out
    )
    assert code == 0 and err.startswith("warning: NOT certified") and len(err.splitlines()) == 1
    assert "MET" in text and f"saved        {out}" in text
    # gains.png is new: the adaptive gains over time
    assert sorted(p.name for p in out.iterdir()) == [
        "certificate.json", "error.png", "gains.png", "result.csv", "result.npz",
        "scenario.yaml", "summary.json", "torque.png", "trajectory.png",
    ]  # fmt: skip
    assert json.loads((out / "certificate.json").read_text())["certified"] is False
    for name in ("error.png", "gains.png", "torque.png", "trajectory.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    loaded = SimulationResult.load(out)
    assert loaded.duration == pytest.approx(0.3) and loaded.info["plant"] == "pinocchio"
    saved = json.loads((out / "summary.json").read_text())
    metrics = json.loads(json.dumps(loaded.summary()))
    assert {key: saved[key] for key in metrics} == metrics
    # summary.json is what --json prints: the guarantee and the true plant too (issue 21.7)
    assert set(saved) == SUMMARY_KEYS and saved["certified"] is False
    assert saved["true_parameters"]["inside_box"] is True
    # the saved scenario reproduces the run
    rerun = run_scenario(load_scenario(out / "scenario.yaml"))
    np.testing.assert_array_equal(rerun.q, loaded.q)


def test_out_is_all_or_nothing(capsys, tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    def broken(self, path, **kwargs):
        Path(path).write_bytes(b"half a figure")
        raise OSError("disk full")

    monkeypatch.setattr(Figure, "savefig", broken)
    out = tmp_path / "run"
    code, text, err = _run(
        capsys, "simulate", "rr_planar/s3_ic1", "--duration", "0.05", "--out", out
    )
    warning, error = err.splitlines()  # the run is not certified (paper law), then the error
    assert code == 2 and text == "" and warning.startswith("warning: NOT certified")
    assert error.startswith("error: ") and "disk full" in error and str(out) in error
    assert list(tmp_path.iterdir()) == []


def test_direct_mode_states_a_seeded_consistent_true_plant(capsys):
    summary = _json(capsys, "simulate", "--robot", "rr_planar", "--duration", "0.3")
    assert set(summary) == SUMMARY_KEYS and summary["scenario"] == "rr_planar"
    assert summary["epsilon"] == 0.01  # the defaults
    values = summary["true_parameters"]["values"]["link2"]
    assert set(values) == {"mass", "com_x", "iyy"}
    scenario = load_scenario("rr_planar/s3_ic1")  # only for the rr box
    box = build(scenario).box
    drawn = sample_true_parameters(box, seed=0).links["link2"]
    link = box.link_box("link2")
    for name, value in values.items():
        k = link.fields.index(name)
        assert value == drawn[k] and link.lower[k] <= value <= link.upper[k]
    assert inertia_problem(np.asarray(link.inertia(drawn).inertia)) is None
    assert "mass = " in summary["true_parameters"]["description"]
    other = _json(capsys, "simulate", "--robot", "rr_planar", "--duration", "0.1", "--seed", "4")
    assert other["true_parameters"]["values"] != summary["true_parameters"]["values"]


def test_direct_mode_with_files_and_continuous_time(capsys, tmp_path):
    summary = _json(
        capsys, "simulate", "--robot", RR_DIR / "rr_planar.urdf", "--uncertainty",
        RR_DIR / "uncertainty.yaml", "--true-params", RR_DIR / "true_parameters.yaml",
        "--continuous", "--epsilon", "1e-3", "--duration", "0.2",
    )  # fmt: skip
    assert summary["scenario"] == "rr_planar" and summary["epsilon"] == 1e-3
    assert summary["true_parameters"]["values"]["link2"]["mass"] == 10.0


def test_direct_mode_on_a_six_joint_arm(capsys):
    text = _run(capsys, "simulate", "--robot", "ur5", "--duration", "0.2")[1]
    assert "ur5 (6 joints)" in text and "payload: mass = " in text
    summary = _json(capsys, "simulate", "--robot", "ur5", "--duration", "0.2", "--method", "hull")
    assert summary["final_error"] < summary["epsilon"]  # starts on the reference, stays close


def _diverging_scenario(tmp_path: Path) -> Path:
    """Computed torque with omega_n = 1e4 rad/s at 1 kHz: the sampled loop is unstable."""
    document = {
        "robot": "rr_planar",
        "uncertainty": str(RR_DIR / "uncertainty.yaml"),
        "true_parameters": "nominal",
        "controller": "computed-torque",
        "controller_options": {"computed-torque": {"natural_frequency": 1e4}},
        "initial_condition": {"offset": [1e-3, 0]},
        "duration": 1.0,
    }
    path = tmp_path / "stiff.yaml"
    path.write_text(yaml.safe_dump(document))
    return path


@pytest.mark.parametrize(
    "argv, message",
    [
        (["simulate", "no/such/scenario.yaml"], "no such scenario file"),
        (["simulate", "ur10"], "'ur10' is a robot, not a scenario: give it as --robot ur10 and"),
        (["certify", "ur5"], "give it as --robot ur5, or one of its shipped scenarios: ur5/"),
        (["simulate", "rr_planar/s2_ic1", "--epsilon", "-1"], "field 'epsilon'"),
        (["simulate", "rr_planar/s2_ic1", "--epsilon", "tiny"], "not a finite number"),
        (["simulate", "rr_planar/s2_ic1", "--controller", "pid"], "--controller: invalid choice: 'pid'"),
        (["simulate", "rr_planar/s2_ic1", "--plant", "bullet"], "--plant: invalid choice: 'bullet'"),
        (["simulate", "rr_planar/s1_ic1", "--plant", "mujoco"], "continuous time"),
        (["simulate", "rr_planar/s2_ic1", "--method", "exact"], "--method: invalid choice: 'exact'"),
        (["simulate", "rr_planar/s2_ic1", "--duration", "0"], "must be > 0"),
        (["simulate", "rr_planar/s2_ic1", "--seed", "x"], "invalid int value"),
        (["simulate", "rr_planar/s2_ic1", "--continuous", "--sample-period", "1e-3"], "not allowed"),
        (["simulate"], "give a scenario file"),
        (["simulate", "--robot", "rr_planer"], "did you mean 'rr_planar'"),
        (["simulate", "--robot", "ur10"], "no shipped uncertainty box"),
        (["simulate", "--robot", "rr_planar", "--torque-limit", "10,-1"], "> 0"),
        (["reproduce-paper", "--duration", "-1"], "must be a finite number > 0"),
        (["reproduce-paper", "--workers", "0"], "integer >= 1"),
    ],
)  # fmt: skip
def test_bad_input_exits_2_with_one_line(capsys, argv, message):
    code, out, err = _run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and err.count("\n") == 1
    assert message in err


def test_a_diverging_run_exits_2_naming_time_and_state(capsys, tmp_path):
    out = tmp_path / "run"
    code, text, err = _run(capsys, "simulate", _diverging_scenario(tmp_path), "--out", out)
    warning, err = err.splitlines()  # computed torque carries no guarantee, then the error
    assert code == 2 and text == "" and warning.startswith("warning: not certified")
    assert err.startswith("error: the simulation diverged at t = ")
    assert "q = " in err and "qd = " in err
    assert not out.exists()


def test_mujoco_plant_gives_nearly_the_same_run(capsys):
    pytest.importorskip("mujoco")
    argv = ("simulate", "rr_planar/s3_ic2", "--duration", "0.3")
    pinocchio = _json(capsys, *argv)
    mujoco = _json(capsys, *argv, "--plant", "mujoco")
    assert mujoco["plant"] == "mujoco" and pinocchio["plant"] == "pinocchio"
    assert mujoco["entry_time"] == pinocchio["entry_time"]
    for name in ("final_error", "max_error_after_entry", "torque_rms", "torque_peak", "phi"):
        assert mujoco[name] == pytest.approx(pinocchio[name], rel=1e-6), name
    # the chattering index differences every sample: rounding shows most there
    assert mujoco["torque_variation"] == pytest.approx(pinocchio["torque_variation"], rel=1e-4)


def test_help_lists_the_simulation_commands(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--help"])
    out = capsys.readouterr().out
    assert info.value.code == 0 and "simulate" in out and "reproduce-paper" in out
