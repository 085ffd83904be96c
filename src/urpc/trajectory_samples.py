"""Trajectories through sampled points from a planner, interpolated twice continuously
differentiably with scipy splines.

:class:`FileTrajectory` (:func:`from_samples`; read from a file by
:func:`urpc.trajectory_files.load_samples`) takes samples ``t, q`` and optionally ``qd``, ``qdd``:
from ``q`` alone a quintic interpolating B-spline (``make_interp_spline(k=5)``) that starts and
ends at rest; with ``qd`` (and ``qdd``) a piecewise quintic Hermite (``BPoly.from_derivatives``)
through every given value (``qdd`` by differences of ``qd`` when absent).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .errors import InputError
from .trajectories import Reference, Trajectory, as_time, check_time_steps


class FileTrajectory(Trajectory):
    """Samples ``t`` [s] (strictly increasing, at least 2), ``q`` ``(K, dof)`` [rad], optional
    ``qd``, ``qdd``, interpolated C2 (module docstring). Before the first sample the reference
    holds the first, after the last it holds the last at rest.

    Attributes:
        t, q: The samples. source: The file they came from, if any. lines: The line of that
            file each sample was read from (a CSV's, for messages; ``None``: not a text file).
    """

    kind = "file"

    def __init__(self, t, q, qd=None, qdd=None, *, source=None, lines=None):
        self.source = None if source is None else str(source)
        self.lines = None if lines is None else [int(line) for line in lines]
        self.t = self._array("t", t).reshape(-1)
        self.q = self._array("q", q)
        if self.q.ndim == 1:
            self.q = self.q[:, None]
        if self.q.ndim != 2 or self.q.shape[1] == 0:
            raise InputError(
                f"q has shape {self.q.shape}; give one row per time and one column per joint "
                "(samples, joints)",
                self.source,
                "q",
            )
        if len(self.t) < 2 or self.q.shape[0] != len(self.t):
            raise InputError(
                f"need at least 2 samples and one row of q per time, got {len(self.t)} times and "
                f"{self.q.shape[0]} rows",
                self.source,
                "q",
            )
        # qd and qdd exactly as q (a transposed array of the same size would be reshaped into
        # scrambled velocities); a single joint's may be a plain vector.
        if qd is None and qdd is not None:
            raise InputError(
                "qdd without qd: give the velocities too (or neither)", self.source, "qdd"
            )
        qd, qdd = (
            None if values is None else self._array(name, values, self.q.shape)
            for name, values in (("qd", qd), ("qdd", qdd))
        )
        for name, values in (("t", self.t), ("q", self.q), ("qd", qd), ("qdd", qdd)):
            if values is not None and not np.all(np.isfinite(values)):
                row = int(
                    np.flatnonzero(
                        ~np.all(np.isfinite(np.reshape(values, (len(self.t), -1))), axis=1)
                    )[0]
                )
                raise InputError(f"{self.describe(row)} is not finite", self.source, name)
        check_time_steps(self.t, self.describe, self.source, "t")
        self.dof = self.q.shape[1]
        with np.errstate(all="ignore"):  # an overflow is refused by _check_finite, by name
            try:
                spline = self._fit(qd, qdd)
            except InputError:
                raise
            except (np.linalg.LinAlgError, ValueError) as exc:
                raise InputError(
                    f"no spline fits the samples ({exc}): {self._scale()}",
                    self.source,
                    self._scale_field(),
                ) from None
            self._spline = spline
            self._velocity = spline.derivative(1)
            self._acceleration = spline.derivative(2)
            self._check_finite()

    def _scale(self) -> str:
        """What double precision cannot hold, and what to change: for messages about a spline
        that overflows (its coefficients scale positions by powers of the steps)."""
        if self._scale_field() == "q":
            return (
                f"positions |q| up to {np.abs(self.q).max():.3g} rad are beyond what double "
                "precision holds through the spline: give positions in rad (or m)"
            )
        return (
            f"the samples span t = {self.t[0]:.6g} to {self.t[-1]:.6g} s, beyond what double "
            "precision holds through the spline: give times in seconds, of a physical span"
        )

    def _scale_field(self) -> str:
        """The field to blame for a spline double precision cannot hold: ``q`` when a position's
        square overflows, else the times ``t``."""
        return "q" if np.abs(self.q).max() > 1e150 else "t"

    def _check_finite(self) -> None:
        """Refuse a spline whose position, velocity, acceleration or jerk is not finite: finite
        samples can still overflow (a span of 1e308 s squared, positions near 1e308), and the
        reference would be NaN everywhere. The coefficients bound the values (the convex hull
        property of the B-spline and Bernstein forms), so finite coefficients suffice."""
        pieces = (
            ("position", self._spline),
            ("velocity", self._velocity),
            ("acceleration", self._acceleration),
            ("jerk", self._spline.derivative(3)),
        )
        for what, piece in pieces:
            if not np.all(np.isfinite(piece.c)):
                raise InputError(
                    f"the {what} of the spline through the samples is not finite: {self._scale()}",
                    self.source,
                    self._scale_field(),
                )

    def _fit(self, qd, qdd):
        """The interpolating spline of the module docstring (``qd``, ``qdd`` checked)."""
        from scipy.interpolate import make_interp_spline

        if qd is None:
            self._warn_if_not_at_rest()
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
        return spline

    def _array(self, name: str, values, shape: tuple | None = None) -> np.ndarray:
        """``values`` as a float array (of ``shape``, when given: a single joint's column may
        be a plain vector), or one error naming ``name``: complex numbers (whose imaginary part
        numpy would drop, with a mere warning) and texts (which it would parse) are refused."""
        try:
            raw = np.asarray(values)
            array = None if raw.dtype.kind in "cUS" else np.asarray(raw, dtype=float)
        except (TypeError, ValueError):
            raise InputError(
                f"{name} is not an array of numbers (got {type(values).__name__})",
                self.source,
                name,
            ) from None
        if array is None:
            what = "complex numbers" if raw.dtype.kind == "c" else "texts"
            raise InputError(
                f"{name} holds {what} (dtype {raw.dtype.name}); give real numbers",
                self.source,
                name,
            )
        if shape is not None:
            if array.ndim == 1 and shape[1] == 1:
                array = array[:, None]
            if array.shape != shape:
                raise InputError(
                    f"{name} has shape {array.shape}, but q has shape {shape} (samples, joints): "
                    f"give {name} as q, one row per time",
                    self.source,
                    name,
                )
        return array

    def _warn_if_not_at_rest(self) -> None:
        """From ``q`` alone the spline starts and ends at rest: samples that start or end moving
        (the speed of the first or last two samples above 5 % of the samples' largest) force it
        to stop within one sample interval, with accelerations the data does not have. Warn,
        naming the end, the joint and the speed."""
        speeds = np.abs(np.diff(self.q, axis=0) / np.diff(self.t)[:, None])  # (K - 1, dof)
        if len(speeds) < 2 or not np.any(speeds > 0):
            return
        peak = speeds.max()
        for end, row in (("start", 0), ("end", -1)):
            joint = int(np.argmax(speeds[row]))
            if speeds[row, joint] > 0.05 * peak:
                where = f"{self.source}: " if self.source else ""
                warnings.warn(
                    f"{where}the samples {end} moving (joint "
                    f"{joint + 1} at {speeds[row, joint]:.3g} rad/s between the {end}'s two "
                    f"samples, {speeds[row, joint] / peak:.0%} of the largest speed), but a "
                    f"trajectory from q alone {end}s at rest: the spline stops within one sample "
                    f"interval, with accelerations the data does not have; extend the samples to "
                    f"rest, or give qd",
                    stacklevel=4,  # the caller of FileTrajectory(), past _fit
                )

    def describe(self, row: int) -> str:
        line = f", line {self.lines[row]}" if self.lines is not None else ""
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
        t = as_time(t)
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
