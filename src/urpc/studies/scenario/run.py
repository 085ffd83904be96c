"""Running a scenario: synthesize its controller, then simulate it against the true plant."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from ...control.base import Controller
from ...errors import InputError, did_you_mean
from ...formats.controller_options import IntervalOptions
from ...formats.scenario import Scenario
from ...model.parameter_box import JOINTS, joint_values
from ...model.point import ParameterPoint
from .settings import CONTROLLERS
from .setup import ScenarioSetup, build


def interval_synthesis_options(scenario: Scenario) -> dict[str, Any]:
    """The keyword arguments of :func:`urpc.control.synthesis.synthesize` for the scenario's
    ``interval`` options: ``sample_period`` is the scenario's (``None`` for continuous time) and
    ``sampled_law`` the option's (``implicit`` by default, ``paper`` for the paper's law
    unchanged)."""
    options = scenario.controller_options.by_controller()["interval"]
    options.setdefault("sampled_law", IntervalOptions.model_fields["sampled_law"].default)
    options["sample_period"] = scenario.sample_period
    return options


def build_controller(setup: ScenarioSetup, controller: str | None = None) -> Controller:
    """Synthesize the scenario's controller (or ``controller``, one of :data:`CONTROLLERS`) with
    its options from the scenario, for the scenario's sample period (every law runs at it).

    ``interval`` options: the keyword arguments of :func:`urpc.control.synthesis.synthesize`
    (:func:`interval_synthesis_options`); a sampled scenario runs ``sampled_law: implicit`` (the
    sampled-data law, default) or ``paper`` (the paper's law unchanged).

    ``r-alpha`` options: ``betas: estimate`` (default,
    :func:`~urpc.control.r_alpha.estimate_betas`), ``paper`` (the paper's values) or explicit
    ``beta0..beta3``; its ``disturbance_bound`` (the bound the r-alpha designer assumes) defaults
    to the box's known bound, else the scenario's ``disturbance``.
    """
    scenario = setup.scenario
    name = scenario.controller if controller is None else controller
    source = None if scenario.source is None else str(scenario.source)
    if name not in CONTROLLERS:
        raise InputError(
            f"unknown controller '{name}'; " + did_you_mean(name, CONTROLLERS), source, "controller"
        )
    options = scenario.controller_options.by_controller()[name]
    try:
        if name == "interval":
            from ...control.synthesis import synthesize

            options = interval_synthesis_options(scenario)
            return synthesize(setup.robot, setup.box, scenario.epsilon, **options)
        if name == "computed-torque":
            from ...control.computed_torque import synthesize_computed_torque

            return synthesize_computed_torque(
                setup.robot, setup.box, sample_period=scenario.sample_period, **options
            )
        from ...control.r_alpha import PAPER_BETAS, Betas, synthesize_r_alpha

        betas = options.pop("betas", "estimate")
        if betas == "paper":
            options["betas"] = PAPER_BETAS
        elif isinstance(betas, Mapping):
            options["betas"] = Betas(**betas)
        if "disturbance_bound" not in options:
            known = setup.box.disturbance_bound
            options["disturbance_bound"] = scenario.disturbance if known is None else known
        return synthesize_r_alpha(
            setup.robot, setup.box, sample_period=scenario.sample_period, **options
        )
    except InputError as exc:
        if exc.source is not None:
            raise
        prefix = f"controller_options.{name}"
        raise InputError(
            exc.detail, source, f"{prefix}.{exc.field}" if exc.field else prefix
        ) from None


def run_scenario(
    scenario: Scenario, controller: str | None = None, progress: Any = None
):  # -> urpc.sim.results.SimulationResult
    """Build, synthesize and simulate one scenario; returns the simulation result.

    ``progress`` is passed to :func:`urpc.sim.simulation.simulate`. The result's ``info`` records the
    plant backend (``plant``) and how the true parameters were chosen (``true_parameters``).
    """
    setup = build(scenario)
    law = build_controller(setup, controller)
    return simulate_setup(setup, law, progress=progress)


def simulate_setup(
    setup: ScenarioSetup, controller: Controller, progress: Any = None
):  # -> urpc.sim.results.SimulationResult
    """Simulate a built scenario with a synthesized controller (the last step of
    :func:`run_scenario`, for callers that want to inspect the setup or the controller). The
    controller runs at its own period, which must be the scenario's.

    Raises:
        InputError: the controller was built for another sample period than the scenario's.
    """
    from ...sim.simulation import simulate

    scenario = setup.scenario
    if controller.sample_period != scenario.sample_period:
        raise InputError(
            f"controller {controller.name!r} runs at {_period(controller.sample_period)}, the "
            f"scenario at {_period(scenario.sample_period)}: synthesize it for the scenario "
            "(build_controller(setup))",
            None if scenario.source is None else str(scenario.source),
            "sample_period",
        )
    result = simulate(
        setup.plant,
        controller,
        setup.trajectory,
        duration=scenario.duration,
        q0=setup.q0,
        qd0=setup.qd0,
        disturbance_bound=scenario.disturbance,
        disturbance=scenario.disturbance_model,
        seed=scenario.seed,
        torque_limit=setup.torque_limit,
        epsilon=scenario.epsilon,
        progress=progress,
        plant_backend=scenario.plant,
        actuation_delay=scenario.actuation_delay,
    ).labelled(scenario=scenario.name, plant=setup.true_description)
    info = {
        **result.info,
        "true_parameters": true_parameter_values(setup),
    }
    return dataclasses.replace(result, info=info)


def _period(period: float | None) -> str:
    return "continuous time" if period is None else f"T = {period:g} s"


def true_parameter_values(setup: ScenarioSetup) -> dict[str, dict[str, float]]:
    """The true values of the uncertain parameters, link -> field -> value (units of the
    uncertainty format: kg, m, kg m^2), and ``"<joints>"`` -> ``joint.field`` -> value for the
    joint parameters; empty when the true plant is the nominal model."""
    values: dict[str, dict[str, float]] = {}
    joints = joint_values(setup.box, setup.true_point)
    if joints:
        values[JOINTS] = joints
    for name, coordinates in ParameterPoint.coerce(setup.true_point).links.items():
        try:
            link_box = setup.box.link_box(name)
        except KeyError:
            continue
        values[name] = {
            field_name: float(coordinates[k])
            for k, field_name in enumerate(link_box.fields)
            if link_box.uncertain[k]
        }
    return values
