"""The control loop of a robot's process: a synthesized controller, a trajectory and the
controller's state, advanced one sample per call of :meth:`ControlLoop.step`.

``step(t, q, qd) -> tau`` is the hot path: the reference at ``t``, the controller's torque
(``controller.output``) and its state one period later (``controller.advance``), exactly as the
sampled simulator (:mod:`urpc.sim.sampled`) calls them, plus one row of the log (preallocated
arrays). It knows nothing about the robot or the clock of the cycle: the safety layer, the
watchdog and the robot's I/O are :func:`urpc.robot.runner.run`'s. The log becomes a
:class:`~urpc.sim.results.SimulationResult` (:meth:`ControlLoop.result`), saved to the same files
as ``urpc simulate --out``.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from ..control.base import Controller
from ..trajectories import Trajectory

#: Rows the log holds before it doubles.
DEFAULT_CAPACITY = 16_384
_SERIES = ("q", "qd", "q_desired", "qd_desired", "torque", "torque_sent")
_SCALARS = ("t", "phi", "kappa", "rho_norm", "step_time")


class ControlLoop:
    """A controller, its trajectory and its state, stepped once per sample.

    Args:
        controller: A synthesized controller (:func:`urpc.synthesize`, :func:`urpc.load_controller`).
        trajectory: The reference (:class:`urpc.Trajectory`, e.g. :func:`urpc.from_samples`, or a
            :class:`~urpc.trajectories_streamed.StreamedReference` updated while the loop runs).
        period: The control period [s]; default: the controller's ``sample_period``.
        epsilon: The precision a run is judged against [rad]; default: the controller's.
        capacity: Rows the log holds before it grows.
        clock: The timer of ``step``'s own duration (``time.perf_counter``).

    Attributes:
        last: Diagnostics of the latest step: ``e`` (``||e||`` [rad]), ``phi``, ``kappa``,
            ``rho_norm`` (``||rho||`` [N m]), ``step_time`` [s].
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
    ):
        self.controller = controller
        self.trajectory = trajectory
        self.period = float(period if period is not None else controller.sample_period)
        if not self.period > 0:
            raise ValueError("the loop needs a period: give period= or a sampled controller")
        self.epsilon = float(
            epsilon if epsilon is not None else getattr(controller, "epsilon", math.nan)
        )
        self.dof = trajectory.dof
        self._clock = clock
        self._gains = getattr(controller, "gains", None)
        self._capacity = max(16, int(capacity))
        self.reset()

    def reset(self) -> None:
        """Back to the controller's initial state and an empty log."""
        self.state = self.controller.initial_state()
        self.samples = 0
        self._log = {name: np.empty((self._capacity, self.dof)) for name in _SERIES}
        self._log.update({name: np.full(self._capacity, np.nan) for name in _SCALARS})
        self._log["clipped"] = np.zeros(self._capacity, dtype=bool)
        self.last: dict[str, float] = {
            "e": math.nan, "phi": math.nan, "kappa": math.nan, "rho_norm": math.nan, "step_time": math.nan
        }  # fmt: skip

    def step(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The torque [N m] for the sample ``(q, qd)`` at loop time ``t`` [s]; advances the
        controller's state by one period and logs the sample."""
        tic = self._clock()
        controller, state = self.controller, self.state
        reference = self.trajectory.reference(t)
        tau = controller.output(t, q, qd, reference, state)
        self.state = controller.advance(t, q, qd, reference, state)
        k = self.samples
        if k == self._capacity:
            self._grow()
        log = self._log
        log["t"][k] = t
        log["q"][k] = q
        log["qd"][k] = qd
        log["q_desired"][k] = reference.q
        log["qd_desired"][k] = reference.qd
        log["torque"][k] = tau
        log["torque_sent"][k] = tau
        if self._gains is not None:
            phi, kappa = self._gains(state)
        else:
            named = controller.diagnostics(state)
            phi, kappa = named.get("phi", math.nan), named.get("kappa", math.nan)
        rho_norm = getattr(controller, "last_rho_norm", math.nan)
        log["phi"][k], log["kappa"][k], log["rho_norm"][k] = phi, kappa, rho_norm
        self.samples = k + 1
        elapsed = self._clock() - tic
        log["step_time"][k] = elapsed
        e = reference.q - q
        last = self.last
        last["e"], last["phi"], last["kappa"] = math.sqrt(e @ e), phi, kappa
        last["rho_norm"], last["step_time"] = rho_norm, elapsed
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
        ``clipped``, ``phi``, ``kappa``, ``rho_norm``, ``step_time``."""
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
        controller's, ``saturated`` marks the samples the safety layer changed); its
        :meth:`~urpc.sim.results.SimulationResult.save` writes the files of ``urpc simulate``."""
        from ..sim.results import SimulationResult

        if self.samples == 0:
            raise ValueError("the loop has not run: nothing to report")
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
            diagnostics={name: s[name] for name in self.controller.diagnostic_units if name in s},
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
            info={"step_time": self.step_time_percentiles(), **(info or {})},
        )


def percentiles(times: np.ndarray) -> dict[str, float]:
    """``p50``, ``p99``, ``p99_9`` and ``max`` of ``times`` [s] (NaN when empty)."""
    times = np.asarray(times, dtype=float)
    if times.size == 0:
        return {"p50": math.nan, "p99": math.nan, "p99_9": math.nan, "max": math.nan}
    p50, p99, p999 = np.percentile(times, [50, 99, 99.9])
    return {"p50": float(p50), "p99": float(p99), "p99_9": float(p999), "max": float(times.max())}
