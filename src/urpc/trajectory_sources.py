"""Trajectories from outside urpc: sampled files from a planner, waypoints, a setpoint streamed
while the loop runs, and an approach segment in front of any trajectory.

* :class:`FileTrajectory` (:func:`from_samples`, :func:`load_samples`): samples ``t, q`` (and
  optionally ``qd``, ``qdd``) interpolated twice continuously differentiably with scipy splines:
  from ``q`` alone a quintic interpolating B-spline (``make_interp_spline(k=5)``) that starts and
  ends at rest; with ``qd`` (and ``qdd``) a piecewise quintic Hermite (``BPoly.from_derivatives``)
  through every given value (``qdd`` by differences of ``qd`` when absent).
* :class:`WaypointTrajectory`: rest-to-rest quintic segments through waypoints, each as short as
  the velocity and acceleration limits allow (or at given times).
* :class:`StreamedReference`: a reference whose target is changed while a loop runs
  (:meth:`StreamedReference.set_target`): a quintic from the current reference (position,
  velocity, acceleration) to the new target, so the reference stays C2 across updates.
* :class:`Approach`: a rest-to-rest move from where the arm is to where a trajectory starts, then
  the trajectory (``urpc run`` puts it in front when the arm starts elsewhere).

:func:`check_limits` refuses a trajectory that leaves the joint position, velocity or
acceleration limits, naming the sample and the joint.
"""

from __future__ import annotations

import re
import threading
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputError, no_file
from .trajectories import (
    QUINTIC_PEAK_ACCELERATION,
    QUINTIC_PEAK_VELOCITY,
    QuinticTrajectory,
    Reference,
    Trajectory,
)


