"""Desired joint trajectories with analytic derivatives (below :mod:`urpc.control`: controllers,
certificates and simulators all read references from here).

A :class:`Trajectory` gives the reference ``(q_d, qd_d, qdd_d)`` [rad, rad/s, rad/s^2] (metres for
prismatic joints) at any time ``t`` [s]; :meth:`Trajectory.evaluate` does the same for an array of
times. Three families:

* :class:`PaperTrajectory`, the paper's test trajectory ``q_d(t) = a sin(pi t / 2) sin(pi t)``,
  ``a = (pi/4, -pi/8)`` (period 4 s, starts at rest at zero);
* :class:`SinusoidTrajectory`, ``q_d(t) = home + A sin(2 pi f t + phase)`` per joint;
* :class:`QuinticTrajectory`, rest-to-rest quintic segments through via points (C2 continuous).

:func:`~urpc.trajectory_generic.generic_trajectory` (importable from here too) picks a sinusoid or
quintic trajectory that fits any robot: inside its joint limits and below its velocity limits.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from . import names
from .errors import InputError
from .trajectory_generic import (  # noqa: F401  (re-exported: their home before the split)
    MAX_AMPLITUDE,
    generic_trajectory,
    home_configuration,
)
from .validation import per_joint


@dataclass(frozen=True)
class Reference:
    """Desired joint trajectory at one instant: position [rad], velocity [rad/s], acceleration
    [rad/s^2] (metres for prismatic joints), each of length ``dof``."""

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray


class Trajectory(ABC):
    """A desired joint trajectory ``t -> (q_d, qd_d, qdd_d)``.

    Attributes:
        dof: Number of joints.
    """

    dof: int
    #: Name used in scenario files.
    kind: str

    @abstractmethod
    def evaluate(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(q, qd, qdd)`` at time(s) ``t`` [s]: each of shape ``np.shape(t) + (dof,)``."""

    def reference(self, t: float) -> Reference:
        """The reference at one time ``t`` [s] (a text or NaN is refused: its reference would be
        a numpy error or NaN)."""
        q, qd, qdd = self.evaluate(as_time(t))
        return Reference(q=q, qd=qd, qdd=qdd)

    def jerk_bound(self, start: np.ndarray, stop: np.ndarray) -> np.ndarray:
        """A bound of ``|d^3 q_d / dt^3|`` [rad/s^3] per joint over each time interval
        ``[start, stop]`` (arrays of the same shape; result ``shape + (dof,)``), where the third
        derivative exists (the reference must be twice continuously differentiable).

        The certificate (:func:`urpc.certify`) encloses the reference over whole cells of time
        from it (:meth:`enclose`). A trajectory class that does not provide it cannot be
        certified; the shipped ones give it in closed form."""
        raise NotImplementedError(
            f"{type(self).__name__} gives no jerk bound: implement jerk_bound(start, stop) "
            "(a bound of |d^3 q_d/dt^3| per joint over [start, stop]) to certify it"
        )

    def fingerprint(self) -> dict[str, Any] | None:
        """Every parameter that determines this reference (what :meth:`evaluate` and
        :meth:`jerk_bound` read), as numbers, text and arrays: the certificate cache
        (:mod:`urpc.control.certificate_key`) keys a certificate on it with the class's name.
        ``None`` (the base class): not known, and the certificate is then computed every time.
        A subclass that overrides :meth:`evaluate` or :meth:`jerk_bound` must define its own (the
        cache ignores one inherited from above those methods)."""
        return None

    def period(self) -> float | None:
        """A period ``P`` [s] of the reference, ``q_d(t + P) = q_d(t)`` for every ``t >= 0``
        (exactly, in the mathematics of :meth:`evaluate`), or ``None``: none, or not known (the
        base class). The certificate covers one period of a periodic reference instead of the
        whole duration, since the states it bounds repeat (:func:`covered_span`). A subclass that
        overrides :meth:`evaluate`, :meth:`reference`, :meth:`jerk_bound` or :meth:`enclose` must
        define its own: one inherited from above those methods is ignored."""
        return None

    def enclose(self, start, stop) -> tuple[np.ndarray, ...]:
        """The reference over whole time intervals ``[start, stop]`` [s] (arrays, one per cell):
        ``(q, rq, qd, rqd, qdd, rqdd, J)``, centers and radii of ``q_d``, ``qd_d``, ``qdd_d`` and
        the jerk bound, each of shape ``cells + (dof,)``: ``|x(t) - x_c| <= r_x`` for every ``t``
        of a cell.

        Taylor expansion at the midpoint ``t_c`` with the Lagrange remainder (``h`` the
        half-width, ``J`` :meth:`jerk_bound`)::

            |qdd(t) - qdd(t_c)| <= h J
            |qd(t) - qd(t_c)|   <= h |qdd(t_c)| + h^2 J / 2
            |q(t) - q(t_c)|     <= h |qd(t_c)| + h^2 |qdd(t_c)| / 2 + h^3 J / 6

        plus a relative 1e-14 for the rounding of the evaluation at ``t_c``."""
        start, stop = np.asarray(start, dtype=float), np.asarray(stop, dtype=float)
        center = 0.5 * (start + stop)
        h = (0.5 * (stop - start))[..., None]
        shape = center.shape + (self.dof,)
        q, qd, qdd = (np.broadcast_to(x, shape) for x in self.evaluate(center))
        J = np.broadcast_to(self.jerk_bound(start, stop), shape)

        def rounding(x):
            return 1e-14 * (1.0 + np.abs(x))

        radius_qdd = h * J + rounding(qdd)
        radius_qd = h * np.abs(qdd) + 0.5 * h * h * J + rounding(qd)
        radius_q = h * np.abs(qd) + 0.5 * h * h * np.abs(qdd) + h**3 * J / 6 + rounding(q)
        return q, radius_q, qd, radius_qd, qdd, radius_qdd, J


