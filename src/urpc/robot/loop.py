"""The control loop of a robot's process: a synthesized controller, a trajectory and the
controller's state, advanced one sample per call of :meth:`ControlLoop.step`.

``step(t, q, qd) -> tau`` is the hot path: the reference at ``t``, the controller's torque
(``controller.output``) and its state one period later (``controller.advance``), exactly as the
sampled simulator (:mod:`urpc.sim.sampled`) calls them, plus one row of the log (preallocated
arrays). It knows nothing about the robot or the clock of the cycle: the safety layer, the
watchdog and the robot's I/O are :func:`urpc.robot.runner.run`'s. The log becomes a
:class:`~urpc.sim.results.SimulationResult` (:meth:`ControlLoop.result`), saved to the same files
as ``urpc simulate --out``. Optionally (``velocity_filter_hz``, default off) the measured velocity
passes a first-order low-pass before the controller sees it (:meth:`ControlLoop.filter_velocity`).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from ..control.base import Controller
from ..errors import InputError
from ..trajectories import Trajectory
from ..validation import check_trajectory_dof, checked_count, number_in, positive_number

#: Rows the log holds before it doubles.
DEFAULT_CAPACITY = 16_384
_SERIES = ("q", "qd", "q_desired", "qd_desired", "torque", "torque_sent")
_SCALARS = ("t", "rho_norm", "step_time")


class ControlLoop:
    """A controller, its trajectory and its state, stepped once per sample.

    Args:
        controller: A synthesized controller (:func:`urpc.synthesize`, :func:`urpc.load_controller`).
        trajectory: The reference (:class:`urpc.Trajectory`, e.g. :func:`urpc.from_samples`, or a
            :class:`~urpc.trajectory_moves.StreamedReference` updated while the loop runs).
        period: The control period [s]; default: the controller's ``sample_period``.
        epsilon: The precision a run is judged against [rad]; default: the controller's.
        capacity: Rows the log holds before it grows.
        clock: The timer of ``step``'s own duration (``time.perf_counter``).
        velocity_filter_hz: Cutoff ``f_c`` [Hz] of a first-order low-pass on the measured
            velocity before the controller sees it, or ``None`` (default): no filter, the
            controller gets the robot's ``qd`` unchanged. See :meth:`filter_velocity`.

    Attributes:
        last: Diagnostics of the latest step: ``e`` (``||e||`` [rad]), then the controller's
            own, exactly the names of its ``diagnostic_units`` (``phi`` and ``kappa`` for the
            interval law, none for r-alpha), ``rho_norm`` (``||rho||`` [N m]) only for a
            controller that reports it (``last_rho_norm``: the interval law), and ``step_time``
            [s].
        diagnostic_units: Name -> unit of every logged diagnostic: the controller's
            ``diagnostic_units``, plus ``rho_norm`` (``N m``) when the controller reports it.
        samples: Steps logged since :meth:`reset`.
    """

    def __init__(
        self,
        controller: Controller,
        trajectory: Trajectory,
        *,
        period: float | None = None,
        epsilon: float | None = None,
        capacity: int = DEFAULT_CAPACITY,
        clock=time.perf_counter,
        velocity_filter_hz: float | None = None,
    ):
        if not callable(getattr(controller, "output", None)) or not hasattr(
            controller, "initial_state"
        ):
            raise InputError(
                f"expected a controller (urpc.synthesize(...), urpc.load_controller(...)), got "
                f"{type(controller).__name__}",
                field="controller",
            )
        self.controller = controller
        self.trajectory = trajectory
        own = getattr(controller, "sample_period", None)
        if period is None and own is None:
            raise InputError(
                "the loop needs a period: give period= or a controller synthesized with a "
                "sample_period",
                field="period",
            )
        self.period = positive_number(
            "period", own if period is None else period, "a finite number > 0 [s]"
        )
        if own is not None and self.period != float(own):
            raise InputError(
                f"{self.period:g} s is not the controller's period {float(own):g} s (its law is "
                "discretized for it); omit period= or synthesize the controller for this period",
                field="period",
            )
        if epsilon is None:  # Controller.epsilon is None for a law without one (r-alpha)
            epsilon = getattr(controller, "epsilon", None)
        self.epsilon = (
            math.nan
            if epsilon is None
            else positive_number("epsilon", epsilon, "a finite number > 0 [rad]")
        )
        if controller.dof is not None:
            name = getattr(controller.robot, "name", controller.name)
            check_trajectory_dof(trajectory, controller.dof, f"the robot {name!r}")
        self.dof = trajectory.dof
        self._clock = clock
        self.velocity_filter_hz = velocity_filter_hz
        self._omega = None  # 2 pi f_c [rad/s] of the velocity filter, None: off
        if velocity_filter_hz is not None:
            try:
                cutoff = float(velocity_filter_hz)
            except (TypeError, ValueError):
                cutoff = math.nan
            if not (math.isfinite(cutoff) and cutoff > 0):
                raise InputError(
                    f"{velocity_filter_hz!r} must be a finite cutoff > 0 [Hz], or None (no filter)",
                    field="velocity_filter_hz",
                )
            self.velocity_filter_hz = cutoff
            self._omega = 2.0 * math.pi * cutoff
        # The controller's own diagnostics, as the simulator logs them (urpc.sim.sampled): the
        # names of its declaration, in order, evaluated at the sample's state.
        self._names = tuple(controller.diagnostic_units)
        self._rho = hasattr(controller, "last_rho_norm")
        units = dict(controller.diagnostic_units)
        if self._rho:
            units.setdefault("rho_norm", "N m")
        taken = set(_SERIES) | set(_SCALARS) | {"clipped", "e", "qd_filtered"}
        clash = [name for name in self._names if name in taken]
        if clash:
            raise InputError(
                f"{controller.name} declares the diagnostic {clash[0]!r}, a name the loop's log "
                f"uses itself; rename it (reserved: {', '.join(sorted(taken))})",
                field="diagnostic_units",
            )
        self.diagnostic_units: dict[str, str] = units
        self._capacity = max(16, checked_count("capacity", capacity, 1, " (the log's rows)"))
        self.reset()

    def reset(self) -> None:
        """Back to the controller's initial state and an empty log."""
        self.state = self.controller.initial_state()
        self.samples = 0
        series = _SERIES + (("qd_filtered",) if self._omega is not None else ())
        self._log = {name: np.empty((self._capacity, self.dof)) for name in series}
        scalars = ("t", *self._names, *(("rho_norm",) if self._rho else ()), "step_time")
        self._log.update({name: np.full(self._capacity, np.nan) for name in scalars})
        self._log["clipped"] = np.zeros(self._capacity, dtype=bool)
        self.last: dict[str, float] = {name: math.nan for name in ("e", *scalars[1:])}
        self._logged_of: np.ndarray | None = None
        self._values = [math.nan] * len(self._names)
        self._filtered: np.ndarray | None = None  # the velocity filter's output and its time
        self._filtered_t = math.nan
        self._last_t = -math.inf  # loop time of the latest step: it must not go back

    def filter_velocity(self, t: float, qd: np.ndarray) -> np.ndarray:
        """The velocity the controller sees at loop time ``t`` [s]: ``qd`` itself without a
        filter; with one, per joint the first-order low-pass ``tau dy/dt = qd - y``
        (``tau = 1 / (2 pi f_c)``) discretized exactly for an input held over each step::

            y_k = y_{k-1} + a (qd_k - y_{k-1}),    a = 1 - exp(-2 pi f_c (t_k - t_{k-1}))

        starting at ``y_0 = qd_0`` (no start-up transient), so a step of the input is followed
        by ``1 - exp(-2 pi f_c t)`` at the samples. The actual time between samples is used, so
        a lost sample is a longer step, not a shorter lag. A sample at the same time as the
        previous one leaves ``y`` unchanged."""
        if self._omega is None:
            return qd
        previous = self._filtered
        if previous is None:
            filtered = np.array(qd, dtype=float)
        else:
            dt = t - self._filtered_t
            a = -math.expm1(-self._omega * dt) if dt > 0 else 0.0
            filtered = previous + a * (qd - previous)
        self._filtered, self._filtered_t = filtered, t
        return filtered

    def step(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The torque [N m] for the sample ``(q, qd)`` at loop time ``t`` [s]; advances the
        controller's state by one period and logs the sample. ``qd`` is the measured velocity;
        with ``velocity_filter_hz`` the controller gets its filtered value
        (:meth:`filter_velocity`), logged as ``qd_filtered`` next to the measured ``qd``.

        Raises:
            InputError: ``t`` is not a finite number, or earlier than the previous step's
                (loop time never goes back; :meth:`reset` starts again).
        """
        tic = self._clock()
        if not (type(t) is float and math.isfinite(t)):  # noqa: E721 (exact type: the fast path)
            t = number_in("t", t, "a finite time [s]", lambda x: True)
        if t < self._last_t:
            raise InputError(
                f"t = {t:.9g} s is before the previous step's {self._last_t:.9g} s: loop time "
                "must not go back (the controller's state has advanced one period per step and "
                "the log is in time order); call reset() to start a new run",
                field="t",
            )
        self._last_t = t
        controller, state = self.controller, self.state
        measured = qd
        if self._omega is not None:
            qd = self.filter_velocity(t, qd)
        reference = self.trajectory.reference(t)
        tau = controller.output(t, q, qd, reference, state)
        self.state = controller.advance(t, q, qd, reference, state)
        k = self.samples
        if k == self._capacity:
            self._grow()
        log = self._log
        log["t"][k] = t
        log["q"][k] = q
        log["qd"][k] = measured
        if self._omega is not None:
            log["qd_filtered"][k] = qd
        log["q_desired"][k] = reference.q
        log["qd_desired"][k] = reference.qd
        log["torque"][k] = tau
        log["torque_sent"][k] = tau
        last = self.last
        names = self._names
        if names:
            if state is not self._logged_of:  # advance() returns the same array while unchanged
                named = controller.diagnostics(state)
                self._logged_of = state
                self._values = [named.get(name, math.nan) for name in names]
            for name, value in zip(names, self._values, strict=True):
                log[name][k] = last[name] = value
        if self._rho:
            log["rho_norm"][k] = last["rho_norm"] = controller.last_rho_norm
        self.samples = k + 1
        elapsed = self._clock() - tic
        log["step_time"][k] = elapsed
        e = reference.q - q
        last["e"], last["step_time"] = math.sqrt(e @ e), elapsed
        return tau

    def record_sent(self, tau: np.ndarray, clipped: bool) -> None:
        """Log the torque the robot actually received for the latest step (after the safety
        layer) and whether the layer changed it."""
        k = self.samples - 1
        self._log["torque_sent"][k] = tau
        self._log["clipped"][k] = clipped

    def _grow(self) -> None:
        self._capacity *= 2
        for name, array in self._log.items():
            grown = np.empty((self._capacity,) + array.shape[1:], dtype=array.dtype)
            grown[: len(array)] = array
            self._log[name] = grown

    # ------------------------------------------------------------------ the log
    def series(self) -> dict[str, np.ndarray]:
        """The logged series (copies), one row per step: ``t``, ``q``, ``qd``, ``q_desired``,
        ``qd_desired``, ``torque`` (the controller's), ``torque_sent`` (what the robot got),
        ``clipped``, ``step_time``, ``qd_filtered`` (with a velocity filter: what the controller
        got; ``qd`` is always the measured velocity), and one per name of
        :attr:`diagnostic_units` (the controller's diagnostics, ``rho_norm`` when it reports
        it)."""
        return {name: array[: self.samples].copy() for name, array in self._log.items()}

    def step_time_percentiles(self) -> dict[str, float]:
        """p50, p99, p99.9 and max of the step time [s]."""
        return percentiles(self._log["step_time"][: self.samples])

    def result(
        self,
        *,
        scenario: str = "",
        plant: str = "",
        torque_limit=None,
        wall_time: float = math.nan,
        info: dict[str, Any] | None = None,
    ):
        """The log as a :class:`~urpc.sim.results.SimulationResult` (``torque`` is the
        controller's, ``saturated`` marks the samples the safety layer changed; ``diagnostics``
        are exactly the controller's declared series, their units in
        ``info["diagnostic_units"]``, as ``urpc simulate`` writes them); its
        :meth:`~urpc.sim.results.SimulationResult.save` writes the files of ``urpc simulate``."""
        from ..sim.results import SimulationResult

        if self.samples == 0:
            raise InputError(
                "the loop has not run: nothing to report; call step() at least once first",
                field="result",
            )
        s = self.series()
        t = s["t"]
        return SimulationResult(
            t=t,
            q=s["q"],
            qd=s["qd"],
            q_desired=s["q_desired"],
            qd_desired=s["qd_desired"],
            torque=s["torque"],
            disturbance=np.zeros_like(s["torque"]),
            diagnostics={name: s[name] for name in self._names},
            saturated=s["clipped"],
            controller=self.controller.name,
            epsilon=self.epsilon,
            duration=float(t[-1] - t[0]),
            sample_period=self.period,
            scenario=scenario,
            plant=plant,
            torque_limit=None if torque_limit is None else tuple(float(x) for x in torque_limit),
            step_time_median=float(np.median(s["step_time"])),
            wall_time=wall_time,
            info={**self._units_info(), "step_time": self.step_time_percentiles(), **(info or {})},
        )

    def _units_info(self) -> dict[str, Any]:
        units = self.controller.diagnostic_units
        info: dict[str, Any] = {"diagnostic_units": dict(units)} if units else {}
        robot = self.controller.robot
        if robot is not None:
            info["joint_kinds"] = list(robot.joint_kinds)  # units: rad, N m or m, N per joint
        if self._omega is not None:
            info["velocity_filter_hz"] = self.velocity_filter_hz
        return info


def percentiles(times: np.ndarray) -> dict[str, float]:
    """``p50``, ``p99``, ``p99_9`` and ``max`` of ``times`` [s] (NaN when empty)."""
    times = np.asarray(times, dtype=float)
    if times.size == 0:
        return {"p50": math.nan, "p99": math.nan, "p99_9": math.nan, "max": math.nan}
    p50, p99, p999 = np.percentile(times, [50, 99, 99.9])
    return {"p50": float(p50), "p99": float(p99), "p99_9": float(p999), "max": float(times.max())}