class FileTrajectory(Trajectory):
    """Samples ``t`` [s] (strictly increasing, at least 2), ``q`` ``(K, dof)`` [rad], optional
    ``qd``, ``qdd``, interpolated C2 (module docstring). Before the first sample the reference
    holds the first, after the last it holds the last at rest.

    Attributes:
        t, q: The samples. source: The file they came from, if any. header_lines: Lines before
            the first sample in that file (for messages).
    """

    kind = "file"

    def __init__(self, t, q, qd=None, qdd=None, *, source=None, header_lines: int = 0):
        from scipy.interpolate import make_interp_spline

        self.source = None if source is None else str(source)
        self.header_lines = header_lines
        self.t = np.asarray(t, dtype=float).reshape(-1)
        self.q = np.asarray(q, dtype=float)
        if self.q.ndim == 1:
            self.q = self.q[:, None]
        if len(self.t) < 2 or self.q.shape[0] != len(self.t):
            raise InputError(
                f"need at least 2 samples and one row of q per time, got {len(self.t)} times and "
                f"{self.q.shape[0]} rows",
                self.source,
                "q",
            )
        for name, values in (("t", self.t), ("q", self.q), ("qd", qd), ("qdd", qdd)):
            if values is not None and not np.all(np.isfinite(values)):
                row = int(
                    np.flatnonzero(
                        ~np.all(np.isfinite(np.reshape(values, (len(self.t), -1))), axis=1)
                    )[0]
                )
                raise InputError(f"{self.describe(row)} is not finite", self.source, name)
        steps = np.diff(self.t)
        if np.any(steps <= 0):
            row = int(np.flatnonzero(steps <= 0)[0]) + 1
            raise InputError(
                f"times must increase strictly: {self.describe(row)} does not come after "
                f"t = {self.t[row - 1]:.6g} s",
                self.source,
                "t",
            )
        self.dof = self.q.shape[1]
        if qd is None:
            k = 5 if len(self.t) >= 6 else (3 if len(self.t) >= 4 else 1)
            if k == 5:
                rest = [(1, np.zeros(self.dof)), (2, np.zeros(self.dof))]
                spline = make_interp_spline(self.t, self.q, k=5, bc_type=(rest, rest))
            elif k == 3:
                rest = [(1, np.zeros(self.dof))]
                spline = make_interp_spline(self.t, self.q, k=3, bc_type=(rest, rest))
            else:  # two or three samples: rest-to-rest quintics between them
                spline = _quintic_bpoly(
                    self.t, self.q, np.zeros_like(self.q), np.zeros_like(self.q)
                )
        else:
            qd = np.asarray(qd, dtype=float).reshape(self.q.shape)
            qdd = (
                np.gradient(qd, self.t, axis=0)
                if qdd is None
                else np.asarray(qdd, dtype=float).reshape(self.q.shape)
            )
            spline = _quintic_bpoly(self.t, self.q, qd, qdd)
        self._spline = spline
        self._velocity = spline.derivative(1)
        self._acceleration = spline.derivative(2)

    def describe(self, row: int) -> str:
        line = (
            f", line {row + self.header_lines + 1}"
            if self.source and self.source.endswith(".csv")
            else ""
        )
        return f"sample {row}{line} (t = {self.t[row]:.6g} s)"

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        inside = np.clip(t, self.t[0], self.t[-1])
        q = self._spline(inside)
        moving = ((t >= self.t[0]) & (t <= self.t[-1]))[..., None]
        qd = np.where(moving, self._velocity(inside), 0.0)
        qdd = np.where(moving, self._acceleration(inside), 0.0)
        return q, qd, qdd

    def reference(self, t: float) -> Reference:
        if self.t[0] <= t <= self.t[-1]:
            return Reference(self._spline(t), self._velocity(t), self._acceleration(t))
        q, qd, qdd = self.evaluate(float(t))
        return Reference(q, qd, qdd)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def _ends_at_rest(self) -> bool:
        ends = np.array([self.t[0], self.t[-1]])
        return bool(
            np.all(np.abs(self._velocity(ends)) <= 1e-9)
            and np.all(np.abs(self._acceleration(ends)) <= 1e-9)
        )

    def jerk_bound(self, start, stop):
        """``|d^3 q_d / dt^3|`` over ``[start, stop]``: the third derivative of the spline is a
        spline whose value on each knot span lies in the convex hull of that span's coefficients
        (B-spline and Bernstein forms alike), so ``max |coefficient|`` of the span bounds it; the
        largest over the spans that meet the interval (zero outside the samples, where the
        reference holds its end at rest)."""
        from scipy.interpolate import BPoly

        if not hasattr(self, "_jerk_pieces"):
            third = self._spline.derivative(3)
            if isinstance(third, BPoly):
                breaks, bound = third.x, np.abs(third.c).max(axis=0)  # (pieces, dof)
            else:  # BSpline of degree k: span [t_i, t_i+1] uses coefficients i - k .. i
                k, knots, c = third.k, third.t, np.abs(third.c)
                spans = range(k, len(knots) - k - 1)
                breaks = np.array([knots[i] for i in spans] + [knots[len(knots) - k - 1]])
                bound = np.array([c[i - k : i + 1].max(axis=0) for i in spans])
            self._jerk_pieces = (np.asarray(breaks), np.asarray(bound) * (1 + 1e-12))
        breaks, bound = self._jerk_pieces
        start, stop = np.asarray(start, dtype=float), np.asarray(stop, dtype=float)
        outside = bool(np.any(start < self.t[0]) or np.any(stop > self.t[-1]))
        if outside and not self._ends_at_rest():
            raise InputError(
                f"the trajectory of {self.source or 'samples'} does not start and end at rest "
                "(velocity or acceleration not zero at its first or last sample), so holding "
                "its end is not twice continuously differentiable: certify it within "
                f"[{self.t[0]:g}, {self.t[-1]:g}] s",
                source=self.source,
                field="duration",
            )
        result = np.zeros(start.shape + (self.dof,))
        last = len(breaks) - 2
        for index in np.ndindex(start.shape):
            a, b = max(start[index], self.t[0]), min(stop[index], self.t[-1])
            if a > b:
                continue
            first = int(np.clip(np.searchsorted(breaks, a, side="right") - 1, 0, last))
            final = int(np.clip(np.searchsorted(breaks, b, side="left") - 1, first, last))
            result[index] = bound[first : final + 1].max(axis=0)
        return result

    def fingerprint(self) -> dict[str, Any]:
        """The samples and the interpolating spline (its knots or breaks, coefficients, degree):
        what :meth:`evaluate` and :meth:`jerk_bound` read."""
        spline = self._spline
        return {
            "t": self.t,
            "q": self.q,
            "spline": type(spline).__name__,
            "knots": getattr(spline, "t", getattr(spline, "x", None)),
            "coefficients": spline.c,
            "degree": getattr(spline, "k", None),
        }

    def __repr__(self) -> str:
        return f"FileTrajectory({len(self.t)} samples, dof={self.dof}, t=[{self.t[0]:g}, {self.t[-1]:g}] s)"