def as_time(t) -> float:
    """``t`` as a float time [s]; a text, or NaN (whose reference would be NaN), is refused.

    Raises:
        InputError: ``t`` is not a number (field ``t``).
    """
    try:
        value = float(t)
    except (TypeError, ValueError):
        raise InputError(f"the time {t!r} is not a number [s]", field="t") from None
    if isinstance(t, str | bytes) or value != value:
        raise InputError(f"the time {t!r} is not a number [s]", field="t")
    return value


#: Smallest step between two sample or waypoint times, relative to the largest time (and at least
#: this many seconds): a reference evaluates the fraction ``(t - t_k) / h`` of a step ``h``, whose
#: rounding error is ``|t| 2.2e-16 / h``, and scales velocity and acceleration by ``1 / h`` and
#: ``1 / h^2``; steps of at least ``1e-9 max(1 s, |t|)`` keep that error below ``2.2e-7`` and
#: those scales finite. Closer samples are rounding noise, not a motion (a controller's sample
#: period is microseconds at the least).
MIN_TIME_STEP = 1e-9


def check_time_steps(times: np.ndarray, describe, source=None, field: str = "t") -> None:
    """Refuse ``times`` that do not increase strictly, or whose steps are below
    :data:`MIN_TIME_STEP` (of the largest time, at least 1 s): too close to tell apart, or to
    differentiate, in double precision. ``describe(row)`` names a sample in the message.

    Raises:
        InputError: naming the first bad sample, the step and the smallest step accepted.
    """
    steps = np.diff(times)
    if np.any(steps <= 0):
        row = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise InputError(
            f"times must increase strictly: {describe(row)} does not come after "
            f"t = {times[row - 1]:.6g} s",
            source,
            field,
        )
    smallest = MIN_TIME_STEP * max(1.0, float(np.max(np.abs(times))))
    if np.any(steps < smallest):
        row = int(np.flatnonzero(steps < smallest)[0]) + 1
        raise InputError(
            f"{describe(row)} comes {steps[row - 1]:.3g} s after the one before; the smallest "
            f"step accepted is {smallest:.3g} s ({MIN_TIME_STEP:g} times max(1 s, largest |t|)): "
            "closer times cannot be told apart or differentiated in double precision; merge or "
            "drop the close ones",
            source,
            field,
        )


def _joints(value: Sequence[float] | np.ndarray, name: str) -> np.ndarray:
    """``value`` as one finite number per joint (at least one joint): what sets a reference's
    joint count."""
    array = per_joint(name, value, None, "rad")
    if array.size == 0:
        raise InputError(f"{name} is empty; give one number per joint [rad]", field=name)
    return array


