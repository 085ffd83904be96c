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
from .validation import positive_number

__all__ = [
    "WAYPOINT_ACCELERATION",
    "Approach",
    "check_limits",
    "from_samples",
    "planned_trajectory",
]


#: Most points of the grid :func:`check_limits` lays over a trajectory whose pieces it does not
#: know (10^6: 1000 s at the default 1 ms; some 150 MB for a 6-joint arm's three arrays).
MAX_GRID_POINTS = 10**6


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
    ``acceleration_limit`` [rad/s^2] (scalar or per joint; ``None``: none), over its samples
    (``times``, default: its own ``t`` or ``times``); the error names the joint and the sample
    nearest to its worst violation.

    A spline (:class:`~urpc.trajectory_samples.FileTrajectory`) or quintic segments
    (:class:`~urpc.trajectories.QuinticTrajectory`) are checked exactly, piece by piece: at every
    sample and break between pieces and at every interior extremum of each piece's position,
    velocity and acceleration (where a polynomial's maximum lies), so no peak hides between
    checked times and the work grows with the pieces, not with the time span (a span of 1e9 s
    costs what 1 s does). Another trajectory is checked on a grid of ``step`` [s] and 64 points
    between samples, of at most :data:`MAX_GRID_POINTS` points.

    Raises:
        InputError: a limit left (``field``), or a grid of too many points (naming the longest
            span the step allows).
    """
    step = positive_number("step", step, "a finite time step > 0 [s]")
    samples = np.asarray(
        times
        if times is not None
        else getattr(trajectory, "t", getattr(trajectory, "times", [0.0])),
        dtype=float,
    ).reshape(-1)
    if samples.size == 0 or not np.all(np.isfinite(samples)):
        raise InputError(
            f"the times to check are {samples.tolist()!r:.80}; give finite times [s]",
            source,
            "times",
        )
    critical, exact = _critical_times(trajectory, samples)
    if exact:
        grid = np.union1d(samples, critical)
    else:
        span = float(samples[-1] - samples[0])
        if not span / step < MAX_GRID_POINTS:
            raise InputError(
                f"checking the limits on a grid of {step:g} s over t = {samples[0]:.6g} to "
                f"{samples[-1]:.6g} s needs {span / step:.3g} points, more than "
                f"{MAX_GRID_POINTS:.0e}: the longest span accepted is {MAX_GRID_POINTS * step:g} "
                "s (give shorter times, or a larger step)",
                source,
                "t",
            )
        grid = np.union1d(
            np.union1d(samples, np.arange(samples[0], samples[-1] + step, step)), critical
        )
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
        limit = per_joint(acceleration_limit, trajectory.dof, None, "acceleration_limit")
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


def per_joint(value, dof: int, source, field: str) -> np.ndarray:
    """A limit given as one number or one per joint, as ``dof`` values, each finite and > 0; an
    error naming ``field`` otherwise."""
    values = np.asarray(value, dtype=float)
    if values.ndim > 1 or (values.ndim == 1 and len(values) != dof):
        count = (
            f"{values.size} value{'' if values.size == 1 else 's'}"
            if values.ndim == 1
            else f"a nested list of shape {values.shape}"
        )
        raise InputError(
            f"{count}; the robot has {dof} joints: give one number or {dof} (one per joint)",
            source,
            field,
        )
    values = np.broadcast_to(values, (dof,))
    bad = ~(np.isfinite(values) & (values > 0))
    if bad.any():
        j = int(np.flatnonzero(bad)[0])
        where = f" (joint {j + 1})" if np.ndim(value) else ""
        raise InputError(f"must be > 0 and finite, got {values[j]:g}{where}", source, field)
    return values


def _critical_times(trajectory: Trajectory, samples: np.ndarray) -> tuple[np.ndarray, bool]:
    """Times inside ``[samples[0], samples[-1]]`` where a joint's position, velocity or
    acceleration can peak, and whether they are all of them (with the samples).

    Exact (``True``) for a spline (:class:`~urpc.trajectory_samples.FileTrajectory`): its breaks
    and the roots of its velocity, acceleration and jerk; and for rest-to-rest quintic segments
    (:class:`~urpc.trajectories.QuinticTrajectory`): the segment ends, the peak velocity at half a
    segment and the peak accelerations at ``(3 -+ sqrt 3) / 6`` of it (the position is monotone
    between ends). Unknown kinds (``False``): 64 points per interval between samples."""
    from scipy.interpolate import BPoly, BSpline, PPoly

    from .trajectories import QuinticTrajectory

    def inside(times: np.ndarray) -> np.ndarray:
        return times[(times >= samples[0]) & (times <= samples[-1])]

    spline = getattr(trajectory, "_spline", None)
    if isinstance(spline, (BSpline, BPoly)):
        found = []
        coefficients = spline.c.reshape(spline.c.shape[0], spline.c.shape[1], -1)
        for j in range(coefficients.shape[2]):
            if isinstance(spline, BSpline):
                piece = PPoly.from_spline(BSpline(spline.t, spline.c[:, j], spline.k))
            else:
                piece = PPoly.from_bernstein_basis(BPoly(coefficients[:, :, j], spline.x))
            found.append(piece.x)
            for order in (1, 2, 3):
                if piece.c.shape[0] > order:
                    roots = piece.derivative(order).roots(extrapolate=False)
                    found.append(roots[np.isfinite(roots)])
        return inside(np.concatenate(found)), True
    if isinstance(trajectory, QuinticTrajectory):
        own = trajectory.times
        start, length = own[:-1], np.diff(own)
        fractions = np.array([0.5, (3 - np.sqrt(3)) / 6, (3 + np.sqrt(3)) / 6])
        peaks = (start[:, None] + length[:, None] * fractions).reshape(-1)
        return inside(np.concatenate([own, peaks])), True
    if len(samples) < 2:
        return np.zeros(0), False
    fractions = np.linspace(0, 1, 65)[1:-1]
    return (samples[:-1, None] + np.diff(samples)[:, None] * fractions).reshape(-1), False


#: Default acceleration limit of waypoint segments [rad/s^2] when the scenario gives none.
WAYPOINT_ACCELERATION = 5.0


def _starts_at_zero(start: float, source, field: str, what: str) -> None:
    if abs(start) > 1e-12:
        raise InputError(
            f"{what} start at t = {start:g} s; a trajectory starts at t = 0: shift the times so "
            "the first is 0",
            source,
            field,
        )


def planned_trajectory(kind: str, options, robot, source=None) -> Trajectory:
    """The ``file`` or ``waypoints`` trajectory of a scenario's options, checked against the
    robot's limits (:func:`check_limits`): its times start at 0, its per-joint limits have one
    value per joint.

    Raises:
        InputError: naming the scenario file, the field, and for a limit the sample and joint.
    """
    dof = robot.dof
    acceleration = options.get("acceleration_limit")
    if acceleration is not None:
        acceleration = per_joint(acceleration, dof, source, "trajectory.acceleration_limit")
    if kind == "file":
        if "path" not in options:
            raise InputError(
                "a file trajectory needs path: FILE (.csv or .npz)", source, "trajectory.path"
            )
        trajectory = load_samples(options["path"], dof, robot.joint_names)
        _starts_at_zero(trajectory.t[0], trajectory.source, "t", "the samples")
        check_limits(
            trajectory,
            robot,
            acceleration_limit=acceleration,
            source=trajectory.source,
            field="trajectory",
        )
        return trajectory
    raw = options["points"]
    for index, point in enumerate(raw):
        count = len(point) if isinstance(point, (list, tuple, np.ndarray)) else 1
        if count != dof:
            raise InputError(
                f"{count} value{'' if count == 1 else 's'}; the robot has {dof} joints",
                source,
                f"trajectory.points[{index}]",
            )
    points = np.array(raw, dtype=float)
    if points.ndim != 2 or points.shape[1] != dof:
        raise InputError(f"each point needs {dof} joint values", source, "trajectory.points")
    times = options.get("times")
    if times is not None:
        times = np.asarray(times, dtype=float).reshape(-1)
        if len(times) != len(points):
            raise InputError(
                f"{len(times)} times for {len(points)} points; give one time per point",
                source,
                "trajectory.times",
            )
        if len(times):
            _starts_at_zero(times[0], source, "trajectory.times", "the waypoints")
    velocity = robot.velocity_limit
    velocity = np.where(np.isfinite(velocity) & (velocity > 0), velocity, np.inf)
    fraction = options.get("velocity_fraction", 0.5)
    a_limit = WAYPOINT_ACCELERATION if acceleration is None else acceleration
    try:
        trajectory = WaypointTrajectory(
            points,
            times,
            velocity_limit=fraction * velocity,
            acceleration_limit=a_limit,
        )
    except InputError as exc:
        raise InputError(exc.detail, source, f"trajectory.{exc.field or 'points'}") from None
    check_limits(
        trajectory, robot, acceleration_limit=acceleration, source=source, field="trajectory"
    )
    return trajectory
