"""The generic trajectory of a robot: a sinusoid or quintic motion about the middle of its joint
limits, inside those limits and below its velocity limits, for a robot that comes without a
scenario (:func:`generic_trajectory`; the trajectory families are :mod:`urpc.trajectories`)."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from .errors import InputError

if TYPE_CHECKING:
    from .model.robot import Robot
    from .trajectories import Trajectory

#: Largest amplitude generic trajectories use on a joint whose range is wide or unbounded.
MAX_AMPLITUDE = {"revolute": 0.5, "continuous": 0.5, "prismatic": 0.05}  # [rad], [rad], [m]


def _check_robot(robot) -> None:
    from .model.robot import Robot
    from .validation import check_type

    check_type("robot", robot, Robot, "a Robot (urpc.load_robot(...))")


def home_configuration(robot: Robot) -> np.ndarray:
    """The middle of each joint's limits [rad or m], or 0 where a limit is infinite."""
    _check_robot(robot)
    lower, upper = robot.position_limits
    with np.errstate(invalid="ignore"):  # -inf + inf on a continuous joint, replaced below
        middle = 0.5 * (lower + upper)
    return np.where(np.isfinite(lower) & np.isfinite(upper), middle, 0.0)


def generic_trajectory(
    robot: Robot,
    kind: str = "sinusoid",
    *,
    home: Sequence[float] | None = None,
    amplitude_fraction: float = 0.25,
    frequency: float = 0.25,
    velocity_fraction: float = 0.5,
    segment_duration: float = 2.0,
) -> Trajectory:
    """A smooth trajectory for any robot, inside its joint limits and below its velocity limits.

    The motion is centered at ``home`` (default :func:`home_configuration`) with, per joint, the
    amplitude ``amplitude_fraction`` of the distance to the nearer limit, capped at
    :data:`MAX_AMPLITUDE`. ``sinusoid``: frequencies spread evenly from ``frequency`` [Hz] (first
    joint) to ``1.5 frequency`` (last joint), lowered where needed so that the peak speed stays
    below ``velocity_fraction`` of the URDF velocity limit; phase ``-pi/2`` so that it starts at
    rest at ``home - amplitude``.
    ``quintic``: rest-to-rest segments ``home -> home + A -> home - A -> home`` (alternate signs on
    alternate joints), each lasting ``segment_duration`` [s] or longer if the speed requires it.

    A joint whose range is empty (lower limit = upper limit, as some URDFs write for joints they
    do not limit) is held still, with a warning that names it.

    Raises:
        InputError: unknown ``kind`` or out-of-range fractions, or a home outside the limits.
    """
    from .trajectories import QUINTIC_PEAK_VELOCITY, QuinticTrajectory, SinusoidTrajectory
    from .validation import per_joint

    _check_robot(robot)
    if kind not in ("sinusoid", "quintic"):
        raise InputError(
            f"unknown generic trajectory kind '{kind}'; valid: sinusoid, quintic", field="kind"
        )
    for name, value in (
        ("amplitude_fraction", amplitude_fraction),
        ("velocity_fraction", velocity_fraction),
    ):
        if not 0 < value <= 1:
            raise InputError(f"{name}={value} must be in (0, 1]", field=name)
    if not (frequency > 0 and segment_duration > 0):
        raise InputError("frequency and segment_duration must be > 0", field="frequency")
    lower, upper = robot.position_limits
    center = (
        home_configuration(robot) if home is None else per_joint("home", home, robot.dof, "rad")
    )
    if np.any(center < lower) or np.any(center > upper):
        raise InputError(f"home {center.tolist()} lies outside the joint limits", field="home")
    margin = np.minimum(center - lower, upper - center)
    cap = np.array([MAX_AMPLITUDE[kind_] for kind_ in robot.joint_kinds])
    amplitude = np.minimum(amplitude_fraction * margin, cap)
    still = [name for name, a in zip(robot.joint_names, amplitude, strict=True) if not a > 0]
    if still:
        warnings.warn(
            f"{robot.name}: the generic trajectory holds joints {still} still: their position "
            f"range is empty (the URDF's lower and upper limits coincide, or home sits on a "
            f"limit), so they are not exercised; fix the limits or give the scenario its own "
            f"trajectory",
            stacklevel=2,
        )
    speed = velocity_fraction * _usable(robot.velocity_limit)

    if kind == "sinusoid":
        frequencies = frequency * np.linspace(1.0, 1.5, robot.dof)
        with np.errstate(divide="ignore", invalid="ignore"):
            allowed = np.where(amplitude > 0, speed / (2 * np.pi * amplitude), np.inf)
        return SinusoidTrajectory(center, amplitude, np.minimum(frequencies, allowed), -np.pi / 2)

    signs = np.where(np.arange(robot.dof) % 2 == 0, 1.0, -1.0)
    points = np.array([center, center + signs * amplitude, center - signs * amplitude, center])
    distance = np.abs(np.diff(points, axis=0)).max(axis=0)  # per joint, largest segment
    with np.errstate(divide="ignore", invalid="ignore"):
        needed = np.where(distance > 0, QUINTIC_PEAK_VELOCITY * distance / speed, 0.0)
    duration = max(segment_duration, float(np.max(needed)))
    return QuinticTrajectory(points, duration * np.arange(len(points)))


def _usable(velocity_limit: np.ndarray) -> np.ndarray:
    """URDF velocity limits, with missing ones (0, negative, non-finite) read as unlimited."""
    limit = np.asarray(velocity_limit, dtype=float)
    return np.where(np.isfinite(limit) & (limit > 0), limit, np.inf)