class PaperTrajectory(Trajectory):
    """``q_d(t) = amplitude * sin(pi t / 2) sin(pi t)`` (Giusti & Althoff, Sec. IV-A).

    Args:
        amplitude: Per-joint amplitude [rad]; the paper's ``(pi/4, -pi/8)`` by default.
    """

    kind = "paper"

    def __init__(self, amplitude: Sequence[float] = (np.pi / 4, -np.pi / 8)):
        self.amplitude = _joints(amplitude, "amplitude")
        self.dof = len(self.amplitude)

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)[..., None]
        w = np.pi
        s1, c1 = np.sin(w * t / 2), np.cos(w * t / 2)
        s2, c2 = np.sin(w * t), np.cos(w * t)
        shape = s1 * s2
        shape_d = w / 2 * c1 * s2 + w * s1 * c2
        shape_dd = -(5 * w**2 / 4) * s1 * s2 + w**2 * c1 * c2
        a = self.amplitude
        return a * shape, a * shape_d, a * shape_dd

    def reference(self, t: float) -> Reference:
        # Scalar fast path (called once per control step): same formulas as evaluate().
        if not (isinstance(t, float | int) and t == t):  # a text, None, NaN: refused
            t = as_time(t)
        w = math.pi
        s1, c1 = math.sin(w * t / 2), math.cos(w * t / 2)
        s2, c2 = math.sin(w * t), math.cos(w * t)
        a = self.amplitude
        return Reference(
            q=a * (s1 * s2),
            qd=a * (w / 2 * c1 * s2 + w * s1 * c2),
            qdd=a * (-(5 * w**2 / 4) * s1 * s2 + w**2 * c1 * c2),
        )

    def jerk_bound(self, start, stop):
        # q = a (cos(pi t / 2) - cos(3 pi t / 2)) / 2: |q^(3)| <= |a| ((pi/2)^3 + (3 pi/2)^3) / 2.
        peak = np.abs(self.amplitude) * 0.5 * ((np.pi / 2) ** 3 + (3 * np.pi / 2) ** 3)
        return np.broadcast_to(peak, np.shape(start) + (self.dof,))

    def fingerprint(self) -> dict[str, Any]:
        return {"amplitude": self.amplitude}

    def __repr__(self) -> str:
        return f"PaperTrajectory(amplitude={self.amplitude.tolist()})"

    def period(self) -> float:
        """4 s: ``sin(pi t / 2)`` and ``sin(pi t)`` both repeat after it."""
        return 4.0


