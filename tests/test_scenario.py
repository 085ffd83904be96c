"""Scenario files: the shipped paper scenarios, validation errors, overrides, building."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import RR_DIR

from urpc.control.computed_torque import ComputedTorqueController
from urpc.control.r_alpha import PAPER_BETAS, RAlphaController
from urpc.errors import InputError
from urpc.model.point import ParameterPoint
from urpc.studies.scenario import (
    CONTROLLERS,
    PLANT_BACKENDS,
    build,
    build_controller,
    interval_synthesis_options,
    load_scenario,
    parse_scenario,
    run_scenario,
    shipped_scenarios,
    simulate_setup,
    true_parameter_values,
)
from urpc.trajectories import PaperTrajectory, QuinticTrajectory, SinusoidTrajectory

#: Table II: sample period [s] (None: continuous), disturbance bound [N m], epsilon [rad].
TABLE_II = {1: (None, 0.0, 1e-3), 2: (1e-4, 10.0, 1e-2), 3: (1e-3, 10.0, 1e-2)}


def test_the_six_paper_scenarios_are_shipped():
    names = [name for name in shipped_scenarios() if name.startswith("rr_planar/")]
    assert names == [f"rr_planar/s{k}_ic{i}" for k in (1, 2, 3) for i in (1, 2)]


@pytest.mark.parametrize("number", [1, 2, 3])
@pytest.mark.parametrize("ic", [1, 2])
def test_paper_scenarios_load_and_build(number, ic):
    scenario = load_scenario(f"rr_planar/s{number}_ic{ic}")
    period, disturbance, epsilon = TABLE_II[number]
    assert scenario.name == f"s{number}_ic{ic}"
    assert scenario.sample_period == period and scenario.continuous == (period is None)
    assert scenario.disturbance == disturbance and scenario.epsilon == epsilon
    assert scenario.duration == 10.0 and scenario.controller == "interval"
    # The shipped scenario names the RR arm's box; after a plain install it is the packaged copy.
    assert scenario.uncertainty.name == "uncertainty.yaml"
    assert scenario.uncertainty.read_bytes() == (RR_DIR / "uncertainty.yaml").read_bytes()
    paper_gains = {"kappa_P": 2.0, "kappa_I": 1.0, "phi_P": 1.0, "phi_I": 1e6}
    # Sampled paper scenarios run the paper's law unchanged (not the sampled-data law).
    if period is not None:
        paper_gains["sampled_law"] = "paper"
    assert scenario.options == paper_gains
    r_alpha = scenario.controller_options.by_controller()["r-alpha"]
    assert (r_alpha["r"], r_alpha["alpha"], r_alpha["Q"], r_alpha["eta"]) == (1e-2, 1, 35, 7e-5)

    setup = build(scenario)
    assert isinstance(setup.trajectory, PaperTrajectory)
    np.testing.assert_allclose(setup.q0, [0, 0] if ic == 1 else [2 * epsilon, -2 * epsilon])
    np.testing.assert_allclose(setup.qd0, [0, 0])
    # the true plant is Table I's vertex m2 = 10, I2 = 20/12, lc2 = 0.525; link 1 unchanged
    link2 = setup.plant.link("link2").inertia
    assert link2.mass == pytest.approx(10.0)
    assert link2.lever[0] == pytest.approx(0.525)
    assert link2.inertia[1, 1] == pytest.approx(20 / 12)
    assert setup.robot.link("link2").inertia.mass == pytest.approx(5.0)
    assert setup.box.disturbance_bound is None  # unknown to the controller (Theorem 2)
    assert setup.torque_limit is None


def test_shipped_scenario_by_path_and_errors_for_unknown_names():
    path = shipped_scenarios()["rr_planar/s3_ic1"]
    assert load_scenario(path) == load_scenario("rr_planar/s3_ic1")
    with pytest.raises(InputError, match="did you mean 'rr_planar/s3_ic1'"):
        load_scenario("rr_planar/s3-ic1")


def write(tmp_path: Path, document: dict, name: str = "scenario.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(document))
    return path


def minimal(**extra) -> dict:
    document = {"robot": "rr_planar", "uncertainty": str(RR_DIR / "uncertainty.yaml")}
    document.update(extra)
    return document


BAD = [
    ({"epsilom": 1e-2}, "epsilom", "did you mean 'epsilon'"),
    ({"epsilon": -1e-3}, "epsilon", "must be > 0"),
    ({"epsilon": "small"}, "epsilon", "not a finite number"),
    ({"duration": 0}, "duration", "must be > 0"),
    ({"sample_period": 0.0}, "sample_period", "must be > 0"),
    ({"sample_period": "discrete"}, "sample_period", "continuous"),
    ({"sample_period": 20.0, "duration": 10.0}, "duration", "shorter than one sample period"),
    ({"sample_period": "continuous", "disturbance": 5}, "disturbance", "per control sample"),
    ({"disturbance": -1}, "disturbance", ">= 0"),
    ({"controller": "pid"}, "controller", "valid: computed-torque, interval, r-alpha"),
    (
        {"trajectory": "circle"},
        "trajectory.kind",
        "valid: file, paper, quintic, sinusoid, waypoints",
    ),
    ({"trajectory": {"kind": "paper", "amplitud": [1, 2]}}, "trajectory.amplitud", "amplitude"),
    ({"initial_condition": {"q": [0, 0]}}, "initial_condition.q", "valid: offset, q0, qd0"),
    (
        {"initial_condition": {"q0": [0, 0], "offset": [0, 0]}},
        "initial_condition.offset",
        "not both",
    ),
    ({"initial_condition": {"q0": 0.1}}, "initial_condition.q0", "list of numbers"),
    ({"true_parameters": "missing.yaml"}, "true_parameters", "'sample' or 'nominal'"),
    ({"true_parameters": {"sample": {"sead": 1}}}, "true_parameters.sample.sead", "seed"),
    ({"seed": -3}, "seed", "integer >= 0"),
    ({"seed": 1.5}, "seed", "integer >= 0"),
    ({"torque_limit": [10, -1]}, "torque_limit", "> 0"),
    ({"controller_options": {"r_alpha": {}}}, "controller_options.r_alpha", "'r-alpha'"),
    ({"controller_options": {"r-alpha": {"etaa": 1}}}, "controller_options.r-alpha.etaa", "eta"),
    (
        {"controller_options": {"r-alpha": {"betas": "guess"}}},
        "controller_options.r-alpha.betas",
        "mapping",
    ),
    (
        {"controller_options": {"interval": {"kappa_p": 2}}},
        "controller_options.interval.kappa_p",
        "kappa_P",
    ),
    (
        {"controller_options": {"interval": {"method": "exact"}}},
        "controller_options.interval.method",
        "hull",
    ),
    ({"uncertainty": "nowhere.yaml"}, "uncertainty", "does not exist"),
    ({"plant": "bullet"}, "plant", "valid: mujoco, pinocchio"),
    ({"plant": "mujoco", "sample_period": "continuous"}, "plant", "give a sample_period"),
]


@pytest.mark.parametrize("extra, field, message", BAD)
def test_bad_scenarios_name_file_and_field(tmp_path, extra, field, message):
    path = write(tmp_path, minimal(**extra))
    with pytest.raises(InputError) as info:
        load_scenario(path)
    assert info.value.source == str(path)
    assert info.value.field == field
    assert message in str(info.value)


def test_missing_required_keys_and_bad_yaml(tmp_path):
    path = write(tmp_path, {"robot": "rr_planar"})
    with pytest.raises(InputError, match="'uncertainty' is required") as info:
        load_scenario(path)
    assert info.value.field == "uncertainty" and info.value.source == str(path)
    broken = tmp_path / "broken.yaml"
    broken.write_text("robot: [rr_planar\n")
    with pytest.raises(InputError, match="YAML syntax error"):
        load_scenario(broken)
    listing = tmp_path / "list.yaml"
    listing.write_text("- robot\n")
    with pytest.raises(InputError, match="mapping"):
        load_scenario(listing)


def test_errors_found_when_building_name_the_scenario_file(tmp_path):
    cases = [
        ({"robot": "rr_planer"}, "robot", "did you mean 'rr_planar'"),
        ({"initial_condition": {"q0": [0, 0, 0]}}, "initial_condition.q0", "2 joints"),
        ({"initial_condition": {"q0": [0, 7.0]}}, "initial_condition.q0", "outside its limits"),
        (
            {"initial_condition": {"offset": [-7.0, 0]}},
            "initial_condition",
            "outside its limits [-6.28319, 6.28319]",
        ),
        ({"torque_limit": [1, 2, 3]}, "torque_limit", "2 joints"),
        ({"trajectory": {"kind": "paper", "amplitude": [1]}}, "trajectory.amplitude", "2"),
        (
            {"trajectory": {"kind": "sinusoid", "amplitude": 7.0}},
            "trajectory",
            "joint limits of joint1, joint2",
        ),
    ]
    for extra, field, message in cases:
        path = write(tmp_path, minimal(**extra))
        with pytest.raises(InputError) as info:
            build(load_scenario(path))
        assert info.value.source == str(path), extra
        assert info.value.field == field, extra
        assert message in str(info.value), extra


def test_relative_paths_resolve_against_the_scenario_folder(tmp_path):
    folder = tmp_path / "deep" / "er"
    folder.mkdir(parents=True)
    (tmp_path / "box.yaml").write_text((RR_DIR / "uncertainty.yaml").read_text())
    (tmp_path / "true.yaml").write_text((RR_DIR / "true_parameters.yaml").read_text())
    (tmp_path / "arm.urdf").write_text((RR_DIR / "rr_planar.urdf").read_text())
    path = write(
        folder,
        {
            "robot": "../../arm.urdf",
            "uncertainty": "../../box.yaml",
            "true_parameters": "../../true.yaml",
        },
    )
    scenario = load_scenario(path)
    assert scenario.uncertainty == (tmp_path / "box.yaml").resolve()
    assert scenario.robot == str((tmp_path / "arm.urdf").resolve())
    setup = build(scenario)
    assert setup.plant.link("link2").inertia.mass == pytest.approx(10.0)


def test_defaults_and_arithmetic_values(tmp_path):
    path = write(tmp_path, minimal(epsilon="2*1e-3", sample_period="1e-3", trajectory="sinusoid"))
    scenario = load_scenario(path)
    assert scenario.epsilon == pytest.approx(2e-3)  # YAML reads 1e-3 as text; it is parsed
    assert scenario.sample_period == pytest.approx(1e-3)
    assert scenario.name == "scenario" and scenario.seed == 0 and scenario.duration == 10.0
    assert scenario.true_parameters == "sample" and scenario.true_parameter_seed == 0
    setup = build(scenario)
    assert isinstance(setup.trajectory, SinusoidTrajectory)
    reference = setup.trajectory.reference(0.0)
    np.testing.assert_allclose(setup.q0, reference.q)  # at_reference by default
    np.testing.assert_allclose(setup.qd0, reference.qd)
    assert "drawn uniformly from the rigid bodies of the box (seed 0)" in setup.true_description


def test_sampled_true_parameters_are_seeded_and_inside_the_box(tmp_path):
    draws = []
    for seed in (1, 1, 2):
        document = minimal(true_parameters={"sample": {"seed": seed}})
        setup = build(load_scenario(write(tmp_path, document)))
        point = setup.true_point.links["link2"]
        box = setup.box.link_box("link2")
        assert np.all(point >= box.lower) and np.all(point <= box.upper)
        draws.append(point)
    np.testing.assert_array_equal(draws[0], draws[1])
    assert not np.array_equal(draws[0], draws[2])
    nominal = build(load_scenario(write(tmp_path, minimal(true_parameters="nominal"))))
    assert nominal.true_point == ParameterPoint({})
    assert nominal.plant.link("link2").inertia.mass == pytest.approx(5.0)


def test_trajectory_and_initial_condition_options(tmp_path):
    document = minimal(
        trajectory={
            "kind": "quintic",
            "points": [[0, 0], ["pi/8", -0.2], [0, 0]],
            "times": [0, 2, 3],
        },
        initial_condition={"offset": [0.01, -0.01], "qd0": [0.1, 0]},
        torque_limit=100,
    )
    setup = build(load_scenario(write(tmp_path, document)))
    assert isinstance(setup.trajectory, QuinticTrajectory)
    np.testing.assert_allclose(setup.trajectory.points[1], [math.pi / 8, -0.2])
    np.testing.assert_allclose(setup.q0, [0.01, -0.01])
    np.testing.assert_allclose(setup.qd0, [0.1, 0])
    np.testing.assert_allclose(setup.torque_limit, [100, 100])
    sinusoid = minimal(
        trajectory={"kind": "sinusoid", "amplitude": [0.2, 0.1], "frequency": 0.5, "phase": 0}
    )
    trajectory = build(load_scenario(write(tmp_path, sinusoid))).trajectory
    np.testing.assert_allclose(trajectory.amplitude, [0.2, 0.1])
    np.testing.assert_allclose(trajectory.frequency, [0.5, 0.5])


def test_overrides():
    scenario = load_scenario("rr_planar/s2_ic1")
    changed = scenario.with_overrides(
        epsilon=5e-3,
        sample_period="continuous",
        disturbance=0,
        controller="r-alpha",
        duration=None,  # not given: ignored
        controller_options={"r-alpha": {"betas": "paper", "Q": 40}},
    )
    assert changed.epsilon == 5e-3 and changed.sample_period is None and changed.duration == 10.0
    assert changed.controller == "r-alpha"
    assert changed.options["betas"] == "paper" and changed.options["Q"] == 40.0
    assert changed.options["eta"] == 7e-5  # merged with the file's options
    assert scenario.epsilon == 1e-2 and scenario.controller == "interval"  # original unchanged
    with pytest.raises(InputError, match="did you mean 'epsilon'") as info:
        scenario.with_overrides(epsilonn=1)
    assert info.value.field == "epsilonn"
    with pytest.raises(InputError, match="must be > 0"):
        scenario.with_overrides(duration=-1)
    with pytest.raises(InputError, match="per control sample") as info:
        scenario.with_overrides(sample_period="continuous")  # the disturbance stays 10 N m
    # The conflicting value is the file's: the error names the file and the override.
    assert info.value.field == "disturbance" and info.value.source == str(scenario.source)
    assert "command-line override of sample_period" in str(info.value)
    with pytest.raises(InputError, match="valid: computed-torque, interval, r-alpha"):
        scenario.with_overrides(controller="lqr")
    sampled = scenario.with_overrides(true_parameters="sample", seed=4)
    assert sampled.true_parameters == "sample" and sampled.true_parameter_seed == 4
    # Each value is checked alone, the combination on the copy: a continuous scenario may run
    # shorter than the default period, and the copy keeps the file it came from.
    short = load_scenario("rr_planar/s1_ic1").with_overrides(duration=5e-4)
    assert short.duration == 5e-4 and short.continuous and short.source.name == "s1_ic1.yaml"
    with pytest.raises(
        InputError, match=r"shorter than one sample period \(sample_period = "
    ) as info:
        scenario.with_overrides(duration=5e-5)  # the file's period is 1e-4 s
    assert info.value.field == "duration" and info.value.source == "command-line override"


def test_to_dict_round_trip(tmp_path):
    scenario = load_scenario("rr_planar/s3_ic2")
    document = scenario.to_dict()
    again = parse_scenario(yaml.safe_load(yaml.safe_dump(document)), source=tmp_path / "x.yaml")
    assert again.to_dict() == document


def test_build_controller_for_each_kind():
    scenario = load_scenario("rr_planar/s3_ic2").with_overrides(
        controller_options={"r-alpha": {"betas": "paper"}}
    )
    setup = build(scenario)
    r_alpha = build_controller(setup, "r-alpha")
    assert isinstance(r_alpha, RAlphaController) and r_alpha.betas == PAPER_BETAS
    assert r_alpha.design_conditions().hold  # the paper's numbers meet the paper's conditions
    computed = build_controller(setup, "computed-torque")
    assert isinstance(computed, ComputedTorqueController) and computed.natural_frequency == 10
    interval = build_controller(setup)
    assert interval.name == "interval"
    assert {c.name for c in (r_alpha, computed, interval)} == set(CONTROLLERS)


def test_plant_backend_key_reaches_the_run(tmp_path):
    assert PLANT_BACKENDS == ("pinocchio", "mujoco")
    scenario = load_scenario("rr_planar/s3_ic1")
    assert scenario.plant == "pinocchio" and scenario.to_dict()["plant"] == "pinocchio"
    result = run_scenario(scenario.with_overrides(duration=0.02))
    assert result.info["plant"] == "pinocchio"
    assert result.info["true_parameters"] == {
        "link2": {"mass": 10.0, "com_x": 0.525, "iyy": pytest.approx(20 / 12)}
    }
    with pytest.raises(InputError, match="continuous time") as info:
        load_scenario("rr_planar/s1_ic1").with_overrides(plant="mujoco")
    assert info.value.field == "plant"
    pytest.importorskip("mujoco")
    path = write(tmp_path, minimal(plant="mujoco", duration=0.02, true_parameters="nominal"))
    mujoco = run_scenario(load_scenario(path))
    assert mujoco.info["plant"] == "mujoco" and mujoco.info["true_parameters"] == {}


def test_sampled_true_parameters_are_named_in_the_description(tmp_path):
    setup = build(load_scenario(write(tmp_path, minimal(seed=5))))
    values = true_parameter_values(setup)["link2"]
    assert set(values) == {"mass", "com_x", "iyy"}  # the uncertain fields of Table I
    link = setup.box.link_box("link2")
    for name, value in values.items():
        assert value == setup.true_point.links["link2"][link.fields.index(name)]
    description = setup.true_description
    assert "(seed 5)" in description
    assert f"mass = {values['mass']:.6g} kg" in description
    assert f"com_x = {values['com_x']:.6g} m" in description
    assert f"iyy = {values['iyy']:.6g} kg m^2" in description


def test_sampled_law_follows_the_scenario():
    paper = load_scenario("rr_planar/s3_ic1")
    options = interval_synthesis_options(paper)
    assert options["sample_period"] == 1e-3 and options["sampled_law"] == "paper"
    implicit = paper.with_overrides(controller_options={"interval": {"sampled_law": "implicit"}})
    assert interval_synthesis_options(implicit)["sampled_law"] == "implicit"
    default = load_scenario("ur5/sampled")
    assert interval_synthesis_options(default)["sampled_law"] == "implicit"  # the default
    continuous = interval_synthesis_options(load_scenario("rr_planar/s1_ic1"))
    assert continuous["sample_period"] is None
    assert build_controller(build(implicit)).name == "interval"


def test_every_controller_runs_at_the_scenario_period_and_a_mismatch_is_an_error():
    """The scenario's period reaches each law through synthesis; a controller built for another
    period is refused rather than run at a period it was not built for."""
    scenario = load_scenario("rr_planar/s3_ic1").with_overrides(duration=0.01)
    setup = build(scenario)
    for name in CONTROLLERS:
        assert build_controller(setup, name).sample_period == 1e-3, name
    faster = build_controller(build(scenario.with_overrides(sample_period=1e-4)))
    with pytest.raises(InputError, match="runs at T = 0.0001 s, the scenario at T = 0.001 s"):
        simulate_setup(setup, faster)
