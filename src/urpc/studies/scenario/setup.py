"""Building a scenario: the robot, the box, the true plant, the trajectory and the initial state.

:func:`build` turns the settings of a :class:`~urpc.formats.scenario.Scenario` into the
objects a run needs (a :class:`ScenarioSetup`), checking what needs the robot (vector lengths,
joint limits, link names) and naming the scenario file and the field in every error.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InputError
from ...formats.base import FileFormat
from ...formats.scenario import InitialState, Scenario
from ...model.parameter_box import joint_values
from ...model.parameter_point import box_excursions as parameter_excursions
from ...model.parameter_point import sample_rigid_point
from ...model.point import ParameterPoint
from ...model.robot import Robot, load_robot
from ...model.uncertainty import UNITS, ParameterBox, load_parameter_point, load_uncertainty
from ...trajectories import (
    PaperTrajectory,
    QuinticTrajectory,
    SinusoidTrajectory,
    Trajectory,
    generic_trajectory,
)


class OutsideBoxWarning(UserWarning):
    """The true plant of a run lies outside the parameter box the controller was built for."""


@dataclass(frozen=True, eq=False)
class ScenarioSetup:
    """The objects a scenario describes, ready for synthesis and simulation.

    Attributes:
        scenario: The settings.
        robot: The controller's nominal model (payloads of the box attached at their nominal).
        box: The parameter box (the controller's knowledge).
        plant: The true plant.
        true_point: The true parameters (:class:`~urpc.model.point.ParameterPoint`; naming no
            body and no joints: nominal).
        true_description: How the true parameters were chosen, for reports.
        trajectory: The desired trajectory.
        q0, qd0: The initial state [rad], [rad/s].
        torque_limit: Per-joint torque bound [N m], or ``None``.
    """

    scenario: Scenario
    robot: Robot
    box: ParameterBox
    plant: Robot
    true_point: ParameterPoint
    true_description: str
    trajectory: Trajectory
    q0: np.ndarray
    qd0: np.ndarray
    torque_limit: np.ndarray | None

    @property
    def outside_box(self) -> dict[str, float]:
        """``link.field`` -> distance [SI] outside the box of each true parameter that is not in
        it (empty: the true plant is one of the plants the guarantee covers)."""
        return parameter_excursions(self.box, self.true_point, self.robot)

    @property
    def inside_box(self) -> bool:
        return not self.outside_box


def box_excursions(
    box: ParameterBox, point: ParameterPoint | Mapping[str, np.ndarray]
) -> dict[str, float]:
    """``link.field`` or ``joint.field`` -> distance [SI] outside ``box`` of the coordinates of
    ``point`` that are not in it, links, payloads and joint drives alike
    (:func:`urpc.model.parameter_point.box_excursions`)."""
    return parameter_excursions(box, point)


def build(scenario: Scenario) -> ScenarioSetup:
    """Load the robot and the box, make the true plant, the trajectory and the initial state.

    Raises:
        InputError: a setting that does not fit the robot (vector lengths, joint limits, an
            unknown robot or link), naming the scenario file and the field.
    """
    source = None if scenario.source is None else str(scenario.source)
    try:
        robot = load_robot(scenario.robot, scenario.locked_joints)
    except InputError as exc:
        if exc.source is not None:
            raise
        raise InputError(exc.detail, source, exc.field or "robot") from None
    box = load_uncertainty(scenario.uncertainty, robot)
    nominal = box.nominal_robot(robot)
    point, description = _true_point(scenario, robot, box, source)
    plant = box.plant(robot, point)
    trajectory = _trajectory(scenario.trajectory, nominal, source)
    reference = trajectory.reference(0.0)
    ic = scenario.initial_condition
    if isinstance(ic, str):  # at_reference
        ic = InitialState()
    q0 = reference.q + _fit(ic.offset, nominal.dof, source, "initial_condition.offset")
    if ic.q0 is not None:
        q0 = _fit(ic.q0, nominal.dof, source, "initial_condition.q0")
    _check_inside_limits(
        q0, nominal, source, "initial_condition.q0" if ic.q0 is not None else "initial_condition"
    )
    qd0 = reference.qd.copy()
    if ic.qd0 is not None:
        qd0 = _fit(ic.qd0, nominal.dof, source, "initial_condition.qd0")
    limit = None
    if scenario.torque_limit is not None:
        limit = np.broadcast_to(
            _fit(
                scenario.torque_limit,
                nominal.dof,
                scenario.source_of("torque_limit"),
                "torque_limit",
            ),
            (nominal.dof,),
        ).copy()
    setup = ScenarioSetup(
        scenario, nominal, box, plant, point, description, trajectory, q0, qd0, limit
    )
    if setup.outside_box:
        where = ", ".join(f"{name} by {gap:.4g}" for name, gap in setup.outside_box.items())
        warnings.warn(
            f"the true parameters lie outside the box ({where}): the guarantee does not cover "
            "this plant",
            OutsideBoxWarning,
            stacklevel=2,
        )
    return setup


def _check_inside_limits(q0: np.ndarray, robot, source, field: str) -> None:
    """Refuse an initial position outside the joint limits (the arm cannot start there)."""
    lower, upper = robot.position_limits
    slack = 1e-9 * np.maximum(1.0, np.abs(q0))
    outside = np.flatnonzero((q0 < lower - slack) | (q0 > upper + slack))
    if outside.size:
        k = int(outside[0])
        raise InputError(
            f"the initial position of joint '{robot.joint_names[k]}' is {q0[k]:.6g}, outside its "
            f"limits [{lower[k]:.6g}, {upper[k]:.6g}]: give a q0 (or an offset from the "
            "reference's start) within the joint limits",
            source,
            field,
        )


def _fit(value: Any, dof: int, source: str | None, fieldname: str) -> np.ndarray:
    """A per-joint vector from ``None`` (zeros), a scalar or ``dof`` numbers."""
    if value is None:
        return np.zeros(dof)
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        return np.full(dof, float(array))
    if array.shape != (dof,):
        raise InputError(
            f"{array.tolist()} has {array.size} entries; the robot has {dof} joints",
            source,
            fieldname,
        )
    return array.copy()


def _true_point(
    scenario: Scenario, robot: Robot, box: ParameterBox, source: str | None
) -> tuple[ParameterPoint, str]:
    true = scenario.true_parameters
    if isinstance(true, Path):
        return load_parameter_point(true, robot, box), f"true parameters from {true}"
    if true == "nominal":
        return ParameterPoint({}), "true parameters = nominal parameters (no model error)"
    seed = scenario.true_parameter_seed
    point, rejected = _sampled(box, seed, source)
    rejections = f"; {rejected} draws that were no rigid body rejected" if rejected else ""
    return point, (
        f"true parameters drawn uniformly from the rigid bodies of the box (seed {seed}"
        f"{rejections}): " + describe_point(box, point)
    )


def describe_point(box: ParameterBox, point: ParameterPoint | Mapping[str, np.ndarray]) -> str:
    """``link2: mass = 8.18 kg, com_x = 0.507 m, iyy = 1.17 kg m^2`` (uncertain fields only)."""
    point = ParameterPoint.coerce(point)
    parts = []
    for name, coordinates in point.links.items():
        link_box = box.link_box(name)
        fields = [
            f"{field_name} = {coordinates[k]:.6g} {UNITS.get(field_name, 'kg m^2')}"
            for k, field_name in enumerate(link_box.fields)
            if link_box.uncertain[k]
        ]
        parts.append(f"{name}: {', '.join(fields) if fields else 'nominal'}")
    joints = joint_values(box, point)
    if joints:
        parts.append("joints: " + ", ".join(f"{k} = {v:.4g}" for k, v in joints.items()))
    return "; ".join(parts) if parts else "nominal"


def sample_true_parameters(
    box: ParameterBox, seed: int, source: str | None = None, tries: int = 1000
) -> ParameterPoint:
    """A seeded uniform draw from the rigid bodies of ``box``
    (:func:`urpc.model.parameter_point.sample_rigid_point`, pseudo-inertia test).

    Raises:
        InputError: no consistent point found in ``tries`` draws.
    """
    return _sampled(box, seed, source, tries)[0]


def _sampled(
    box: ParameterBox, seed: int, source: str | None, tries: int = 1000
) -> tuple[ParameterPoint, int]:
    try:
        return sample_rigid_point(box, np.random.default_rng(seed), tries)
    except InputError as exc:
        raise InputError(exc.detail, source=source, field="true_parameters") from None


def _trajectory(spec: str | FileFormat, robot: Robot, source: str | None) -> Trajectory:
    """The trajectory of a scenario's ``trajectory``: a kind, or a kind's model and its options."""
    kind = spec if isinstance(spec, str) else spec.kind
    options = {} if isinstance(spec, str) else spec.model_dump(exclude_unset=True, exclude={"kind"})
    dof = robot.dof
    if kind in ("file", "waypoints"):
        from ...trajectory_sources import planned_trajectory

        return planned_trajectory(kind, options, robot, source)
    try:
        if kind == "paper":
            amplitude = options.get("amplitude", (math.pi / 4, -math.pi / 8))
            if len(amplitude) != dof:
                raise InputError(
                    f"the paper trajectory needs one amplitude per joint ({dof}), got "
                    f"{len(amplitude)}",
                    source,
                    "trajectory.amplitude",
                )
            trajectory = PaperTrajectory(amplitude)
            reach = np.abs(trajectory.amplitude)
            return _within_limits(trajectory, (-reach, reach), robot, source)
        knobs = {
            k: options.pop(k)
            for k in ("home", "amplitude_fraction", "velocity_fraction", "segment_duration")
            if k in options
        }
        if "home" in knobs:
            knobs["home"] = _fit(knobs["home"], dof, source, "trajectory.home")
        generic = generic_trajectory(robot, kind, **knobs)
        if kind == "sinusoid":
            assert isinstance(generic, SinusoidTrajectory)
            values = {
                key: _fit(options.get(key, getattr(generic, key)), dof, source, f"trajectory.{key}")
                for key in ("amplitude", "frequency", "phase")
            }
            trajectory = SinusoidTrajectory(generic.home, **values)
            reach = np.abs(trajectory.amplitude)
            q_range = (trajectory.home - reach, trajectory.home + reach)
        else:
            if "points" not in options:
                return generic
            points = np.array(options["points"], dtype=float)
            if points.ndim != 2 or points.shape[1] != dof:
                raise InputError(
                    f"each point needs {dof} joint values", source, "trajectory.points"
                )
            times = options.get("times")
            if times is None:
                step = knobs.get("segment_duration", 2.0)
                times = step * np.arange(len(points))
            trajectory = QuinticTrajectory(points, times)
            q_range = (points.min(axis=0), points.max(axis=0))
    except InputError as exc:
        if exc.source is not None or (exc.field or "").startswith("trajectory"):
            raise
        raise InputError(
            exc.detail, source, f"trajectory.{exc.field}" if exc.field else "trajectory"
        ) from None
    return _within_limits(trajectory, q_range, robot, source)


def _within_limits(
    trajectory: Trajectory, q_range: tuple, robot: Robot, source: str | None
) -> Trajectory:
    lower, upper = robot.position_limits
    outside = np.flatnonzero((q_range[0] < lower) | (q_range[1] > upper))
    if outside.size:
        names = ", ".join(robot.joint_names[j] for j in outside)
        raise InputError(f"the trajectory leaves the joint limits of {names}", source, "trajectory")
    return trajectory
