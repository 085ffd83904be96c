"""Closed-loop simulation of a true plant under a controller, continuous or sampled.

The plant is a :class:`~urpc.model.robot.Robot` carrying the *true* parameters; its accelerations come
from Pinocchio's articulated-body algorithm. The plant sees ``sat(u) + d``: the controller's torque
``u``, clipped to the optional per-joint ``torque_limit``, plus an input disturbance ``d``.

* **Continuous time** (``sample_period=None``, the paper's scenario 1): the plant state and the
  controller's internal state form one ODE, integrated by :func:`scipy.integrate.solve_ivp` with
  tight tolerances; series are recorded on a fixed output grid (``output_rate``, default 1 kHz)
  from the solver's dense output, the torque being re-evaluated at each grid point.
* **Sampled** (scenarios 2, 3): at each sample ``t_k = k T`` the controller reads ``(q, qd)``,
  its output is held (zero-order hold) over ``[t_k, t_k + T)`` together with a disturbance ``d_k``
  drawn uniformly in the ball ``||d|| <= disturbance_bound`` (seeded), and a
  :class:`~urpc.sim.plants.Plant` of the chosen backend (``plant_backend``: ``pinocchio``, the
  reference, or the independent ``mujoco`` one) integrates the period by classical Runge-Kutta 4
  with steps of at most ``integration_step``. Under a held torque the plant alone is not stiff, so
  RK4 with ``1e-4`` s steps is accurate to far below the tracking tolerances
  (``tests/test_simulation.py`` compares it with ten times finer steps). The controller's state
  advances once per sample (:meth:`Controller.advance`).

A run that diverges (a non-finite value, ``|q|`` or ``|qd|`` above ``max_state``, a solver failure)
raises :class:`~urpc.errors.SimulationError` naming the time and the state.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

from ..control.base import Controller, Reference
from ..errors import InputError, SimulationError
from ..model.robot import Robot
from ..validation import finite_vector, positive_number
from .plants import PLANTS, Plant, make_plant
from .results import SimulationResult

#: Default continuous-time integrator and tolerances, chosen by measurement on the paper's
#: scenario 1 (10 s): the interval law (Kr = 95/s, phi up to ~1.5e3) is stiff-ish, and the r-alpha
#: law (a near-discontinuous ``s / (||s|| + eta)``) is very stiff. Radau handles both (~5 s each);
#: RK45/DOP853 take ~4x longer on the interval law, LSODA fails or crawls (minutes) on r-alpha and
#: BDF is erratic on it. Halving both tolerances changes every reported metric by less than 1 %
#: (interval law: < 1e-5 relative; r-alpha: torque_variation 0.9 %, others < 1e-3).
CONTINUOUS_METHOD = "Radau"
CONTINUOUS_RTOL = 1e-8
CONTINUOUS_ATOL = 1e-10


class Trajectory(Protocol):
    """Anything with ``reference(t) -> Reference`` (desired q [rad], qd [rad/s], qdd [rad/s^2])."""

    def reference(self, t: float) -> Reference: ...


def simulate(
    plant: Robot,
    controller: Controller,
    trajectory: Trajectory,
    *,
    duration: float,
    q0: np.ndarray | None = None,
    qd0: np.ndarray | None = None,
    sample_period: float | None = None,
    disturbance_bound: float = 0.0,
    seed: int = 0,
    torque_limit: float | np.ndarray | None = None,
    epsilon: float | None = None,
    method: str = CONTINUOUS_METHOD,
    rtol: float = CONTINUOUS_RTOL,
    atol: float = CONTINUOUS_ATOL,
    output_rate: float = 1000.0,
    integration_step: float = 1e-4,
    max_state: float = 1e4,
    scenario: str = "",
    plant_description: str | None = None,
    progress: bool | Callable[[float], Any] | Any | None = None,
    plant_backend: str = "pinocchio",
    controller_state0: np.ndarray | None = None,
) -> SimulationResult:
    """Simulate ``plant`` under ``controller`` tracking ``trajectory``.

    Args:
        plant: The true plant (a robot with the true parameters).
        controller: The control law (built once, reusable: its state is explicit).
        trajectory: Object with ``reference(t) -> Reference``.
        duration: Simulated time [s] (a sampled run is rounded up to whole periods).
        q0, qd0: Initial joint positions [rad] and velocities [rad/s]; ``None`` starts on the
            reference at ``t = 0``.
        sample_period: Control period [s] (zero-order hold); ``None`` for continuous time.
        disturbance_bound: Radius [N m] of the ball the input disturbance is drawn from, once per
            sample (sampled runs only).
        seed: Seed of the disturbance generator (``numpy.random.default_rng``).
        torque_limit: Per-joint bound [N m] (scalar or ``dof`` values) the command is clipped to;
            ``None`` for no limit.
        epsilon: Required precision [rad] for the metrics; defaults to ``controller.epsilon``.
        method, rtol, atol: ``solve_ivp`` method and tolerances (continuous time).
        output_rate: Recording rate [Hz] of a continuous run.
        integration_step: Largest RK4 step [s] inside one sample period.
        max_state: Bound on ``|q|`` [rad] and ``|qd|`` [rad/s] (the norm of ``(q, qd)`` in a sampled
            run) beyond which the run counts as diverged; the default 1e4 is far beyond any arm
            and keeps a diverging continuous run from crawling through ever stiffer dynamics.
        scenario: Scenario name stored in the result.
        plant_description: Text describing the true parameters (default: the plant's link masses
            and centers of mass).
        progress: ``None``; ``True`` for a tqdm bar on stderr; a callable receiving the fraction
            done in ``[0, 1]``; or a tqdm-like object (``update``, ``total``), advanced by
            ``total`` times the fraction done (``total`` is set to 100 when it is ``None``).
        plant_backend: Plant of a sampled run, a key of :data:`urpc.sim.plants.PLANTS`
            (``pinocchio`` or ``mujoco``); continuous time needs ``pinocchio``.
        controller_state0: The controller's internal state at ``t = 0`` (length
            ``controller.n_states``), e.g. to continue a run after a tool change; ``None`` uses
            ``controller.initial_state()``.

    Raises:
        InputError: an argument out of range (the message names it).
        SimulationError: the run diverged or the integrator failed (names the time and state).
    """
    start = time.perf_counter()
    n = plant.dof
    reference0 = trajectory.reference(0.0)
    q0 = finite_vector("q0", reference0.q if q0 is None else q0, n)
    qd0 = finite_vector("qd0", reference0.qd if qd0 is None else qd0, n)
    duration = positive_number("duration", duration, "a finite number > 0 [s]")
    if epsilon is None:
        epsilon = getattr(controller, "epsilon", None)
        if epsilon is None:
            raise InputError(
                f"controller '{controller.name}' has no epsilon; pass the required precision",
                field="epsilon",
            )
    epsilon = positive_number("epsilon", epsilon, "a finite number > 0 [rad]")
    disturbance_bound = float(disturbance_bound)
    if not (math.isfinite(disturbance_bound) and disturbance_bound >= 0):
        raise InputError(
            f"{disturbance_bound!r} is out of range; expected a finite number >= 0 [N m]",
            field="disturbance_bound",
        )
    limit = None
    if torque_limit is not None:
        limit = np.broadcast_to(np.asarray(torque_limit, dtype=float), (n,)).copy()
        if not np.all(limit > 0):
            raise InputError(
                f"{torque_limit!r} is out of range; expected numbers > 0 [N m]",
                field="torque_limit",
            )
    if plant_backend not in PLANTS:
        raise InputError(
            f"unknown plant {plant_backend!r}; valid: {', '.join(PLANTS)}", field="plant"
        )
    if sample_period is None and plant_backend != "pinocchio":
        raise InputError(
            f"the {plant_backend} plant steps under a held torque: give a sample_period, or use "
            "the pinocchio plant for continuous time",
            field="plant",
        )
    state0 = controller.initial_state()
    if controller_state0 is not None:
        state0 = finite_vector("controller_state0", controller_state0, controller.n_states)
    common = dict(
        controller=controller.name,
        epsilon=epsilon,
        seed=int(seed),
        scenario=scenario,
        plant=plant_description if plant_description is not None else describe_plant(plant),
        disturbance_bound=disturbance_bound,
        torque_limit=None if limit is None else tuple(float(x) for x in limit),
    )
    bar = _Progress(progress)
    setup = _Setup(plant, controller, trajectory, duration, q0, qd0, state0, limit, max_state, bar)
    try:
        if sample_period is None:
            if disturbance_bound > 0:
                raise InputError(
                    "an input disturbance is drawn once per control sample; give a sample_period "
                    "or set disturbance_bound to 0 for continuous time",
                    field="disturbance_bound",
                )
            rate = positive_number("output_rate", output_rate, "a finite number > 0 [Hz]")
            series, info = _continuous(setup, method, rtol, atol, rate)
        else:
            period = positive_number("sample_period", sample_period, "a finite number > 0 [s]")
            if period > duration:
                raise InputError(
                    f"{period!r} s is longer than the duration {duration!r} s",
                    field="sample_period",
                )
            step = positive_number("integration_step", integration_step, "a finite number > 0 [s]")
            stepper = make_plant(plant_backend, plant, max_step=step)
            series, info = _sampled(setup, stepper, period, disturbance_bound, int(seed))
            duration = float(series["t"][-1])
    finally:
        bar.close()
    return SimulationResult(
        **series,
        **common,
        duration=duration,
        sample_period=None if sample_period is None else float(sample_period),
        wall_time=time.perf_counter() - start,
        info=info,
    )


def describe_plant(plant: Robot) -> str:
    """``link: m = .. kg, com = (..) m, I_C diag = (..) kg m^2`` for each moving link."""
    parts = []
    for link in plant.links:
        if link.joint_index == 0:
            continue
        inertia = link.inertia
        com = ", ".join(f"{c:.6g}" for c in np.asarray(inertia.lever))
        diag = ", ".join(f"{c:.6g}" for c in np.diag(np.asarray(inertia.inertia)))
        parts.append(
            f"{link.name}: m = {inertia.mass:.6g} kg, com = ({com}) m, I_C diag = ({diag})"
        )
    return f"{plant.name}; " + "; ".join(parts)


# ============================================================================== sampled
def _sampled(
    setup: _Setup, stepper: Plant, period: float, disturbance_bound: float, seed: int
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    controller, trajectory = setup.controller, setup.trajectory
    q, qd, limit, bar = setup.q0, setup.qd0, setup.limit, setup.bar
    n = stepper.dof
    n_periods = max(1, math.ceil(setup.duration / period - 1e-9))
    samples = n_periods + 1
    disturbance = ball_samples(samples, n, disturbance_bound, np.random.default_rng(seed))
    stepper.reset(q, qd)

    rate = 1.0 / period
    if abs(rate - round(rate)) < 1e-9 * rate:  # k / rate is the exact decimal time: 0.0411 s
        t_series = np.arange(samples) / round(rate)
    else:
        t_series = np.arange(samples) * period
    q_series, qd_series = np.empty((samples, n)), np.empty((samples, n))
    qdes_series, qddes_series = np.empty((samples, n)), np.empty((samples, n))
    torque = np.empty((samples, n))
    phi, kappa = np.full(samples, np.nan), np.full(samples, np.nan)
    saturated = np.zeros(samples, dtype=bool)
    step_times = np.empty(samples)
    state = setup.state0
    has_gains = bool(controller.diagnostics(state))
    gains_of, gains = None, (np.nan, np.nan)
    report_every = max(1, samples // 200)
    bound = setup.max_state**2
    clock = time.perf_counter
    for k in range(samples):
        t = t_series[k]
        reference = trajectory.reference(t)
        tic = clock()
        u = controller.output(t, q, qd, reference, state)
        next_state = controller.advance(t, q, qd, reference, state, period)
        step_times[k] = clock() - tic
        q_series[k], qd_series[k] = q, qd
        qdes_series[k], qddes_series[k] = reference.q, reference.qd
        torque[k] = u
        if has_gains:
            if state is not gains_of:  # advance() returns the same array while nothing changes
                named = controller.diagnostics(state)
                gains_of, gains = state, (named.get("phi", np.nan), named.get("kappa", np.nan))
            phi[k], kappa[k] = gains
        if k == n_periods:
            break
        if limit is not None:
            clipped = np.clip(u, -limit, limit)
            saturated[k] = np.any(clipped != u)
            u = clipped
        if not u @ u < math.inf:  # NaN or overflow; the plant refuses non-finite torques
            _diverged(t, q, qd, "non-finite or overflowing torque")
        try:
            q, qd = stepper.step(u + disturbance[k], period)
        except SimulationError:
            _diverged(t, q, qd, "the state became non-finite during the following period")
        # One dot product catches runaway (and NaN, should the plant let one through).
        if not q @ q + qd @ qd <= bound:
            _diverged(t + period, q, qd, f"non-finite or ||(q, qd)|| above {setup.max_state:g}")
        state = next_state
        if k % report_every == 0:
            bar.update((k + 1) / samples)
    if limit is not None:
        saturated[-1] = np.any(np.abs(torque[-1]) > limit)
    bar.update(1.0)
    series = dict(
        t=t_series,
        q=q_series,
        qd=qd_series,
        q_desired=qdes_series,
        qd_desired=qddes_series,
        torque=torque,
        disturbance=disturbance,
        phi=phi,
        kappa=kappa,
        saturated=saturated,
        step_time_median=float(np.median(step_times)),
    )
    substeps = max(1, math.ceil(period / stepper.max_step - 1e-9))
    info = {
        "plant": stepper.kind,
        "integrator": "rk4",
        "integration_step": period / substeps,
        "substeps": substeps,
        "controller_state_final": np.asarray(state, dtype=float).tolist(),
    }
    return series, info


def ball_samples(count: int, dimension: int, radius: float, rng: np.random.Generator) -> np.ndarray:
    """``count`` points drawn uniformly in the ball ``||d|| <= radius`` of ``R^dimension``:
    a normalized Gaussian direction times ``radius * U^(1/dimension)``."""
    if radius == 0:
        return np.zeros((count, dimension))
    directions = rng.standard_normal((count, dimension))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radii = radius * rng.random(count) ** (1.0 / dimension)
    return directions * radii[:, None]


# ============================================================================== continuous
def _continuous(
    setup: _Setup, method: str, rtol: float, atol: float, output_rate: float
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    plant, controller, trajectory = setup.plant, setup.controller, setup.trajectory
    duration, limit, max_state, bar = setup.duration, setup.limit, setup.max_state, setup.bar
    n = plant.dof
    model, data = plant.model, plant.model.createData()
    aba = pin.aba
    configuration = (lambda q: q) if model.nq == model.nv else plant.configuration
    step_times: list[float] = []
    clock = time.perf_counter
    furthest = [0.0]

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        x = np.ascontiguousarray(x)  # implicit methods pass strided Jacobian columns
        q, qd, state = x[:n], x[n : 2 * n], x[2 * n :]
        if not np.isfinite(x).all():
            raise _Diverged(t, x, "non-finite state")
        reference = trajectory.reference(t)
        tic = clock()
        u = controller.output(t, q, qd, reference, state)
        state_rate = controller.state_derivative(t, q, qd, reference, state)
        step_times.append(clock() - tic)
        if not np.isfinite(u).all():
            raise _Diverged(t, x, "non-finite torque")
        if limit is not None:
            u = np.clip(u, -limit, limit)
        if t > furthest[0] + 0.005 * duration:
            furthest[0] = t
            bar.update(t / duration)
        return np.concatenate((qd, aba(model, data, configuration(q), qd, u), state_rate))

    def runaway(t: float, x: np.ndarray) -> float:
        return max_state - np.abs(x[: 2 * n]).max()

    runaway.terminal = True
    samples = max(2, int(round(duration * output_rate)) + 1)
    grid = np.linspace(0.0, duration, samples)
    x0 = np.concatenate((setup.q0, setup.qd0, setup.state0))
    try:
        solution = solve_ivp(
            rhs,
            (0.0, duration),
            x0,
            method=method,
            t_eval=grid,
            rtol=rtol,
            atol=atol,
            events=runaway,
        )
    except _Diverged as exc:
        _diverged(exc.t, exc.x[:n], exc.x[n : 2 * n], exc.reason)
    except ValueError as exc:  # an unknown method or bad tolerances
        raise InputError(str(exc), field="method") from None
    if solution.status == 1:
        x = solution.y_events[0][0]
        _diverged(solution.t_events[0][0], x[:n], x[n : 2 * n], f"|q| or |qd| above {max_state:g}")
    if solution.status != 0:
        x = solution.y[:, -1] if solution.y.size else x0
        t = solution.t[-1] if solution.t.size else 0.0
        _diverged(t, x[:n], x[n : 2 * n], f"the integrator failed: {solution.message}")
    bar.update(1.0)

    q, qd, states = solution.y[:n].T, solution.y[n : 2 * n].T, solution.y[2 * n :].T
    qdes, qddes = np.empty((samples, n)), np.empty((samples, n))
    torque = np.empty((samples, n))
    phi, kappa = np.full(samples, np.nan), np.full(samples, np.nan)
    has_gains = bool(controller.diagnostics(controller.initial_state()))
    for k, t in enumerate(solution.t):
        reference = trajectory.reference(t)
        qdes[k], qddes[k] = reference.q, reference.qd
        torque[k] = controller.output(t, q[k], qd[k], reference, states[k])
        if has_gains:
            gains = controller.diagnostics(states[k])
            phi[k], kappa[k] = gains.get("phi", np.nan), gains.get("kappa", np.nan)
    saturated = (
        np.zeros(samples, dtype=bool) if limit is None else np.any(np.abs(torque) > limit, axis=1)
    )
    series = dict(
        t=solution.t,
        q=q,
        qd=qd,
        q_desired=qdes,
        qd_desired=qddes,
        torque=torque,
        disturbance=np.zeros((samples, n)),
        phi=phi,
        kappa=kappa,
        saturated=saturated,
        step_time_median=float(np.median(step_times)),
    )
    info = {
        "plant": "pinocchio",
        "integrator": method,
        "rtol": rtol,
        "atol": atol,
        "output_rate": output_rate,
        "rhs_evaluations": int(solution.nfev),
        "controller_state_final": states[-1].tolist(),
    }
    return series, info


# ============================================================================== helpers
@dataclass(frozen=True)
class _Setup:
    """What both integrators need."""

    plant: Robot
    controller: Controller
    trajectory: Trajectory
    duration: float
    q0: np.ndarray
    qd0: np.ndarray
    state0: np.ndarray
    limit: np.ndarray | None
    max_state: float
    bar: _Progress


class _Diverged(Exception):
    def __init__(self, t: float, x: np.ndarray, reason: str):
        self.t, self.x, self.reason = t, x, reason


def _diverged(t: float, q: np.ndarray, qd: np.ndarray, reason: str):
    with np.printoptions(precision=6, threshold=20):
        raise SimulationError(
            f"the simulation diverged at t = {t:.6g} s ({reason}): q = {np.asarray(q)} rad, "
            f"qd = {np.asarray(qd)} rad/s"
        )


class _Progress:
    """Adapts ``progress`` (None, True, a callable of the fraction, a tqdm-like bar)."""

    def __init__(self, progress: Any):
        self._owned = False
        self._done = 0.0
        self._bar = None
        self._callback = None
        if progress is True:
            from tqdm import tqdm

            self._bar = tqdm(total=100, file=sys.stderr, unit="%", leave=False, desc="simulate")
            self._owned = True
        elif progress is None or progress is False:
            pass
        elif hasattr(progress, "update"):
            self._bar = progress
            if getattr(progress, "total", None) is None:
                progress.total = 100
        elif callable(progress):
            self._callback = progress
        else:
            raise InputError(
                f"{progress!r} is not a progress reporter; give True, a callable or a tqdm bar",
                field="progress",
            )

    def update(self, fraction: float) -> None:
        fraction = min(max(fraction, 0.0), 1.0)
        if fraction <= self._done:
            return
        if self._bar is not None:
            self._bar.update((fraction - self._done) * self._bar.total)
        elif self._callback is not None:
            self._callback(fraction)
        self._done = fraction

    def close(self) -> None:
        if self._owned and self._bar is not None:
            self._bar.close()
