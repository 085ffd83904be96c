"""A scenario's trajectory from outside urpc, checked against the robot's limits.

:func:`planned_trajectory` builds the ``file`` (:func:`urpc.trajectory_files.load_samples`) or
``waypoints`` (:class:`urpc.trajectory_moves.WaypointTrajectory`) trajectory of a scenario's
options; :func:`check_limits` refuses a trajectory that leaves the joint position, velocity or
acceleration limits, naming the sample and the joint.

:func:`~urpc.trajectory_samples.from_samples` and :class:`~urpc.trajectory_moves.Approach` are
importable from here too, where ``docs/robot.md`` and the tests import them.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError
from .trajectories import Trajectory
from .trajectory_files import load_samples
from .trajectory_moves import Approach, WaypointTrajectory
from .trajectory_samples import from_samples

__all__ = [
    "WAYPOINT_ACCELERATION",
    "Approach",
    "check_limits",
    "from_samples",
    "planned_trajectory",
]


def check_limits(
    trajectory: Trajectory,
    robot,
    *,
    acceleration_limit=None,
    source=None,
    field: str = "trajectory",
    times=None,
    step: float = 1e-3,
) -> None:
    """Refuse a trajectory that leaves the robot's position or velocity limits, or
    ``acceleration_limit`` [rad/s^2] (scalar or per joint; ``None``: none), on a grid of ``step``
    [s] over its samples (``times``, default: its own ``t`` or ``times``); the error names the
    joint and the sample nearest to its worst violation."""
    samples = np.asarray(
        times
        if times is not None
        else getattr(trajectory, "t", getattr(trajectory, "times", [0.0])),
        dtype=float,
    )
    grid = np.union1d(samples, np.arange(samples[0], samples[-1] + step, step))
    q, qd, qdd = trajectory.evaluate(grid)
    lower, upper = robot.position_limits
    velocity = np.where(
        np.isfinite(robot.velocity_limit) & (robot.velocity_limit > 0), robot.velocity_limit, np.inf
    )
    checks = [
        ("position", q < lower, q, lambda j: f"below the lower limit {lower[j]:.6g}"),
        ("position", q > upper, q, lambda j: f"above the upper limit {upper[j]:.6g}"),
        (
            "velocity",
            np.abs(qd) > velocity * (1 + 1e-9),
            qd,
            lambda j: f"above the limit {velocity[j]:.6g} rad/s",
        ),
    ]
    if acceleration_limit is not None:
        limit = np.broadcast_to(np.asarray(acceleration_limit, float), (trajectory.dof,))
        checks.append(
            (
                "acceleration",
                np.abs(qdd) > limit * (1 + 1e-9),
                qdd,
                lambda j: f"above the limit {limit[j]:.6g} rad/s^2",
            )
        )
    describe = getattr(trajectory, "describe", None)
    for what, bad, values, text in checks:
        if bad.any():
            # the worst violation (a jump between two samples, not the ringing around it)
            i, j = np.unravel_index(np.argmax(np.where(bad, np.abs(values), -np.inf)), bad.shape)
            row = int(np.clip(np.searchsorted(samples, grid[i]), 0, len(samples) - 1))
            if row > 0 and abs(samples[row - 1] - grid[i]) < abs(samples[row] - grid[i]):
                row -= 1
            where = describe(row) if describe else f"sample {row} (t = {samples[row]:.6g} s)"
            raise InputError(
                f"the {what} of joint {robot.joint_names[j]} is {values[i, j]:.6g} at t = "
                f"{grid[i]:.6g} s, near {where}: {text(j)}",
                source,
                field,
            )


#: Default acceleration limit of waypoint segments [rad/s^2] when the scenario gives none.
WAYPOINT_ACCELERATION = 5.0


def planned_trajectory(kind: str, options, robot, source=None) -> Trajectory:
    """The ``file`` or ``waypoints`` trajectory of a scenario's options, checked against the
    robot's limits (:func:`check_limits`).

    Raises:
        InputError: naming the scenario file, the field, and for a limit the sample and joint.
    """
    dof = robot.dof
    acceleration = options.get("acceleration_limit")
    if acceleration is not None:
        acceleration = np.broadcast_to(np.asarray(acceleration, dtype=float), (dof,))
    if kind == "file":
        if "path" not in options:
            raise InputError(
                "a file trajectory needs path: FILE (.csv or .npz)", source, "trajectory.path"
            )
        trajectory = load_samples(options["path"], dof, robot.joint_names)
        check_limits(
            trajectory,
            robot,
            acceleration_limit=acceleration,
            source=trajectory.source,
            field="trajectory",
        )
        return trajectory
    points = np.array(options["points"], dtype=float)
    if points.ndim != 2 or points.shape[1] != dof:
        raise InputError(f"each point needs {dof} joint values", source, "trajectory.points")
    velocity = robot.velocity_limit
    velocity = np.where(np.isfinite(velocity) & (velocity > 0), velocity, np.inf)
    fraction = options.get("velocity_fraction", 0.5)
    a_limit = WAYPOINT_ACCELERATION if acceleration is None else acceleration
    try:
        trajectory = WaypointTrajectory(
            points,
            options.get("times"),
            velocity_limit=fraction * velocity,
            acceleration_limit=a_limit,
        )
    except InputError as exc:
        raise InputError(exc.detail, source, f"trajectory.{exc.field or 'points'}") from None
    check_limits(
        trajectory, robot, acceleration_limit=acceleration, source=source, field="trajectory"
    )
    return trajectory
