"""Quintic moves between given positions, each ending at rest:

* :class:`WaypointTrajectory`: rest-to-rest quintic segments through waypoints, each as short as
  the velocity and acceleration limits allow (:func:`segment_durations`), or at given times.
* :class:`StreamedReference`: a reference whose target is changed while a loop runs
  (:meth:`StreamedReference.set_target`): a quintic from the current reference (position,
  velocity, acceleration) to the new target, so the reference stays C2 across updates.
* :class:`Approach`: a rest-to-rest move from where the arm is to where a trajectory starts, then
  the trajectory (``urpc run`` puts it in front when the arm starts elsewhere).
"""

from __future__ import annotations

import threading

import numpy as np

from .errors import InputError
from .trajectories import (
    QUINTIC_PEAK_ACCELERATION,
    QUINTIC_PEAK_VELOCITY,
    QuinticTrajectory,
    Reference,
    Trajectory,
)
from .validation import check_type, number_in, per_joint, positive_number


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


def move_limits(dof: int, velocity_limit, acceleration_limit, minimum) -> tuple:
    """``(velocity_limit, acceleration_limit, minimum)`` checked: the limits ``> 0`` per joint
    (a scalar for every joint; ``inf``: no limit), ``minimum`` a finite duration ``> 0`` [s].

    Raises:
        InputError: a limit that is not a number, NaN, ``<= 0`` or of another length than the
            ``dof`` joints; a ``minimum`` that is not finite and ``> 0`` (each names its field).
    """
    limits = []
    for field, value, unit in (
        ("velocity_limit", velocity_limit, "rad/s"),
        ("acceleration_limit", acceleration_limit, "rad/s^2"),
    ):
        array = per_joint(field, value, dof, unit, finite=False)
        if not np.all(array > 0):
            raise InputError(
                f"{array.tolist()}: every limit must be > 0 [{unit}] (inf: no limit)", field=field
            )
        limits.append(array)
    minimum = positive_number("minimum", minimum, "a finite duration > 0 [s]")
    return limits[0], limits[1], minimum


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
        try:
            points = np.atleast_2d(np.asarray(points, dtype=float))
        except (TypeError, ValueError):
            raise InputError(
                "points must be a (points, joints) array of numbers, every point with the same "
                "number of joints",
                field="points",
            ) from None
        if points.ndim != 2 or points.shape[1] == 0:
            raise InputError(
                f"points has shape {points.shape}; give (points, joints), at least one joint",
                field="points",
            )
        if times is None:
            if len(points) < 2:
                raise InputError("need at least 2 waypoints", field="points")
            velocity_limit, acceleration_limit, minimum = move_limits(
                points.shape[1], velocity_limit, acceleration_limit, minimum
            )
            start = number_in("start", start, "a finite time [s]", lambda x: True)
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
        try:
            q0 = np.asarray(q0, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(f"{q0!r} is not a vector of joint positions", field="q0") from None
        if q0.size == 0 or not np.all(np.isfinite(q0)):
            raise InputError(f"{q0.tolist()} must be finite joint positions [rad]", field="q0")
        self.dof = len(q0)
        self.velocity_limit, self.acceleration_limit, self.minimum = move_limits(
            self.dof, velocity_limit, acceleration_limit, minimum
        )
        zeros = np.zeros(self.dof)
        self._segment = (0.0, np.inf, _quintic(q0, zeros, zeros, q0, 1.0), q0)
        self._lock = threading.Lock()
        self.updates = 0

    def set_target(self, q, t: float, duration: float | None = None) -> float:
        """Move to ``q`` [rad] starting at loop time ``t`` [s]; returns the segment's duration."""
        try:
            q = np.asarray(q, dtype=float).reshape(self.dof)
        except (TypeError, ValueError):
            raise InputError(
                f"{q!r} is not {self.dof} joint positions (one per joint)", field="target"
            ) from None
        if not np.all(np.isfinite(q)):
            raise InputError(f"target {q.tolist()} is not finite", field="target")
        t = number_in("t", t, "a finite time [s]", lambda x: True)
        if duration is not None:
            duration = positive_number("duration", duration, "a finite duration > 0 [s] or None")
        current = self.reference(t)
        given = duration is not None
        # a finite target far away (1e308) or a tiny duration (1e-300) overflows the quintic:
        # refused below, by name, instead of a NaN reference
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            if duration is None:
                points = np.stack([current.q, q])
                duration = float(
                    segment_durations(
                        points, self.velocity_limit, self.acceleration_limit, self.minimum
                    )[0]
                )
                # a moving start needs time to turn around: not shorter than stopping at the limit
                stop = np.nan_to_num(np.abs(current.qd) / self.acceleration_limit, posinf=0.0)
                duration = max(duration, 2.0 * float(stop.max()))
            coefficients = _quintic(current.q, current.qd, current.qdd, q, duration)
        if not (np.isfinite(duration) and np.all(np.isfinite(coefficients))):
            raise InputError(
                f"the move to {q.tolist()} over {duration:.3g} s overflows double precision (its "
                "position, velocity or acceleration is not finite): give "
                + ("a longer duration or a nearer target" if given else "a nearer target"),
                field="duration" if given else "target",
            )
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
        check_type("trajectory", trajectory, Trajectory, "a urpc.Trajectory")
        self.dof = trajectory.dof
        self.kind = trajectory.kind
        self.trajectory = trajectory
        q_start = per_joint("q_start", q_start, self.dof, "rad", broadcast=False)
        self.duration = positive_number("duration", duration, "a finite duration > 0 [s]")
        start = trajectory.reference(0.0)
        try:
            self.segment = QuinticTrajectory(np.stack([q_start, start.q]), [0.0, self.duration])
        except InputError as exc:
            raise InputError(
                f"the approach from q_start to the trajectory's start: {exc.detail}",
                field="duration",
            ) from None

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