def _quintic_bpoly(t, q, qd, qdd):
    """Piecewise quintic Hermite through values, slopes and curvatures (C2)."""
    from scipy.interpolate import BPoly

    y = np.stack([q, qd, qdd], axis=1)  # (K, 3, dof)
    return BPoly.from_derivatives(t, y)


def from_samples(t, q, qd=None, qdd=None) -> FileTrajectory:
    """A C2 trajectory through samples ``t`` [s], ``q`` ``(K, dof)`` [rad] (see
    :class:`FileTrajectory`)."""
    return FileTrajectory(t, q, qd, qdd)


_NAME = re.compile(r"^(qdd|qd|q)[_\s-]?(\d+)$")


def load_samples(path: str | Path, dof: int | None = None, joint_names=()) -> FileTrajectory:
    """Read a trajectory file: a CSV (a header row ``t, q1..qn[, qd1..qdn[, qdd1..qddn]]``, names
    ``q1``/``q_1``/a joint's name for positions, ``qd1``, ``qdd1`` for derivatives; or no header and
    ``1 + n``, ``1 + 2n`` or ``1 + 3n`` columns) or an NPZ (arrays ``t``, ``q`` and optionally
    ``qd``, ``qdd``).

    Raises:
        InputError: a missing or unreadable file, wrong columns, a non-finite value, times that do
            not increase (the sample is named).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(no_file(path, "trajectory file"), path)
    if path.suffix.lower() == ".npz":
        try:
            with np.load(path, allow_pickle=False) as archive:
                data = {k: archive[k] for k in archive.files}
        except (OSError, ValueError) as exc:
            raise InputError(f"not a readable NPZ file ({exc})", path) from None
        if "t" not in data or "q" not in data:
            raise InputError(
                f"needs arrays 't' and 'q'; found {', '.join(sorted(data)) or 'none'}", path
            )
        q = np.asarray(data["q"], dtype=float)
        q = q[:, None] if q.ndim == 1 else q
        _check_dof(q.shape[1], dof, path)
        return FileTrajectory(data["t"], q, data.get("qd"), data.get("qdd"), source=path)
    if path.suffix.lower() != ".csv":
        raise InputError(f"unknown trajectory file type '{path.suffix}'; valid: .csv, .npz", path)
    text = path.read_text().splitlines()
    rows = [line for line in text if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise InputError("the file has no samples", path)
    first = [cell.strip() for cell in rows[0].split(",")]
    has_header = not _is_number(first[0])
    header_lines = text.index(rows[0]) + 1 if has_header else text.index(rows[0])
    try:
        table = np.array(
            [[float(c) for c in r.split(",")] for r in rows[1 if has_header else 0 :]], ndmin=2
        )
    except ValueError as exc:
        raise InputError(
            f"a value is not a number ({exc}); expected t, q1..qn per row", path
        ) from None
    if table.size == 0:
        raise InputError("the file has a header but no samples", path)
    columns = table.shape[1]
    if has_header:
        if first[0].lower() not in ("t", "time"):
            raise InputError(f"the first column is '{first[0]}'; expected t [s]", path, "t")
        groups: dict[str, list[int]] = {"q": [], "qd": [], "qdd": []}
        names = list(joint_names)
        for index, name in enumerate(first[1:], start=1):
            match = _NAME.match(name.replace(" ", ""))
            if match:
                groups[match.group(1)].append(index)
            elif name in names:
                groups["q"].append(index)
            else:
                raise InputError(
                    f"unknown column '{name}'; expected q1..qn, qd1..qdn, qdd1..qddn or joint names",
                    path,
                    name,
                )
        n = len(groups["q"])
        for kind in ("qd", "qdd"):
            if groups[kind] and len(groups[kind]) != n:
                raise InputError(
                    f"{len(groups[kind])} {kind} columns for {n} q columns", path, kind
                )
        _check_dof(n, dof, path)
        pick = {kind: table[:, idx] if idx else None for kind, idx in groups.items()}
    else:
        n = dof or columns - 1
        if columns not in (1 + n, 1 + 2 * n, 1 + 3 * n):
            raise InputError(
                f"{columns} columns; expected t and {n}, {2 * n} or {3 * n} more", path
            )
        blocks = [table[:, 1 + k * n : 1 + (k + 1) * n] for k in range((columns - 1) // n)]
        pick = {
            "q": blocks[0],
            "qd": blocks[1] if len(blocks) > 1 else None,
            "qdd": blocks[2] if len(blocks) > 2 else None,
        }
    return FileTrajectory(
        table[:, 0], pick["q"], pick["qd"], pick["qdd"], source=path, header_lines=header_lines
    )


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_dof(n: int, dof: int | None, path) -> None:
    if dof is not None and n != dof:
        raise InputError(f"{n} joint columns; the robot has {dof} joints", path, "q")


# ============================================================================ waypoints
def segment_durations(
    points, velocity_limit, acceleration_limit, minimum: float = 0.5
) -> np.ndarray:
    """The shortest duration [s] of each rest-to-rest quintic segment between ``points`` whose
    peak speed and acceleration stay within the limits (``inf``: no limit), at least ``minimum``."""
    distance = np.abs(np.diff(np.asarray(points, dtype=float), axis=0))
    v = np.asarray(velocity_limit, dtype=float)
    a = np.asarray(acceleration_limit, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        by_speed = np.where(distance > 0, QUINTIC_PEAK_VELOCITY * distance / v, 0.0)
        by_acceleration = np.where(
            distance > 0, np.sqrt(QUINTIC_PEAK_ACCELERATION * distance / a), 0.0
        )
    return np.maximum(np.maximum(by_speed, by_acceleration).max(axis=1), minimum)


class WaypointTrajectory(QuinticTrajectory):
    """Rest-to-rest quintic segments through ``points`` ``(K, dof)`` [rad], at ``times`` [s] or, by
    default, each segment as short as ``velocity_limit`` [rad/s] and ``acceleration_limit``
    [rad/s^2] allow (times start at ``start`` [s])."""

    kind = "waypoints"

    def __init__(
        self,
        points,
        times=None,
        *,
        velocity_limit=np.inf,
        acceleration_limit=np.inf,
        minimum=0.5,
        start=0.0,
    ):
        points = np.atleast_2d(np.asarray(points, dtype=float))
        if times is None:
            if len(points) < 2:
                raise InputError("need at least 2 waypoints", field="points")
            durations = segment_durations(points, velocity_limit, acceleration_limit, minimum)
            times = start + np.concatenate([[0.0], np.cumsum(durations)])
        super().__init__(points, times)

    def __repr__(self) -> str:
        return f"WaypointTrajectory({len(self.points)} points, times={np.round(self.times, 4).tolist()})"


# ============================================================================ streamed
def _quintic(p0, v0, a0, p1, duration):
    """Coefficients ``c[0..5]`` (per joint) of the quintic from ``(p0, v0, a0)`` to ``(p1, 0, 0)``."""
    T = duration
    d = p1 - p0
    c3 = (20 * d - (12 * v0) * T - 3 * a0 * T**2) / (2 * T**3)
    c4 = (-30 * d + 16 * v0 * T + 3 * a0 * T**2) / (2 * T**4)
    c5 = (12 * d - 6 * v0 * T - a0 * T**2) / (2 * T**5)
    return np.stack([p0, v0, a0 / 2, c3, c4, c5])


class StreamedReference(Trajectory):
    """A reference updated while the loop runs: :meth:`set_target` (from any thread) starts a
    quintic from the current reference to the target, ending at rest, over ``duration`` [s] or
    the shortest one the limits allow. Holds ``q0`` until the first target."""

    kind = "streamed"

    def __init__(
        self, q0, *, velocity_limit=np.inf, acceleration_limit=np.inf, minimum: float = 0.05
    ):
        q0 = np.asarray(q0, dtype=float).reshape(-1)
        self.dof = len(q0)
        self.velocity_limit = np.broadcast_to(np.asarray(velocity_limit, float), (self.dof,))
        self.acceleration_limit = np.broadcast_to(
            np.asarray(acceleration_limit, float), (self.dof,)
        )
        self.minimum = float(minimum)
        zeros = np.zeros(self.dof)
        self._segment = (0.0, np.inf, _quintic(q0, zeros, zeros, q0, 1.0), q0)
        self._lock = threading.Lock()
        self.updates = 0

    def set_target(self, q, t: float, duration: float | None = None) -> float:
        """Move to ``q`` [rad] starting at loop time ``t`` [s]; returns the segment's duration."""
        q = np.asarray(q, dtype=float).reshape(self.dof)
        if not np.all(np.isfinite(q)):
            raise InputError(f"target {q.tolist()} is not finite", field="target")
        current = self.reference(t)
        if duration is None:
            points = np.stack([current.q, q])
            duration = float(
                segment_durations(
                    points, self.velocity_limit, self.acceleration_limit, self.minimum
                )[0]
            )
            # a moving start needs time to turn around: not shorter than stopping at the limit
            with np.errstate(divide="ignore", invalid="ignore"):
                stop = np.nan_to_num(np.abs(current.qd) / self.acceleration_limit, posinf=0.0)
            duration = max(duration, 2.0 * float(stop.max()))
        coefficients = _quintic(current.q, current.qd, current.qdd, q, duration)
        with self._lock:
            self._segment = (float(t), float(t) + duration, coefficients, q)
            self.updates += 1
        return duration

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        start, stop, c, target = self._segment
        s = np.clip(t - start, 0.0, stop - start)[..., None]
        q = c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * (c[4] + s * c[5]))))
        qd = c[1] + s * (2 * c[2] + s * (3 * c[3] + s * (4 * c[4] + s * 5 * c[5])))
        qdd = 2 * c[2] + s * (6 * c[3] + s * (12 * c[4] + s * 20 * c[5]))
        still = ((t > stop) | (t < start))[..., None]
        q = np.where((t > stop)[..., None], target, q)
        return q, np.where(still, 0.0, qd), np.where(still, 0.0, qdd)


# ============================================================================ approach
class Approach(Trajectory):
    """A rest-to-rest quintic from ``q_start`` to ``trajectory``'s start over ``duration`` [s],
    then ``trajectory`` shifted by ``duration``."""

    def __init__(self, q_start, trajectory: Trajectory, duration: float):
        self.dof = trajectory.dof
        self.kind = trajectory.kind
        self.trajectory = trajectory
        self.duration = float(duration)
        start = trajectory.reference(0.0)
        self.segment = QuinticTrajectory(
            np.stack([np.asarray(q_start, float), start.q]), [0.0, self.duration]
        )

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        first = self.segment.evaluate(t)
        then = self.trajectory.evaluate(t - self.duration)
        before = (t < self.duration)[..., None]
        return tuple(np.where(before, a, b) for a, b in zip(first, then, strict=True))

    def reference(self, t: float) -> Reference:
        if t < self.duration:
            return self.segment.reference(t)
        return self.trajectory.reference(t - self.duration)


# ============================================================================ limits
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