class SinusoidTrajectory(Trajectory):
    """``q_d(t) = home + amplitude sin(2 pi frequency t + phase)``, per joint.

    Args:
        home: Center of the motion [rad or m].
        amplitude: Amplitude [rad or m] (scalar or per joint).
        frequency: Frequency [Hz] (scalar or per joint), >= 0.
        phase: Phase at ``t = 0`` [rad] (scalar or per joint); ``-pi/2`` starts at rest.
    """

    kind = "sinusoid"

    def __init__(self, home, amplitude, frequency, phase=0.0):
        self.home = _joints(home, "home")
        self.dof = len(self.home)
        self.amplitude = per_joint("amplitude", amplitude, self.dof, "rad")
        self.frequency = per_joint("frequency", frequency, self.dof, "Hz")
        self.phase = per_joint("phase", phase, self.dof, "rad")
        if np.any(self.frequency < 0):
            raise InputError(
                f"frequency must be >= 0 [Hz], got {self.frequency}", field="frequency"
            )
        self._omega = 2 * np.pi * self.frequency
        self._velocity_gain = self.amplitude * self._omega
        self._acceleration_gain = -self.amplitude * self._omega**2

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)[..., None]
        omega = 2 * np.pi * self.frequency
        angle = omega * t + self.phase
        s, c = np.sin(angle), np.cos(angle)
        a = self.amplitude
        return self.home + a * s, a * omega * c, -a * omega**2 * s

    def reference(self, t: float) -> Reference:
        # Scalar fast path (called once per control step): same formulas as evaluate().
        if not (isinstance(t, float | int) and t == t):  # a text, None, NaN: refused
            t = as_time(t)
        angle = self._omega * t + self.phase
        s = np.sin(angle)
        return Reference(
            q=self.home + self.amplitude * s,
            qd=self._velocity_gain * np.cos(angle),
            qdd=self._acceleration_gain * s,
        )

    def jerk_bound(self, start, stop):
        peak = np.abs(self.amplitude) * self._omega**3
        return np.broadcast_to(peak, np.shape(start) + (self.dof,))

    def period(self) -> float | None:
        """The least common period [s] of the moving joints (non-zero amplitude and frequency),
        exactly: the frequencies are binary fractions, so each period ``1 / f`` is a rational
        number and their least common multiple is computed in rationals. ``None`` when no joint
        moves or when that period exceeds 10^6 s (frequencies with no short common period, as
        0.1 and 0.3 written in binary)."""
        moving = (self.amplitude != 0) & (self.frequency > 0)
        if not np.any(moving):
            return None
        common = None
        for f in self.frequency[moving]:
            period = Fraction(1) / Fraction(float(f))
            if common is None:
                common = period
            else:
                numerator = math.lcm(common.numerator, period.numerator)
                common = Fraction(numerator, math.gcd(common.denominator, period.denominator))
        return float(common) if common <= 10**6 else None

    @property
    def peak_velocity(self) -> np.ndarray:
        """``|A| 2 pi f`` [rad/s] per joint."""
        return np.abs(self.amplitude) * 2 * np.pi * self.frequency

    @property
    def peak_acceleration(self) -> np.ndarray:
        """``|A| (2 pi f)^2`` [rad/s^2] per joint."""
        return np.abs(self.amplitude) * (2 * np.pi * self.frequency) ** 2

    def fingerprint(self) -> dict[str, Any]:
        return {
            "home": self.home,
            "amplitude": self.amplitude,
            "frequency": self.frequency,
            "phase": self.phase,
        }

    def __repr__(self) -> str:
        return (
            f"SinusoidTrajectory(home={self.home.tolist()}, amplitude={self.amplitude.tolist()}, "
            f"frequency={self.frequency.tolist()}, phase={self.phase.tolist()})"
        )


#: Peak |velocity| and |acceleration| of the rest-to-rest quintic blend ``10 s^3 - 15 s^4 + 6 s^5``
#: per unit distance, for a unit duration.
QUINTIC_PEAK_VELOCITY = 15.0 / 8.0
QUINTIC_PEAK_ACCELERATION = 10.0 / np.sqrt(3.0)


