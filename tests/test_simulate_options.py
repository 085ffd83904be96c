"""The smaller ``simulate`` (issue 18.9): the integrator's settings in one ``SolverOptions``, the
report's labels on the result; the older keywords still work for one release, warned, and give
the same run to the bit."""

from __future__ import annotations

import dataclasses
import warnings

import pytest

import urpc
from urpc.errors import InputError
from urpc.sim.simulation import describe_plant

_SERIES = ("t", "q", "qd", "q_desired", "qd_desired", "torque", "disturbance", "saturated")


@pytest.fixture(scope="module")
def parts():
    robot = urpc.load_robot("rr_planar")
    box = urpc.load_uncertainty("rr_planar", robot)
    plant = box.plant(urpc.load_parameter_point("rr_planar", robot, box))
    continuous = urpc.synthesize(robot, box, epsilon=1e-2)
    sampled = urpc.synthesize(robot, box, epsilon=1e-2, sample_period=1e-3)
    return plant, continuous, sampled, urpc.PaperTrajectory()


def _identical(a: urpc.SimulationResult, b: urpc.SimulationResult) -> None:
    for name in _SERIES:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), name
    assert a.diagnostics.keys() == b.diagnostics.keys()
    for name in a.diagnostics:
        assert a.diagnostics[name].tobytes() == b.diagnostics[name].tobytes(), name
    assert a.info == b.info
    for name in ("controller", "epsilon", "duration", "sample_period", "scenario", "plant"):
        assert getattr(a, name) == getattr(b, name), name


@pytest.mark.parametrize("sampled", [False, True])
def test_the_older_keywords_give_the_same_run_to_the_bit_with_a_warning(parts, sampled):
    plant, continuous, held, trajectory = parts
    controller = held if sampled else continuous
    if sampled:
        settings = dict(integration_step=2.5e-4, max_state=50.0)
    else:
        settings = dict(method="DOP853", rtol=1e-7, atol=1e-9, output_rate=500.0, max_state=50.0)
    common = dict(duration=0.2, q0=[0.05, -0.05], qd0=[0.0, 0.0])
    with pytest.warns(DeprecationWarning) as caught:
        old = urpc.simulate(
            plant, controller, trajectory, **common, **settings,
            scenario="s", plant_description="the true arm",
        )  # fmt: skip
    messages = [str(w.message) for w in caught]
    assert any("solver=urpc.SolverOptions(" in m and "max_state=" in m for m in messages)
    assert any(".labelled(scenario=..., plant=...)" in m for m in messages)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the new form warns about nothing
        new = urpc.simulate(
            plant, controller, trajectory, **common, solver=urpc.SolverOptions(**settings)
        ).labelled(scenario="s", plant="the true arm")
    _identical(old, new)
    if not sampled:
        assert new.info["integrator"] == "DOP853" and len(new.t) == 101  # 500 Hz over 0.2 s
    else:
        assert new.info["substeps"] == 4


def test_the_defaults_are_the_older_defaults(parts):
    plant, _, controller, trajectory = parts
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        old = urpc.simulate(
            plant, controller, trajectory, duration=0.1,
            integration_step=1e-4, max_state=1e4, scenario="",
        )  # fmt: skip
    new = urpc.simulate(plant, controller, trajectory, duration=0.1)
    _identical(old, new)
    assert new.scenario == "" and new.plant == describe_plant(plant)
    defaults = urpc.SolverOptions()
    assert (defaults.method, defaults.rtol, defaults.atol) == ("Radau", 1e-8, 1e-10)
    assert (defaults.output_rate, defaults.integration_step, defaults.max_state) == (
        1000.0,
        1e-4,
        1e4,
    )


def test_labelled_sets_the_labels_and_shares_the_series(parts):
    plant, _, controller, trajectory = parts
    result = urpc.simulate(plant, controller, trajectory, duration=0.05)
    named = result.labelled(scenario="demo")
    assert named.scenario == "demo" and named.plant == result.plant and named.q is result.q
    assert result.scenario == ""  # the original is unchanged (frozen)
    assert named.labelled(plant="p").scenario == "demo"
    with pytest.raises(InputError) as caught:
        result.labelled(plant=3)  # type: ignore[arg-type]
    assert caught.value.field == "plant"


@pytest.mark.parametrize(
    ("name", "value", "words"),
    [
        ("output_rate", 0.0, "[Hz]"),
        ("integration_step", -1e-4, "[s]"),
        ("max_state", float("nan"), "[rad, rad/s]"),
        ("max_state", "big", "not a number"),
    ],
)
def test_solver_options_refuse_what_is_no_positive_number(name, value, words):
    with pytest.raises(InputError) as caught:
        urpc.SolverOptions(**{name: value})
    assert caught.value.field == name and words in str(caught.value)


def test_solver_options_are_frozen_and_mistakes_are_named(parts):
    plant, _, controller, trajectory = parts
    options = urpc.SolverOptions(integration_step=1e-3)
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.max_state = 1.0  # type: ignore[misc]
    run = dict(duration=0.01)
    with pytest.raises(TypeError, match="unexpected keyword argument 'duraton'"):
        urpc.simulate(plant, controller, trajectory, **run, duraton=0.01)
    with pytest.raises(TypeError, match="solver= only"):
        urpc.simulate(plant, controller, trajectory, **run, solver=options, max_state=10.0)
    with pytest.raises(InputError) as caught:
        urpc.simulate(plant, controller, trajectory, **run, solver={"max_state": 10.0})
    assert caught.value.field == "solver"