class QuinticTrajectory(Trajectory):
    """Rest-to-rest quintic segments through via points (zero velocity and acceleration at each).

    Between ``times[k]`` and ``times[k+1]``, ``q_d = p_k + (p_{k+1} - p_k) b(tau)`` with
    ``tau = (t - times[k]) / (times[k+1] - times[k])`` and ``b = 10 tau^3 - 15 tau^4 + 6 tau^5``.
    Before the first time the trajectory holds the first point, after the last it holds the last.

    Args:
        points: Via points [rad or m], shape ``(n_points, dof)``, at least 2.
        times: Times of the points [s], strictly increasing, length ``n_points``.
    """

    kind = "quintic"

    def __init__(self, points, times):
        try:
            self.points = np.atleast_2d(np.asarray(points, dtype=float))
            self.times = np.asarray(times, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(
                "points must be a (points, joints) array of numbers and times a list of numbers "
                "(every point with the same number of joints)",
                field="points",
            ) from None
        if self.points.ndim != 2 or self.points.shape[1] == 0:
            raise InputError(
                f"points has shape {self.points.shape}; give (points, joints)", field="points"
            )
        if len(self.points) < 2 or len(self.times) != len(self.points):
            raise InputError(
                f"need at least 2 points and one time per point, got {len(self.points)} points "
                f"and {len(self.times)} times",
                field="points",
            )
        if not (np.all(np.isfinite(self.points)) and np.all(np.isfinite(self.times))):
            raise InputError("points and times must be finite", field="points")
        check_time_steps(
            self.times, lambda row: f"point {row} (t = {self.times[row]:.6g} s)", field="times"
        )
        self.dof = self.points.shape[1]
        # position, velocity, acceleration and jerk of each segment: |delta| times the blend's
        # peaks over L^0..L^3 (a finite point may be 2e308 from the next, a short segment's
        # acceleration overflow)
        lengths = np.diff(self.times)[:, None]
        with np.errstate(over="ignore", invalid="ignore"):
            delta = np.abs(np.diff(self.points, axis=0))
            peaks = {
                "position step": delta,
                "velocity": QUINTIC_PEAK_VELOCITY * delta / lengths,
                "acceleration": QUINTIC_PEAK_ACCELERATION * delta / lengths**2,
                "jerk": 60.0 * delta / lengths**3,
            }
        for what, values in peaks.items():
            if not np.all(np.isfinite(values)):
                segment = int(np.flatnonzero(~np.all(np.isfinite(values), axis=1))[0])
                raise InputError(
                    f"the {what} of the segment from point {segment} to {segment + 1} "
                    f"(t = {self.times[segment]:.6g} to {self.times[segment + 1]:.6g} s) "
                    "overflows double precision: give points closer together or the segment "
                    "more time",
                    field="points",
                )

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        k = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2)
        start, stop = self.times[k], self.times[k + 1]
        length = stop - start
        tau = np.clip((t - start) / length, 0.0, 1.0)[..., None]
        length = length[..., None]
        blend = tau**3 * (10 - 15 * tau + 6 * tau**2)
        blend_d = 30 * tau**2 * (1 - tau) ** 2 / length
        blend_dd = 60 * tau * (1 - tau) * (1 - 2 * tau) / length**2
        delta = self.points[k + 1] - self.points[k]
        return self.points[k] + delta * blend, delta * blend_d, delta * blend_dd

    def jerk_bound(self, start, stop):
        """``60 |p_{k+1} - p_k| / L_k^3`` over the segments that meet ``[start, stop]`` (the
        blend's third derivative ``(60 - 360 tau + 360 tau^2) / L^3`` peaks at the segment ends);
        zero where the trajectory holds a point."""
        start, stop = np.asarray(start, dtype=float), np.asarray(stop, dtype=float)
        lengths = np.diff(self.times)
        peaks = 60.0 * np.abs(np.diff(self.points, axis=0)) / lengths[:, None] ** 3  # (seg, dof)
        last_segment = len(lengths) - 1
        first = np.clip(np.searchsorted(self.times, start, side="right") - 1, 0, last_segment)
        last = np.clip(np.searchsorted(self.times, stop, side="left") - 1, 0, last_segment)
        result = np.zeros(start.shape + (self.dof,))
        for index in np.ndindex(start.shape):
            if stop[index] <= self.times[0] or start[index] >= self.times[-1]:
                continue  # holding a point
            a = first[index]
            result[index] = peaks[a : max(a, last[index]) + 1].max(axis=0)
        return result

    def fingerprint(self) -> dict[str, Any]:
        return {"points": self.points, "times": self.times}

    def __repr__(self) -> str:
        return f"QuinticTrajectory(points={self.points.tolist()}, times={self.times.tolist()})"


#: Kinds a scenario names (:data:`urpc.names.TRAJECTORY_KINDS`); ``file`` and ``waypoints`` are
#: built by :mod:`urpc.trajectory_sources`.
TRAJECTORY_KINDS = names.TRAJECTORY_KINDS


def defining_class(kind: type, name: str) -> type:
    """The class of ``kind``'s method resolution order that defines ``name``."""
    for base in kind.__mro__:
        if name in vars(base):
            return base
    return object


#: The methods of a reference that the certificate reads.
READ_METHODS = ("evaluate", "reference", "jerk_bound", "enclose")


def covered_span(trajectory: Trajectory, duration: float) -> float:
    """The time span [s] from ``0`` whose states of the reference are those of ``[0,
    duration]``: one :meth:`Trajectory.period` when it is shorter (widened by a relative
    ``1e-12`` for the rounding of the period to a float), else the duration. A period inherited
    from above a method that computes the reference is ignored."""
    owner = defining_class(type(trajectory), "period")
    if not all(issubclass(owner, defining_class(type(trajectory), m)) for m in READ_METHODS):
        return float(duration)
    period = trajectory.period()
    if period is None or not (0 < period < duration):
        return float(duration)
    return min(float(duration), float(period) * (1 + 1e-12))
